// PatchAligner: sub-pixel alignment of a small patch from one image into another (Lucas-Kanade,
// inverse compositional, translation only, invariant to gain and bias).
//
// What it is for: a Harris corner is re-detected in the next frame with a localisation jitter of a few
// tenths of a pixel, and that jitter -- not the stereo depth -- limits the rotation a stereo VO step can
// measure. Aligning the previous frame's patch around its corner into the current frame gives the same
// physical point to a few hundredths of a pixel (on textured patches). One-dimensional mode (along
// rows) refines a stereo disparity on a rectified pair the same way.
//
// Method: the template T is the (2r+1)^2 patch of `ref` centred on the (sub-pixel) reference point,
// sampled bilinearly, made zero-mean and unit-norm, with its gradients (central differences on a grid
// one pixel wider). Each iteration samples the target patch at the current estimate, normalises it the
// same way (gain and bias drop out), and solves the 2x2 (1x1 in row mode) normal equations of the
// template gradients for the update (inverse compositional: the Hessian is computed once). Both
// normalisations are applied to sums (one pass over the template, one per iteration; the maps are in
// patch_align.cpp), the same estimate as per-sample normalisation up to rounding. It stops
// when the update is below converge_px, after max_iterations, or when the estimate leaves
// max_shift_px of the start or the image.
//
// Result: position, the final ZNCC between template and target (the quality), iterations, and the
// position's 1-sigma from the residual and the Hessian (sigma^2 = residual variance * H^-1).
// Errors (nothing written): kNotReady before configure, kOutOfRange (patch not inside either image,
// or the estimate left the image), kDegenerate (template without texture in some direction: the
// smaller Hessian eigenvalue below min_gradient_energy), kNotFound (no convergence, moved beyond
// max_shift_px, or final ZNCC below min_zncc).
// Cost: O((2r+3)^2) to build the template + O(iterations * (2r+1)^2); no heap (fixed arrays for
// radius <= kMaxRadius, about 5 KB in the object).
#pragma once

#include "nav/core/image.hpp"
#include "nav/core/status.hpp"

namespace qnav::vision {

struct PatchAlignConfig {
  int radius = 3;                  // template (2r+1)^2, 1..kMaxRadius
  int max_iterations = 12;
  float converge_px = 0.01f;       // stop when the update is smaller than this
  float max_shift_px = 2.0f;       // from the start position
  float min_zncc = 0.85f;          // final quality
  float min_gradient_energy = 1e-3f;  // smaller eigenvalue of the normalised template's Hessian
};

struct PatchAlignResult {
  float x_px = 0.0f;
  float y_px = 0.0f;
  float zncc = 0.0f;
  int iterations = 0;
  float sigma_x_px = 0.0f;  // 1-sigma of the position from the final residual (0 in row mode for y)
  float sigma_y_px = 0.0f;
};

class PatchAligner {
 public:
  static constexpr int kMaxRadius = 7;

  PatchAligner() noexcept = default;
  // kInvalidArgument for a radius outside 1..kMaxRadius or a non-positive / non-finite bound.
  Status configure(const PatchAlignConfig& config) noexcept;
  const PatchAlignConfig& config() const noexcept { return config_; }

  // Aligns the patch of `ref` at (ref_x, ref_y) into `target`, starting at (x0, y0). rows_only: the
  // row is held at y0 (stereo on a rectified pair).
  Status align(ConstImageViewU8 ref, float ref_x, float ref_y, ConstImageViewU8 target, float x0, float y0,
               bool rows_only, PatchAlignResult& out) noexcept;
  // Same, with the template sampled through a local affine map: the target offset (dx, dy) from the
  // aligned point corresponds to the reference offset (a00 dx + a01 dy, a10 dx + a11 dy), warp =
  // {a00, a01, a10, a11} (e.g. the perspective change of a ground patch predicted from the motion).
  // kInvalidArgument for a non-finite warp or one that scales by more than 4 or less than 1/4.
  Status align_warped(ConstImageViewU8 ref, float ref_x, float ref_y, const float (&warp)[4], ConstImageViewU8 target,
                      float x0, float y0, bool rows_only, PatchAlignResult& out) noexcept;

 private:
  static constexpr int kMaxSide = 2 * kMaxRadius + 1;
  static constexpr int kMaxGrid = kMaxSide + 2;
  // Samples the template grid (side 2r + 3, centred on the pixel (cx, cy)) of `ref` through `warp` into grid_.
  // rows_only: the first and last rows are left out (no vertical gradients in row mode).
  void build_grid(ConstImageViewU8 ref, float cx, float cy, const float (&warp)[4], int r, bool rows_only) noexcept;
  // The normalised template's Hessian (inverse compositional: computed once per call).
  struct Hessian {
    double xx = 0.0, xy = 0.0, yy = 0.0, det = 0.0;
  };
  // One evaluation of the target patch against the template.
  struct Residual {
    double bx = 0.0, by = 0.0;  // sum of gradient * error
    double ess = 0.0;           // sum of squared errors
    double cross = 0.0;         // ZNCC of template and target patch
    int iterations = 0;
  };
  // The raw template t_, gx_, gy_, its maps tmpl_ and the Hessian; kDegenerate without texture.
  Status prepare_template(ConstImageViewU8 ref, float cx, float cy, const float (&warp)[4], bool rows_only,
                          Hessian& h) noexcept;
  // The normalised target patch at (x, y) against the template; kNotFound for a flat patch.
  Status evaluate(ConstImageViewU8 target, float x, float y, bool rows_only, Residual& e) noexcept;
  // The Gauss-Newton iterations from (xs, ys); kOutOfRange / kNotFound as align_warped.
  Status iterate(ConstImageViewU8 target, float xs, float ys, bool rows_only, const Hessian& h, float& x, float& y,
                 Residual& last) noexcept;
  PatchAlignConfig config_{};
  bool ready_ = false;
  float grid_[kMaxGrid * kMaxGrid] = {};
  float t_[kMaxSide * kMaxSide] = {};   // template samples less the grid's centre
  float gx_[kMaxSide * kMaxSide] = {};  // twice its central differences along x
  float gy_[kMaxSide * kMaxSide] = {};  // and along y
  float win_[(kMaxSide + 1) * (kMaxSide + 1)] = {};  // target pixels under the patch, as floats
  int win_x_ = -1, win_y_ = -1;                        // win_'s integer position in the target (none: -1)
  // The affine maps from the raw template samples (t_, gx_, gy_: the samples less the centre and twice
  // the central differences) to the normalised template and its projected gradients (prepare_template).
  struct TemplateMaps {
    double mt = 0.0, mx = 0.0, my = 0.0;  // means of T, X, Y
    double inv = 0.0;                     // 1 / |T - mT|
    double gxt = 0.0, gyt = 0.0;          // the gradients' parts along the normalised template
  };
  TemplateMaps tmpl_{};
};

}  // namespace qnav::vision
