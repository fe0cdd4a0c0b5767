// HomographyChain: the underwater paper's downward-camera odometry over a flat seabed. Per frame:
//   frame check (black / saturated / textureless -> kBadInput, nothing else runs)
//   -> ImagePyramid -> HarrisDetector on each level -> keypoints in level-0 pixels, strongest first,
//      a keypoint closer than min_separation_px to a stronger one removed (grid of cells of side
//      min_separation_px / sqrt 2: one kept keypoint per cell, 5 x 5 cells checked)
//   -> OrientedDescriptor (nav/vision) at each kept keypoint on its level, up to max_keypoints, from
//      the level's gradient planes (Sobel magnitude and angle computed once per pixel of a level with
//      corners, not once per keypoint support: the supports overlap several times)
//   -> RatioMatcher against the current KEYFRAME (predicted through the last homography when the
//      last frame registered; all-against-all when that fails or there is no prediction)
//   -> optional outlier filter: fundamental matrix by RANSAC and LMedS, keep what both accept (the
//      paper's rule; weak over a flat seabed, where F is not unique, so off by default)
//   -> robust_homography (RANSAC, DLT on the inliers, LM refinement): H_key<-cur
//   -> plausibility (scale of the affine part, perspective terms, overlap) -> kDegenerate
//   -> global pose by the paper's eq. 2: H_0<-cur = H_0<-key H_key<-cur (H_0<-key fixed when the
//      keyframe was taken), so per-frame noise does not accumulate between keyframes
//   -> keyframe selection: the current frame becomes the keyframe when its overlap with the keyframe
//      falls below min_overlap, its inliers below keyframe_min_inliers, or max_keyframe_gap frames.
// A frame that fails (any flag but kOk) leaves the pose, the keyframe and the prediction untouched.
//
// Pose: the mosaic frame is frame 0's pixel grid (x right, y down). position_px = H_0<-cur applied to
// the principal point; heading_rad = rotation (closest similarity) of H_0<-cur's Jacobian at the
// principal point = the current camera's x axis in the mosaic frame; the image content turned by
// -heading_rad from frame 0 (clockwise on screen positive). Metric scale: with altitude_m and fx,
// metres per mosaic pixel = altitude_m / (fx * s), s = scale of H_0<-cur at the principal point;
// averaged over the frames that gave an altitude. position_m = (position_px - principal point) * that,
// in frame 0's camera axes.
//
// Bounds: keypoints <= max_keypoints per frame, corners per level <= corners_per_level, matches <=
// max_keypoints, RANSAC / LMedS iterations from the configuration. Memory: every buffer from the Arena
// in init() (arena_bytes(): the pyramid levels and their two float gradient planes, 9 bytes per pixel
// of each level, are most of it); process() allocates nothing. Stack: ~3 KB inside the descriptor (its 40 KB
// per-support planes are not used: the chain describes from the level planes).
// Cost per frame: pyramid + Harris O(W H), descriptors O(K r^2), matching O(K min(K, candidates) 128),
// robust fits O(iterations K).
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/arena.hpp"
#include "nav/core/fixed_vector.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/image.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/match/ratio_match.hpp"
#include "nav/match/robust_two_view.hpp"
#include "nav/vision/corner.hpp"
#include "nav/vision/descriptor.hpp"
#include "nav/vision/downsample.hpp"
#include "nav/vision/harris.hpp"

