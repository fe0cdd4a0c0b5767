// StereoVo: stereo visual odometry with external attitude (Souvannavong et al., Mars paper), one call per
// rectified stereo pair: (left, right, attitude R, odometry prior) -> step + pose + quality flags.
//
// Per frame: Harris corners on the left image (neighbourhood-normalised scores, best max_corners, in
// decreasing score) -> stereo correlation at the corners -> 3D landmarks with depth uncertainty ->
// geometric matching against the previous frame's landmarks with the prior (fb / fc / fast) ->
// 6D-VME (Arun) or 3D-VME (eq. 9, R from the sensor), weighted by 1/sigma^2, optional IRLS ->
// quality checks -> pose integration (3D mode: orientation from the absolute attitude when given).
// 3D mode with estimate_attitude_bias (default): an AttitudeBiasFilter (nav/motion) fuses each good
// step's 6D-VME rotation with the sensor samples and estimates the sensor's drift; its corrected
// orientation replaces the sensor's in 3D-VME and in the integration (a second O(matches) 6D solve +
// IRLS and a 3D re-solve per step). A NaN attitude resets it with the chain.
//
// Honest failure: a step that fails a check (too few corners / stereo points / matches, residual too
// high, implausible step, degenerate geometry, bad input) is flagged kLost and NOT integrated as a
// visual step; if a finite odometry prior exists, the pose is propagated with it and flagged
// kDeadReckoned. The frame's landmarks (when valid) become the reference, so the next good frame
// recovers. A frame with bad input (empty image, NaN attitude) keeps the previous reference and the
// priors are chained across it. The pose is never NaN.
//
// Capacities (declared in VoConfig, allocated from the Arena in init(); arena_bytes() tells how much):
// image size, corners, stereo points (= corners), landmarks per frame (2 sets), matcher buffers.
// process() makes no allocation. Worst case per frame: Harris O(W H) + stereo O(corners * disparity
// range * patch) + matching (see nav/match/geometric_match.hpp) + O(matches * irls iterations).
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/arena.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/fixed_vector.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/image.hpp"
#include "nav/core/status.hpp"
#include "nav/match/geometric_match.hpp"
#include "nav/motion/attitude_bias_filter.hpp"
#include "nav/motion/pose_integrator.hpp"
#include "nav/motion/rigid3d.hpp"
#include "nav/vision/harris.hpp"
#include "nav/vision/stereo.hpp"
#include "nav/vo/track_refiner.hpp"

