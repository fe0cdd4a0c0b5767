// TrackRefiner: re-measures a matched landmark in the current stereo pair by patch alignment, so the two
// ends of a VO pair are the same physical point to a tenth of a pixel (beyond the Mars paper, whose
// pairs are two independent Harris detections).
//
// Why: a Harris corner is re-detected in the next frame with a jitter of ~0.25 px per axis (measured on
// the Mars yard with ray-cast truth), and on a ground plane seen obliquely the patch also changes shape
// between frames (the near part grows faster than the far part), which biases a plain translation
// alignment. Both limit the rotation a step can measure, and a bias accumulates along the path.
//
// refine(): the reference landmark's patch in the reference left image is warped by the local affine map
// the motion estimate induces through the landmark's local plane (normal from its normal_neighbours
// nearest reference landmarks in 3D; a plane facing the camera when they are not planar), aligned into
// the current left image (vision::PatchAligner, inverse-compositional Lucas-Kanade), and the disparity is
// measured again at the aligned point by aligning along the row into the right image. The result is the
// current 3D point of the same physical point. refine_disparity(): the row alignment alone, for a
// stereo point's sub-pixel disparity.
// Cost: O(ref landmarks * normal_neighbours) for the neighbours (with ref_by_x: O(log n + the landmarks
// within the neighbours' x reach) per pair after one O(n log n) sort) + two alignments per pair
// (O(iterations * (2r+1)^2)); no heap.
#pragma once

#include <cstddef>

#include "nav/core/geometry.hpp"
#include "nav/core/image.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/match/geometric_match.hpp"
#include "nav/vision/patch_align.hpp"
#include "nav/vision/stereo.hpp"

namespace qnav::vo {

struct TrackRefineConfig {
  vision::PatchAlignConfig align;
  int normal_neighbours = 12;  // reference landmarks in the local plane fit (3..kMaxNeighbours)
  double max_planarity = 0.3;  // smallest / middle eigenvalue of the fit above this: not a plane
  float max_disparity_change_px = 1.0f;  // refine_disparity: the aligned disparity must stay this close
};

class TrackRefiner {
 public:
  static constexpr int kMaxNeighbours = 32;

  TrackRefiner() noexcept = default;
  // kInvalidArgument for a bad configuration or camera.
  Status init(const TrackRefineConfig& config, const vision::StereoCamera& camera) noexcept;

  // ref: the reference frame's landmarks (for the local plane), ref_index the pair's reference landmark,
  // cur its matched landmark in the current frame (start of the search), prev_T_cur the step estimate
  // (p = R c + t). On success writes the current-frame point. kNotReady, kOutOfRange (index),
  // kNotFound (an alignment failed or the disparity is not positive).
  // ref_by_x (optional, for many calls on one ref): the indices of ref ordered by position x, equal x by
  // index, every position finite (the caller's promise; sort_by_x() makes it). The neighbours of the
  // local plane are then searched outwards from the landmark's x (O(log n + the landmarks within reach)
  // instead of O(n)), with the same result bit for bit.
  Status refine(ConstImageViewU8 ref_left, Span<const match::Landmark3> ref, std::size_t ref_index,
                ConstImageViewU8 left, ConstImageViewU8 right, const match::Landmark3& cur, const Pose3& prev_T_cur,
                Vec3d& cur_point_m, Span<const std::int32_t> ref_by_x = {}) noexcept;
  // Writes ref's indices ordered as refine()'s ref_by_x needs into order (size >= ref.size()) and returns
  // true; false (order unspecified) when a position is not finite or order is too small.
  static bool sort_by_x(Span<const match::Landmark3> ref, Span<std::int32_t> order) noexcept;

  // Sub-pixel disparity of p by row alignment from its current disparity; updates disparity, point and
  // depth sigma (disparity_sigma_px) on success. kNotFound when it does not align or moves too far.
  Status refine_disparity(ConstImageViewU8 left, ConstImageViewU8 right, float disparity_sigma_px,
                          vision::StereoPoint& p) noexcept;

  // Local affine map from current-image offsets to reference-image offsets at the current pixel (u, v)
  // for the plane n . X = n . point through the reference point (reference frame), under prev_T_cur.
  // False when the plane is seen edge-on.
  bool plane_affine(const Vec3d& point_ref_m, const Vec3d& normal_ref, const Pose3& prev_T_cur, double u_px,
                    double v_px, float (&affine)[4]) const noexcept;

  // The local plane's normal at ref[index] (reference frame, towards the camera) that refine() warps by:
  // the smallest-eigenvalue direction of the normal_neighbours nearest landmarks (the landmark itself
  // included; equal distances by index), or the direction to the camera when they are too few or not
  // planar. ref_by_x as refine()'s (optional: the same result without it). index < ref.size().
  Vec3d local_normal(Span<const match::Landmark3> ref, std::size_t index,
                     Span<const std::int32_t> ref_by_x = {}) const noexcept;

 private:
  TrackRefineConfig config_{};
  vision::StereoCamera camera_{};
  vision::PatchAligner aligner_;
  bool ready_ = false;
};

}  // namespace qnav::vo