namespace qnav::topo {

struct CameraIntrinsics {
  double fx = 0.0, fy = 0.0;  // pixels; 0 = unknown (no metric scale)
  double cx = -1.0, cy = -1.0;  // principal point; < 0 = image centre
};

struct HomographyChainConfig {
  int max_width = 640;            // largest frame process() accepts
  int max_height = 480;
  int pyramid_levels = 2;         // Harris on levels 0 .. levels-1 (1..4)
  int corners_per_level = 300;    // Harris cap per level
  std::size_t max_keypoints = 400;   // described keypoints per frame
  float min_separation_px = 6.0f;    // level-0 pixels between kept keypoints
  float descriptor_scale = 2.0f;     // descriptor sample scale on the keypoint's level (level pixels)
  int border_px = 8;                 // no keypoint this close to the image edge (level 0)
  vision::HarrisConfig harris{};     // max_width/height/max_corners/border_px are set from the above
  match::RatioMatchConfig ratio{};   // max_query/max_train are set to max_keypoints
  float predicted_radius_px = 40.0f; // search radius around the predicted position
  bool fundamental_filter = false;   // paper's F both-accept outlier rule before the homography
  match::RobustTwoViewConfig homography{};  // RANSAC; min_inliers used as the registration floor
  match::RobustTwoViewConfig fundamental_ransac{};
  match::RobustTwoViewConfig fundamental_lmeds{};
  std::size_t min_keypoints = 20;    // fewer -> kFewKeypoints
  std::size_t min_matches = 15;      // fewer ratio-test matches -> kFewMatches
  std::uint32_t min_inliers = 15;    // fewer homography inliers -> kFewMatches
  double min_scale = 0.6, max_scale = 1.6;  // frame-to-keyframe scale outside -> kDegenerate
  double max_perspective = 0.15;     // |h20|, |h21| of H in coordinates centred on the principal point with
                                     // half the larger image side as unit (~ tilt change x half-side / f); above -> kDegenerate
  // Keyframes.
  double min_overlap = 0.7;          // keyframe area covered by the current frame, below -> new keyframe
  std::uint32_t keyframe_min_inliers = 60;
  std::uint32_t max_keyframe_gap = 30;
  // Frame check (on every 2nd pixel of every 2nd row).
  double dark_mean = 8.0;            // mean grey below -> black
  double saturated_fraction = 0.9;   // fraction of pixels >= 250 above -> saturated
  double min_stddev = 3.0;           // grey stddev below -> textureless
  CameraIntrinsics camera{};
};

enum class StepStatus : std::uint8_t {
  kOk = 0,          // registered (or the first frame: the reference)
  kBadInput,        // black, saturated, textureless, wrong size or an image view that lies
  kFewKeypoints,
  kFewMatches,      // ratio-test matches or homography inliers below their floors
  kDegenerate,      // no homography, or an implausible one (scale, perspective, mirrored)
};
const char* to_string(StepStatus s) noexcept;

// Why a frame was refused as bad input (bits).
enum : std::uint8_t { kFrameDark = 1, kFrameSaturated = 2, kFrameTextureless = 4, kFrameSize = 8 };

struct ChainPose {
  Mat3d H_0_cur = Mat3d::Identity();  // mosaic (frame 0 pixels) <- current frame pixels
  Vec2d position_px = Vec2d::Zero();  // principal point of the current frame in the mosaic
  double heading_rad = 0.0;           // current camera x axis in the mosaic (image frame, y down)
  double scale = 1.0;                 // mosaic pixels per current pixel at the principal point
  Vec2d position_m = Vec2d::Zero();   // (position_px - principal point) * metres_per_px
  bool metric = false;                // metres_per_px known (an altitude was given)
};

struct ChainStep {
  StepStatus status = StepStatus::kOk;
  std::uint8_t bad_input = 0;         // kFrame* bits when status == kBadInput
  bool reference = false;             // the first good frame (pose = identity)
  bool new_keyframe = false;          // this frame became the keyframe
  bool predicted = false;             // matching used the prediction
  std::uint32_t frame_index = 0;      // frames given to process(), this one counted from 0
  std::uint32_t keyframe_index = 0;   // frame index of the keyframe it was registered against
  std::uint32_t keypoints = 0;
  std::uint32_t matches = 0;          // ratio-test matches
  std::uint32_t fundamental_inliers = 0;  // matches both F fits accept (when the filter is on)
  std::uint32_t inliers = 0;          // homography inliers
  double rms_px = 0.0;                // homography symmetric transfer RMS over the inliers
  double overlap = 0.0;               // fraction of the keyframe covered by this frame
  Mat3d H_key_cur = Mat3d::Identity();
  ChainPose pose;                     // after this frame (unchanged when status != kOk)
};

class HomographyChain {
 public:
  HomographyChain() noexcept = default;
  HomographyChain(const HomographyChain&) = delete;  // key_/cur_ point into this object
  HomographyChain& operator=(const HomographyChain&) = delete;
  Status init(const HomographyChainConfig& config, Arena& arena) noexcept;
  static std::size_t arena_bytes(const HomographyChainConfig& config) noexcept;

  // One frame, with the altitude above the seabed when known (altitude_m <= 0 or NaN = unknown).
  // Errors (Status) only for misuse: kNotReady before init(). Everything about the frame is in the step.
  Status process(ConstImageViewU8 frame, double altitude_m, ChainStep& step) noexcept;
  Status process(ConstImageViewU8 frame, ChainStep& step) noexcept { return process(frame, -1.0, step); }

  // Forget the map: the next good frame is the reference again.
  void reset() noexcept;