namespace qnav::vo {

enum class VmeMode : std::uint8_t { k6D, k3D };

struct VoConfig {
  int max_width = 320;
  int max_height = 256;
  int max_corners = 300;
  vision::StereoCamera camera;  // rectified pair: focal_px, cu, cv, baseline_m
  vision::HarrisConfig harris;  // max_width/max_height/max_corners are overwritten from the above
  vision::StereoConfig stereo;
  match::GeometricMatchConfig match;  // max_landmarks is overwritten with max_corners
  VmeMode mode = VmeMode::k3D;
  bool weighted = true;  // weights 1 / (sigma_p^2 + sigma_c^2); false = eq. 8 / 9 as printed
  bool irls = true;
  motion::IrlsConfig irls_config;
  // ICP-like refinement (paper sec. 3.3): re-associate every landmark with its mutual nearest
  // neighbour under the estimated motion (gate n_sigma * sqrt(sigma_p^2 + sigma_c^2)) and re-estimate;
  // removes the pull of the odometry prior on the geometric matches. 0 = off.
  int icp_iterations = 2;
  double lateral_sigma_px = 0.5;  // image-plane uncertainty added to the stereo depth sigma
  double max_depth_m = 1e9;       // stereo points farther than this are not used
  std::size_t min_stereo_points = 12;
  std::size_t min_matches = 8;
  double max_rms_residual_m = 0.03;
  // rms residual / rms predicted sigma (sqrt(mean(sigma_p^2 + sigma_c^2))) of the final pairs; a wrong
  // motion still finds near neighbours in a dense cloud, but their residuals fill the whole gate.
  double max_normalized_residual = 1.2;
  double max_step_m = 5.0;
  double max_step_rotation_rad = 0.5;
  double default_translation_sigma_m = 0.5;  // gate when no odometry prior is given
  // Attitude drift estimation (3D mode with an absolute attitude only; see
  // nav/motion/attitude_bias_filter.hpp): each good step's 6D-VME rotation (on the final 3D-VME pairs)
  // and the sensor sample feed an AttitudeBiasFilter; its drift-corrected orientation replaces the sensor
  // in 3D-VME (step rotation, when corrected_step_rotation) and in the pose integration. Off = the
  // paper's 3D-VME (orientation straight from the sensor).
  bool estimate_attitude_bias = true;
  bool corrected_step_rotation = true;
  // true: the filtered orientation (AttitudeBiasFilter::corrected); false: the sensor sample with the
  // estimated drift removed (corrected_sample), whose white noise does not accumulate along the path.
  bool use_filtered_orientation = false;
  // The filter's VO rotation: Arun + IRLS, then Gauss-Newton with each point's anisotropic stereo
  // covariance (depth sigma along the ray, lateral_sigma_px across; motion::refine_rigid_6d_stereo).
  bool anisotropic_vo_rotation = true;
  motion::AttitudeBiasConfig attitude_bias;
  // Track refinement (beyond the paper). A Harris corner is re-detected in the next frame with a jitter
  // of a few tenths of a pixel, and that jitter -- not the stereo depth -- limits the rotation a step
  // measures. With refine_tracks the final pairs are re-measured once the step is accepted (TrackRefiner:
  // the reference frame's left patch around each reference corner, warped by the step estimate through
  // the landmark's local plane, aligned into the current left image, and the disparity measured again at
  // the aligned point), and the step (6D-VME, or 3D-VME's translation and the attitude filter's rotation)
  // is re-estimated on those pairs with the lateral sigma refined_lateral_sigma_px. Pairs that do not align are dropped;
  // with fewer than min_matches left the unrefined estimate stands (counted). Costs one stored left
  // image (max_width x max_height bytes) and O(pairs * iterations * patch) per frame.
  bool refine_tracks = true;
  // Sub-pixel disparity of every landmark by aligning its left patch along the row into the right image
  // (instead of the ZNCC parabola at the rounded column); a point that does not align keeps the parabola.
  bool refine_disparity = true;
  TrackRefineConfig track_refine;
  double refined_lateral_sigma_px = 0.1;
  double frame_period_s = 10.0;  // filter dt when stamp_ns is missing (0) or not increasing
};

// Input of one frame. Rotations and translations are in the left camera frame (x right, y down, z fwd).
struct VoInput {
  ConstImageViewU8 left;
  ConstImageViewU8 right;
  std::uint64_t stamp_ns = 0;
  Mat3d R_prev_cur = Mat3d::Identity();  // relative attitude since the previous call (sensor)
  bool has_translation_prior = false;
  Vec3d t_prev_cur_prior_m = Vec3d::Zero();  // odometry, previous camera frame
  double t_prior_sigma_m = 0.05;
  bool has_absolute_attitude = false;  // world_R_cam from the sensor (3D-VME integration)
  Mat3d world_R_cam = Mat3d::Identity();
  bool attitude_recalibrated = false;  // the sensor was just reset against an absolute reference
};

enum VoFlag : std::uint32_t {
  kVoFirstFrame = 1u << 0,
  kVoLost = 1u << 1,
  kVoDeadReckoned = 1u << 2,
  kVoBadInput = 1u << 3,
  kVoFewCorners = 1u << 4,
  kVoFewStereo = 1u << 5,
  kVoFewMatches = 1u << 6,
  kVoHighResidual = 1u << 7,
  kVoDegenerate = 1u << 8,
  kVoImplausible = 1u << 9,
};

struct VoStep {
  std::uint32_t flags = 0;
  bool visual = false;                   // true when prev_T_cur is a visual estimate
  Pose3 prev_T_cur;                      // the step that was integrated (identity if none)
  Mat6d covariance = Mat6d::Zero();      // [rotvec, t] of the visual step
  Pose3 world_T_cur;                     // integrated pose of the left camera
  std::size_t corners = 0;
  std::size_t stereo_points = 0;
  std::size_t landmarks = 0;
  std::size_t matches = 0;
  std::size_t inliers = 0;
  std::size_t refined_pairs = 0;  // pairs the step was re-estimated on (0: not refined)
  double rms_residual_m = 0.0;
  double normalized_residual = 0.0;
  bool attitude_corrected = false;  // world_T_cur.R is the attitude filter's estimate, not the raw sensor
  Vec3d attitude_drift_rad = Vec3d::Zero();  // the filter's estimate of the sensor drift
  bool has_vo_rotation = false;               // the filter's 6D rotation of this step (diagnostics)
  Mat3d vo_R_prev_cur = Mat3d::Identity();
  Mat3d vo_rotation_cov_right = Mat3d::Zero();
  match::MatchStats match_stats;
};

enum class VoCounter : std::uint8_t {
  kBadImage,
  kBadAttitude,
  kBadPrior,
  kFewCorners,
  kFewStereo,
  kFewMatches,
  kHighResidual,
  kDegenerate,
  kImplausibleStep,
  kLostFrames,
  kAttitudeFilterRejected,  // sample or VO step refused by the attitude filter (its own counters say why)
  kTrackAlignFailed,        // a final pair whose patch did not align (dropped from the refined step)
  kStepNotRefined,          // fewer than min_matches pairs aligned: the unrefined step stands
  kCount
};

class StereoVo {
 public:
  StereoVo() noexcept = default;
  static std::size_t arena_bytes(const VoConfig& config) noexcept;
  // Validates the configuration and carves every buffer from the arena (plus the matcher's own
  // one-time allocation). Errors: kInvalidArgument, kCapacityExceeded.
  Status init(const VoConfig& config, Arena& arena) noexcept;
  void reset(const Pose3& world_T_start = Pose3{}) noexcept;
  // Processes one frame. Returns an error only before init(); every input problem is a flagged step.
  Result<VoStep> process(const VoInput& in) noexcept;

