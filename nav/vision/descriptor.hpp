// Appearance descriptors for the matchers.
//
// PatchDescriptor (ZNCC): a kPatchSide x kPatchSide patch sampled bilinearly around a point, on a
// grid rotated by a known angle (e.g. the heading change from the attitude sensor) and scaled by
// `scale` pixels per sample, made zero-mean and unit-norm so ZNCC = dot product (in [-1, 1]).
// Use when rotation is known (Mars paper stereo VO, sonar tiles with heading).
//
// OrientedDescriptor (SIFT-like gradient histogram): dominant gradient orientation from a 36-bin
// histogram of Gaussian-weighted gradients; then a 4 x 4 grid of 8-bin orientation histograms over a
// square of side 4 * kOrientedCellScale * scale pixels rotated to the dominant orientation, with
// trilinear binning, L2 normalisation, clipping at 0.2, renormalisation (Lowe 2004). Survives
// rotation, and +/-30 % scale when computed on the pyramid level closest to the corner's scale; for
// the underwater paper's ratio-test matching (distance = L2).
//
// Both: no allocation; out-of-image support or a flat patch returns an error and marks the output
// invalid. Cost: PatchDescriptor O(kPatchSide^2); OrientedDescriptor O((support radius)^2).
#pragma once

#include <cstdint>

#include "nav/core/image.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/vision/corner.hpp"

namespace qnav::vision {

constexpr int kPatchSide = 11;
constexpr int kPatchSize = kPatchSide * kPatchSide;

struct PatchDescriptor {
  float v[kPatchSize] = {};  // zero mean, unit L2 norm
  bool valid = false;
};

// Samples the patch centred at (x, y) in image pixels, grid rotated by rotation_rad (counter-
// clockwise in image coordinates x right / y down means: sample offset (dx, dy) maps to
// (c dx - s dy, s dx + c dy)), spacing scale px. Errors: kOutOfRange (support leaves the image),
// kDegenerate (patch stddev below min_stddev grey levels / intensity units), kInvalidArgument (NaN).
Status compute_patch_descriptor(ConstImageViewU8 image, float x, float y, float rotation_rad, float scale,
                                PatchDescriptor& out, float min_stddev = 1.0f) noexcept;
Status compute_patch_descriptor(ConstImageViewF32 image, float x, float y, float rotation_rad, float scale,
                                PatchDescriptor& out, float min_stddev = 1e-3f) noexcept;
// Mutable views: exact matches (ImageView's const conversion is a template, see harris.hpp).
inline Status compute_patch_descriptor(ImageViewU8 image, float x, float y, float rotation_rad, float scale,
                                       PatchDescriptor& out, float min_stddev = 1.0f) noexcept {
  return compute_patch_descriptor(ConstImageViewU8(image), x, y, rotation_rad, scale, out, min_stddev);
}
inline Status compute_patch_descriptor(ImageViewF32 image, float x, float y, float rotation_rad, float scale,
                                       PatchDescriptor& out, float min_stddev = 1e-3f) noexcept {
  return compute_patch_descriptor(ConstImageViewF32(image), x, y, rotation_rad, scale, out, min_stddev);
}
// ZNCC of two valid descriptors (dot product), -2 if either is invalid.
float zncc(const PatchDescriptor& a, const PatchDescriptor& b) noexcept;

constexpr int kOrientedDims = 128;
constexpr float kOrientedCellScale = 3.0f;  // cell side in units of `scale`
constexpr float kOrientedMaxScale = 4.0f;   // larger scales: use a coarser pyramid level
// Support side at the largest scale: 2 * (ceil(2 * 3 * 4 * sqrt 2) + 1) + 1. The two scratch planes
// of that side live on the stack: 2 * 71 * 71 * 4 bytes = 40 KB.
constexpr int kOrientedMaxSide = 71;

struct OrientedDescriptor {
  float v[kOrientedDims] = {};  // L2-normalised
  float orientation_rad = 0.0f; // dominant gradient orientation, image frame
  float x = 0.0f, y = 0.0f;     // level-0 position
  float scale = 1.0f;           // level-0 pixels per level pixel (2^level) times the detection scale
  bool valid = false;
};

// Computes the descriptor at (x, y) of `image` (a pyramid level) with sample scale `scale` (level
// pixels, 0.25..4): orientation window sigma 4.5 * scale, descriptor window 4 cells of 3 * scale px.
// Stack: 44 KB of scratch (gradient magnitude and angle of the support, two 6 x 6 x 8 histograms).
// Fills v, orientation_rad, valid; x/y/scale are left for the caller (level-0 bookkeeping).
// Errors: kOutOfRange (support leaves the image), kDegenerate (no gradient), kInvalidArgument.
Status compute_oriented_descriptor(ConstImageViewU8 image, float x, float y, float scale, OrientedDescriptor& out) noexcept;

// Gradient planes of one image, for describing many of its keypoints: the Sobel magnitude and angle
// compute_oriented_descriptor computes over each keypoint's support, computed once per pixel (supports
// of neighbouring keypoints overlap many times). Views into caller-owned storage, row-major, stride =
// width; the one-pixel border is not written (no support reaches it).
struct GradientPlanes {
  const float* mag = nullptr;
  const float* ang = nullptr;
  int width = 0, height = 0;
};
// Fills mag and ang (each at least width x height floats) from image; out views them. Time O(W H),
// no allocation. Errors: kInvalidArgument (image under 3 x 3), kCapacityExceeded (planes too small).
Status compute_gradient_planes(ConstImageViewU8 image, Span<float> mag, Span<float> ang, GradientPlanes& out) noexcept;
// The descriptor of compute_oriented_descriptor(image, ...) from the image's gradient planes: bit for
// bit the same output and the same errors, without the per-support gradient pass.
Status compute_oriented_descriptor(const GradientPlanes& planes, float x, float y, float scale,
                                   OrientedDescriptor& out) noexcept;
// Squared L2 distance of two descriptors (large value if either is invalid).
float descriptor_distance_sq(const OrientedDescriptor& a, const OrientedDescriptor& b) noexcept;

}  // namespace qnav::vision