  const ChainPose& pose() const noexcept { return pose_; }
  double metres_per_px() const noexcept { return mpp_count_ > 0 ? mpp_sum_ / mpp_count_ : 0.0; }
  std::uint32_t keyframes() const noexcept { return keyframes_; }
  const HomographyChainConfig& config() const noexcept { return config_; }
  // Keypoints of the last frame that got as far as description (level-0 positions), for plots, tests
  // and the topological map's place signature. A frame that became the keyframe had its descriptors
  // swapped into the keyframe set: last_ follows them.
  Span<const vision::OrientedDescriptor> current_keypoints() const noexcept {
    return Span<const vision::OrientedDescriptor>(last_->data(), last_->size());
  }
  // The last frame's ratio-test matches as level-0 positions: matched_current()[i] in the frame,
  // matched_keyframe()[i] in its keyframe (step.matches pairs; empty when the frame got no matching).
  // For evaluation against a known truth (qnav map eval's true matches); valid until the next process().
  Span<const Vec2d> matched_current() const noexcept { return Span<const Vec2d>(src_.data(), last_matches_); }
  Span<const Vec2d> matched_keyframe() const noexcept { return Span<const Vec2d>(dst_.data(), last_matches_); }

 private:
  std::uint8_t check_frame(ConstImageViewU8 frame) const noexcept;
  Status extract(ConstImageViewU8 frame, BoundedVector<vision::OrientedDescriptor>& out) noexcept;
  // The steps of process() after extract(); each false return has set step.status.
  void take_reference(ConstImageViewU8 frame, double altitude_m, ChainStep& step) noexcept;
  bool match_to_keyframe(ChainStep& step) noexcept;              // matches_, src_ / dst_, last_matches_
  bool fit_to_keyframe(ChainStep& step, Mat3d& H) noexcept;      // H_key<-cur, normalised h22 = 1
  bool plausible(const Mat3d& H, ConstImageViewU8 frame, ChainStep& step) const noexcept;  // scale, perspective, overlap
  void chain_pose(const Mat3d& H, double altitude_m, ChainStep& step) noexcept;  // eq. 2, keyframe switch
  void update_pose_outputs(ChainPose& p, double altitude_m) noexcept;
  Vec2d principal_point() const noexcept;
  double overlap_of(const Mat3d& H_key_cur, int w, int h) const noexcept;

  HomographyChainConfig config_{};
  bool ready_ = false;
  vision::ImagePyramid pyramid_;
  vision::HarrisDetector harris_;
  match::RatioMatcher matcher_;
  BoundedVector<vision::Corner> corners_;      // one level's corners
  BoundedVector<vision::Corner> all_corners_;  // every level, level-0 positions
  Span<std::int32_t> grid_;                    // separation grid: kept corner index per cell or -1
  int grid_w_ = 0, grid_h_ = 0;
  float cell_px_ = 1.0f;
  Span<float> grad_mag_[4], grad_ang_[4];      // per pyramid level: Sobel magnitude and angle planes
  vision::GradientPlanes planes_[4];           // this frame's, for the levels with corners
  BoundedVector<vision::OrientedDescriptor> desc_a_, desc_b_;
  BoundedVector<vision::OrientedDescriptor>* key_ = &desc_a_;  // keyframe's descriptors
  BoundedVector<vision::OrientedDescriptor>* cur_ = &desc_b_;  // the frame being processed
  const BoundedVector<vision::OrientedDescriptor>* last_ = &desc_b_;  // the last described frame's (cur_ or, after a swap, key_)
  BoundedVector<match::DescriptorMatch> matches_;
  Span<Vec2d> predicted_, src_, dst_, src_f_, dst_f_;
  Span<std::uint8_t> mask_, mask2_;
  Span<double> scratch_;
  std::size_t last_matches_ = 0;  // pairs in src_ / dst_ from the last process()

  bool have_reference_ = false;
  std::uint32_t frame_count_ = 0;
  std::uint32_t key_frame_index_ = 0;
  std::uint32_t keyframes_ = 0;
  int key_w_ = 0, key_h_ = 0;
  Mat3d H_0_key_ = Mat3d::Identity();
  Mat3d H_key_last_ = Mat3d::Identity();  // last good frame -> keyframe (prediction)
  bool have_prediction_ = false;
  ChainPose pose_{};
  double mpp_sum_ = 0.0;
  std::uint32_t mpp_count_ = 0;
};

}  // namespace qnav::topo