  const VoConfig& config() const noexcept { return config_; }
  const Pose3& pose() const noexcept { return integrator_.pose(); }
  const motion::PoseIntegrator& integrator() const noexcept { return integrator_; }
  const CounterSet<VoCounter>& counters() const noexcept { return counters_; }
  const vision::HarrisDetector& harris() const noexcept { return harris_; }
  const vision::StereoMatcher& stereo() const noexcept { return stereo_; }
  const match::GeometricMatcher& matcher() const noexcept { return matcher_; }
  const motion::AttitudeBiasFilter& attitude_filter() const noexcept { return att_filter_; }
  std::size_t matcher_bytes() const noexcept { return matcher_.working_set_bytes(); }
  // Landmarks of the last processed frame (in decreasing Harris score).
  Span<const match::Landmark3> current_landmarks() const noexcept {
    return Span<const match::Landmark3>(landmarks_[cur_].data(), landmarks_[cur_].size());
  }

  static const char* const kCounterNames[static_cast<std::size_t>(VoCounter::kCount)];

 private:
  // The steps of process(), in order. accept_input: checks the input, counts what is bad, chains the
  // prior; false (step flagged bad input, lost) when the frame cannot be used.
  bool accept_input(const VoInput& in, VoStep& step) noexcept;
  void reset_chain() noexcept;  // the prior chained since the reference starts again from identity
  // Harris, stereo and the landmarks of this frame into lms; false (flagged few corners / few stereo,
  // lost) when they are too few for a reference.
  bool front_end(const VoInput& in, BoundedVector<match::Landmark3>& lms, VoStep& step) noexcept;
  // The first usable frame becomes the reference (landmarks_[next]) and sets the start attitude.
  void start_reference(const VoInput& in, int next, VoStep& step) noexcept;
  match::MotionPrior chained_prior() const noexcept;  // the matcher's prior from the chain
  // fc matching, the VME and the ICP rounds into est; returns the lost reason (0: est is usable) and the
  // pair count in mp_/mc_/w_ that est was computed from (0 when the buffers no longer hold them).
  std::uint32_t estimate_step(const BoundedVector<match::Landmark3>& ref, const BoundedVector<match::Landmark3>& lms,
                              VoStep& step, motion::RigidEstimate& est, std::size_t& n_final_pairs) noexcept;
  // Residual and plausibility checks of est (n_final pairs); the lost reason or 0.
  std::uint32_t check_estimate(const motion::RigidEstimate& est, std::size_t n_final, VoStep& step) noexcept;
  // Track refinement (refine_tracks) of the final pairs and the re-estimate on them (kept in est when
  // plausible, step.refined_pairs set); returns the aligned pair count now in the buffers (0: none).
  std::size_t refine_estimate(const VoInput& in, const BoundedVector<match::Landmark3>& ref,
                              const BoundedVector<match::Landmark3>& lms, std::size_t n_final_pairs,
                              motion::RigidEstimate& est, VoStep& step) noexcept;
  // The attitude this step integrates with: the sensor's, or with the attitude filter the corrected one
  // (the filter fed with the step's 6D-VME rotation on the n_pairs final pairs; est re-estimated with the
  // corrected step rotation when configured).
  const Mat3d* filtered_attitude(const VoInput& in, std::size_t n_pairs, bool refined, motion::RigidEstimate& est,
                                 VoStep& step) noexcept;
  // Refinement, attitude and integration of an accepted estimate.
  void integrate_step(const VoInput& in, const BoundedVector<match::Landmark3>& ref, const BoundedVector<match::Landmark3>& lms,
                      std::size_t n_final_pairs, motion::RigidEstimate& est, VoStep& step) noexcept;
  void build_landmarks(const VoInput& in, BoundedVector<match::Landmark3>& out) noexcept;
  // The appearance descriptor of a landmark for fc-matching's optional term (match.appearance_weight > 0).
  static bool fill_appearance(ConstImageViewU8 img, float x_px, float y_px, match::Landmark3& l) noexcept;
  // Flags the step lost and dead-reckons it on the chained prior, integrated with att (3D mode: the
  // attitude this frame integrates with; nullptr in 6D mode or without an absolute attitude).
  void finish_lost(VoStep& step, std::uint32_t why, const Mat3d* att) noexcept;
  // The sensor's absolute attitude when 3D-VME integrates with it (input-checked: a rotation), else nullptr.
  const Mat3d* sensor_attitude(const VoInput& in) const noexcept;
  bool filter_active(const VoInput& in) const noexcept;
  // Feeds the attitude filter with this frame (the reference frame since the last call); returns the
  // attitude to integrate with (corrected, or the sensor's if the filter refused).
  const Mat3d* filter_frame(const VoInput& in, bool has_vo, const Mat3d& dR_vo, const Mat3d& cov_vo_right,
                            VoStep& step) noexcept;
  // Re-associates ref and cur under est (mutual nearest within the gate); returns the pair count written
  // to mp_/mc_/w_.
  std::size_t icp_associate(const BoundedVector<match::Landmark3>& ref, const BoundedVector<match::Landmark3>& cur,
                            const Pose3& est) noexcept;
  // Re-measures the n final pairs (mp_/mc_/w_, pair_ref_/pair_cur_) by patch alignment (refine_tracks);
  // on success compacts the aligned pairs into the same buffers and returns their count, else 0 and the
  // buffers are unchanged.
  std::size_t refine_pairs(const VoInput& in, const BoundedVector<match::Landmark3>& ref,
                           const BoundedVector<match::Landmark3>& cur, std::size_t n, const Pose3& prev_T_cur) noexcept;
  // 6D-VME (mode k6D) or 3D-VME with the chained rotation, then IRLS when configured, on the first n pairs
  // of mp_ / mc_ / w_.
  Result<motion::RigidEstimate> solve_pairs(std::size_t n) noexcept;
  // Keeps a copy of this frame's left image as the reference for refine_tracks.
  void keep_reference_image(ConstImageViewU8 left) noexcept;
  // Per-point stereo error model for the anisotropic 6D refinement (lateral sigma of refined pairs or not).
  motion::StereoPointModel stereo_point_model(bool refined) const noexcept;
  double weight_for(double sigma2_m2) const noexcept {
    return config_.weighted ? (sigma2_m2 > 1e-12 ? 1e-4 / sigma2_m2 : 1e8) : 1.0;  // ~1 for 1 cm sigmas
  }

  VoConfig config_;
  bool ready_ = false;
  vision::HarrisDetector harris_;
  vision::StereoMatcher stereo_;
  match::GeometricMatcher matcher_;
  motion::PoseIntegrator integrator_;
  BoundedVector<vision::Corner> corners_;
  BoundedVector<vision::StereoPoint> points_;
  BoundedVector<match::Landmark3> landmarks_[2];
  Span<Vec3d> mp_;
  Span<Vec3d> mc_;
  Span<double> w_;
  Span<double> scratch_;
  Span<std::int32_t> nn_prev_;  // nearest cur of each prev landmark (ICP)
  Span<std::int32_t> nn_cur_;   // nearest prev of each cur landmark (ICP)
  Span<std::int32_t> pair_ref_;  // landmark indices of the pairs in mp_ / mc_
  Span<std::int32_t> pair_cur_;
  Span<Vec3d> refined_;          // aligned current points (refine_pairs)
  Span<double> refined_s2_;
  Span<std::uint8_t> ref_pixels_;  // the reference frame's left image (refine_tracks)
  ConstImageViewU8 ref_left_;
  TrackRefiner refiner_;
  int cur_ = 0;
  bool have_prev_ = false;
  // Prior chained since the reference frame (across bad-input frames).
  Mat3d chain_R_ = Mat3d::Identity();
  Vec3d chain_t_ = Vec3d::Zero();
  double chain_sigma2_ = 0.0;
  bool chain_has_t_ = false;
  motion::AttitudeBiasFilter att_filter_;
  std::uint64_t filter_stamp_ns_ = 0;
  std::uint32_t frames_since_filter_ = 0;
  Mat3d filter_ref_R_ = Mat3d::Identity();  // corrected attitude of the reference frame
  Mat3d filter_out_R_ = Mat3d::Identity();  // corrected_sample() of this frame
  CounterSet<VoCounter> counters_{kCounterNames};
};

}  // namespace qnav::vo
