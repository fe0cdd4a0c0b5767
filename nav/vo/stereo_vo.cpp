#include "nav/vo/stereo_vo.hpp"

#include <algorithm>
#include <cmath>

namespace qnav::vo {

const char* const StereoVo::kCounterNames[static_cast<std::size_t>(VoCounter::kCount)] = {
    "vo_bad_image",     "vo_bad_attitude", "vo_bad_prior",        "vo_few_corners",      "vo_few_stereo",
    "vo_few_matches",   "vo_high_residual", "vo_degenerate",      "vo_implausible_step", "vo_lost_frames",
    "vo_attitude_filter_rejected", "vo_track_align_failed", "vo_step_not_refined"};

namespace {

constexpr std::size_t kSlack = 64;

template <typename T>
std::size_t bytes_for(std::size_t n) noexcept {
  return n * sizeof(T) + alignof(T) + kSlack;
}

bool is_rotation(const Mat3d& R) noexcept {
  return R.allFinite() && (R.transpose() * R - Mat3d::Identity()).cwiseAbs().maxCoeff() < 1e-6 && R.determinant() > 0.0;
}

vision::HarrisConfig harris_config(const VoConfig& c) noexcept {
  vision::HarrisConfig h = c.harris;
  h.max_width = c.max_width;
  h.max_height = c.max_height;
  h.max_corners = c.max_corners;
  return h;
}

}  // namespace

std::size_t StereoVo::arena_bytes(const VoConfig& c) noexcept {
  if (c.max_corners <= 0) return 0;
  const std::size_t n = static_cast<std::size_t>(c.max_corners);
  return vision::HarrisDetector::arena_bytes(harris_config(c)) + bytes_for<vision::Corner>(n) +
         bytes_for<vision::StereoPoint>(n) + 2 * bytes_for<match::Landmark3>(n) + 2 * bytes_for<Vec3d>(n) +
         2 * bytes_for<double>(n) + 4 * bytes_for<std::int32_t>(n) + bytes_for<Vec3d>(n) + bytes_for<double>(n) +
         (c.refine_tracks ? bytes_for<std::uint8_t>(static_cast<std::size_t>(c.max_width) *
                                                    static_cast<std::size_t>(c.max_height))
                          : 0);
}

Status StereoVo::init(const VoConfig& config, Arena& arena) noexcept {
  ready_ = false;
  if (config.max_width <= 0 || config.max_height <= 0 || config.max_corners < 3 || config.max_corners > 4096 ||
      config.min_matches < 3 || !(config.max_rms_residual_m > 0.0) || !(config.max_step_m > 0.0) ||
      !(config.max_normalized_residual > 0.0) || config.icp_iterations < 0 || config.icp_iterations > 10 || !(config.lateral_sigma_px >= 0.0) || !(config.default_translation_sigma_m > 0.0) || !(config.max_depth_m > 0.0))
    return Status(StatusCode::kInvalidArgument, "VO config out of range");
  if (!(config.frame_period_s > 0.0) || !std::isfinite(config.frame_period_s))
    return Status(StatusCode::kInvalidArgument, "VO frame_period_s must be > 0");
  // Every check that needs no memory before the arena is touched.
  if (config.refine_tracks || config.refine_disparity) {
    QNAV_RETURN_IF_ERROR(refiner_.init(config.track_refine, config.camera));
    if (!(config.refined_lateral_sigma_px > 0.0) || !std::isfinite(config.refined_lateral_sigma_px))
      return Status(StatusCode::kInvalidArgument, "VO refined_lateral_sigma_px must be > 0");
  }
  QNAV_RETURN_IF_ERROR(stereo_.init(config.stereo, config.camera));
  QNAV_RETURN_IF_ERROR(att_filter_.init(config.attitude_bias));
  config_ = config;
  QNAV_RETURN_IF_ERROR(harris_.init(harris_config(config), arena));
  match::GeometricMatchConfig mc = config.match;
  mc.max_landmarks = static_cast<std::size_t>(config.max_corners);
  if (mc.max_matches > mc.max_landmarks) mc.max_matches = mc.max_landmarks;
  Result<match::GeometricMatcher> m = match::GeometricMatcher::create(mc);
  if (!m) return m.status();
  matcher_ = std::move(m.value());
  const std::size_t n = static_cast<std::size_t>(config.max_corners);
  Span<vision::Corner> cs = arena.allocate<vision::Corner>(n);
  Span<vision::StereoPoint> ps = arena.allocate<vision::StereoPoint>(n);
  Span<match::Landmark3> l0 = arena.allocate<match::Landmark3>(n);
  Span<match::Landmark3> l1 = arena.allocate<match::Landmark3>(n);
  mp_ = arena.allocate<Vec3d>(n);
  mc_ = arena.allocate<Vec3d>(n);
  w_ = arena.allocate<double>(n);
  scratch_ = arena.allocate<double>(n);
  nn_prev_ = arena.allocate<std::int32_t>(n);
  nn_cur_ = arena.allocate<std::int32_t>(n);
  pair_ref_ = arena.allocate<std::int32_t>(n);
  pair_cur_ = arena.allocate<std::int32_t>(n);
  refined_ = arena.allocate<Vec3d>(n);
  refined_s2_ = arena.allocate<double>(n);
  if (config.refine_tracks) {
    ref_pixels_ = arena.allocate<std::uint8_t>(static_cast<std::size_t>(config.max_width) *
                                               static_cast<std::size_t>(config.max_height));
    if (ref_pixels_.empty()) return Status(StatusCode::kCapacityExceeded, "arena too small for the VO reference image");
  }
  if (pair_ref_.empty() || pair_cur_.empty() || refined_.empty() || refined_s2_.empty() || nn_prev_.empty() || nn_cur_.empty() || cs.empty() || ps.empty() || l0.empty() || l1.empty() || mp_.empty() || mc_.empty() || w_.empty() || scratch_.empty())
    return Status(StatusCode::kCapacityExceeded, "arena too small for VO buffers");
  corners_ = BoundedVector<vision::Corner>(cs);
  points_ = BoundedVector<vision::StereoPoint>(ps);
  landmarks_[0] = BoundedVector<match::Landmark3>(l0);
  landmarks_[1] = BoundedVector<match::Landmark3>(l1);
  ready_ = true;
  reset();
  return Status::ok();
}

void StereoVo::reset(const Pose3& world_T_start) noexcept {
  integrator_.reset(world_T_start);
  have_prev_ = false;
  cur_ = 0;
  landmarks_[0].clear();
  landmarks_[1].clear();
  chain_R_ = Mat3d::Identity();
  chain_t_ = Vec3d::Zero();
  chain_sigma2_ = 0.0;
  chain_has_t_ = true;
  att_filter_.reset();
  filter_stamp_ns_ = 0;
  frames_since_filter_ = 0;
  filter_ref_R_ = Mat3d::Identity();
  ref_left_ = ConstImageViewU8();
}

void StereoVo::keep_reference_image(ConstImageViewU8 left) noexcept {
  if (!config_.refine_tracks || ref_pixels_.empty()) return;
  const int w = left.width(), h = left.height();
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* src = left.row(y);
    std::uint8_t* dst = ref_pixels_.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(w);
    for (int x = 0; x < w; ++x) dst[x] = src[x];
  }
  ref_left_ = ConstImageViewU8::unchecked(ref_pixels_.data(), w, h, w);
}

const Mat3d* StereoVo::sensor_attitude(const VoInput& in) const noexcept {
  return (config_.mode == VmeMode::k3D && in.has_absolute_attitude) ? &in.world_R_cam : nullptr;
}

motion::StereoPointModel StereoVo::stereo_point_model(bool refined) const noexcept {
  motion::StereoPointModel pm;
  const double fb = config_.camera.focal_px * config_.camera.baseline_m;
  const double lat = refined ? config_.refined_lateral_sigma_px : config_.lateral_sigma_px;
  pm.ray_sigma_per_z2 = fb > 0.0 ? static_cast<double>(config_.stereo.disparity_sigma_px) / fb : 0.0;
  pm.lateral_sigma_per_z = config_.camera.focal_px > 0.0 ? lat / config_.camera.focal_px : 0.0;
  // Unrefined pairs are two Harris detections associated by proximity, not one point with the model's
  // noise: the plain linearisation (seeds 3-10, 27 m: step rotation mean -0.03 deg about x with the
  // fused form, docs/vo.md).
  pm.fused_linearisation = refined;
  return pm;
}

bool StereoVo::filter_active(const VoInput& in) const noexcept {
  return config_.estimate_attitude_bias && sensor_attitude(in) != nullptr && is_rotation(in.world_R_cam);
}

const Mat3d* StereoVo::filter_frame(const VoInput& in, bool has_vo, const Mat3d& dR_vo, const Mat3d& cov_vo_right,
                                    VoStep& step) noexcept {
  if (!filter_active(in)) return sensor_attitude(in);
  double dt_s = config_.frame_period_s * static_cast<double>(frames_since_filter_ > 0 ? frames_since_filter_ : 1);
  if (filter_stamp_ns_ != 0 && in.stamp_ns > filter_stamp_ns_) dt_s = 1e-9 * static_cast<double>(in.stamp_ns - filter_stamp_ns_);
  if (in.attitude_recalibrated) att_filter_.recalibrated();
  const Status s = att_filter_.update(in.world_R_cam, dt_s, has_vo, dR_vo, cov_vo_right);
  filter_stamp_ns_ = in.stamp_ns;
  frames_since_filter_ = 0;
  if (!s.is_ok()) counters_.increment(VoCounter::kAttitudeFilterRejected);
  if (!att_filter_.initialised()) return &in.world_R_cam;
  step.attitude_corrected = true;
  step.attitude_drift_rad = att_filter_.drift_rad();
  if (config_.use_filtered_orientation) return &att_filter_.corrected();
  filter_out_R_ = att_filter_.corrected_sample();
  return &filter_out_R_;
}

void StereoVo::build_landmarks(const VoInput& in, BoundedVector<match::Landmark3>& out) noexcept {
  out.clear();
  const double f = config_.camera.focal_px;
  for (vision::StereoPoint& p : points_) {
    // Row alignment of the left patch into the right image from the parabola's disparity (a point that
    // does not align keeps the parabola's).
    if (config_.refine_disparity) (void)refiner_.refine_disparity(in.left, in.right, config_.stereo.disparity_sigma_px, p);
    const Vec3d pos = p.p_m.cast<double>();
    if (!pos.allFinite() || !(pos.z() > 0.0) || pos.z() > config_.max_depth_m || !std::isfinite(p.sigma_z_m)) continue;
    match::Landmark3* l = out.emplace_back();
    if (l == nullptr) break;
    const double sz = static_cast<double>(p.sigma_z_m);
    const double sxy = pos.z() / f * config_.lateral_sigma_px;
    l->position_m = pos;
    l->sigma_m = std::sqrt(sz * sz + sxy * sxy);
    const std::uint32_t ci = p.corner_index;
    l->score = ci < corners_.size() ? static_cast<double>(corners_[ci].score) : 0.0;
    l->u_px = p.x_px;
    l->v_px = p.y_px;
    l->has_appearance = config_.match.appearance_weight > 0.0 && fill_appearance(in.left, p.x_px, p.y_px, *l);
  }
}

bool StereoVo::fill_appearance(ConstImageViewU8 img, float x_px, float y_px, match::Landmark3& l) noexcept {
  // The fc appearance term's descriptor (match::kAppearanceDims = 9): the 3x3 grid of 3x3-pixel block means
  // around the corner (a 9x9 pixel support), zero-mean and unit-norm, so the matcher's dot product is a
  // normalised cross-correlation of coarse appearance.
  static_assert(match::kAppearanceDims == 9, "a 3x3 grid of block means");
  const int cx = static_cast<int>(std::lround(x_px)), cy = static_cast<int>(std::lround(y_px));
  if (cx < 4 || cy < 4 || cx + 4 >= img.width() || cy + 4 >= img.height()) return false;
  float mean = 0.0f;
  for (int gy = 0; gy < 3; ++gy)
    for (int gx = 0; gx < 3; ++gx) {
      int sum = 0;
      for (int j = -1; j <= 1; ++j) {
        const std::uint8_t* row = img.row(cy + 3 * (gy - 1) + j) + cx + 3 * (gx - 1);
        sum += row[-1] + row[0] + row[1];
      }
      l.appearance[gy * 3 + gx] = static_cast<float>(sum) / 9.0f;
      mean += l.appearance[gy * 3 + gx];
    }
  mean /= 9.0f;
  float ss = 0.0f;
  for (float& v : l.appearance) {
    v -= mean;
    ss += v * v;
  }
  if (!(ss > 1.0f)) return false;  // a flat neighbourhood: no appearance evidence
  const float inv = 1.0f / std::sqrt(ss);
  for (float& v : l.appearance) v *= inv;
  return true;
}

void StereoVo::finish_lost(VoStep& step, std::uint32_t why, const Mat3d* att) noexcept {
  step.flags |= why | kVoLost;
  counters_.increment(VoCounter::kLostFrames);
  step.visual = false;
  if (chain_has_t_ && is_rotation(chain_R_) && chain_t_.allFinite()) {
    const Pose3 dr{chain_R_, chain_t_};
    const Mat3d cov = Mat3d::Identity() * (chain_sigma2_ > 0.0 ? chain_sigma2_ : 0.0);
    if (integrator_.add_step(dr, cov, att).is_ok()) {
      step.flags |= kVoDeadReckoned;
      step.prev_T_cur = dr;
    }
  }
}

std::size_t StereoVo::icp_associate(const BoundedVector<match::Landmark3>& ref,
                                    const BoundedVector<match::Landmark3>& cur, const Pose3& est) noexcept {
  const double ns = config_.match.n_sigma;
  // The current landmarks in the reference frame, once (refined_ is free until refine_pairs).
  for (std::size_t j = 0; j < cur.size(); ++j) {
    nn_cur_[j] = -1;
    refined_[j] = est.apply(cur[j].position_m);
  }
  // Gate terms of the cur landmarks, once: w_ is free until the pairs are written below.
  for (std::size_t j = 0; j < cur.size(); ++j) w_[j] = ns * ns * cur[j].sigma_m * cur[j].sigma_m;
  // Nearest cur for each prev within the gate: the cur j with the smallest d2 < gi + w_[j], the lowest j
  // among equals (what the scan in ascending j below gives: it takes only strictly nearer ones).
  const std::size_t nc = cur.size();
  auto scan_all = [&](std::size_t i, const Vec3d& p, double gi) {
    nn_prev_[i] = -1;
    double best = 0.0;
    for (std::size_t j = 0; j < nc; ++j) {
      // The bound is the gate, or the best so far when nearer; the x term alone rejects most pairs.
      const double bound = nn_prev_[i] >= 0 && best < gi + w_[j] ? best : gi + w_[j];
      const double dx = p.x() - refined_[j].x();
      const double dx2 = dx * dx;
      if (dx2 >= bound) continue;
      const double dy = p.y() - refined_[j].y(), dz = p.z() - refined_[j].z();
      const double d2 = dx2 + dy * dy + dz * dz;  // the order of squaredNorm()
      if (d2 >= bound) continue;
      nn_prev_[i] = static_cast<std::int32_t>(j);
      best = d2;
    }
  };
  bool finite = true;
  double w_max = 0.0;
  for (std::size_t j = 0; j < nc; ++j) {
    finite = finite && refined_[j].allFinite() && std::isfinite(w_[j]);
    w_max = std::max(w_max, w_[j]);
  }
  // The curs in ascending x (ties by index; pair_cur_ is free until the pairs are written below). Each
  // prev is scanned outwards from its x on both sides until dx^2 reaches the largest gate or exceeds the
  // best d2 so far: d2 (dx^2 plus non-negative rounded squares) is at least dx^2, and dx^2 does not
  // shrink along either side (rounding is monotone), so no cur the full scan would take is skipped, and
  // equal d2 are decided by index. The same pairs as scan_all, bit for bit, in O(n log n + n_p k) for k
  // curs within reach instead of O(n_p n_c). Non-finite values (which the comparisons cannot order)
  // take scan_all.
  std::int32_t* order = pair_cur_.data();
  if (finite) {
    for (std::size_t j = 0; j < nc; ++j) order[j] = static_cast<std::int32_t>(j);
    std::sort(order, order + nc, [this](std::int32_t a, std::int32_t b) {
      const double xa = refined_[static_cast<std::size_t>(a)].x(), xb = refined_[static_cast<std::size_t>(b)].x();
      return xa < xb || (xa == xb && a < b);
    });
  }
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const Vec3d p = ref[i].position_m;
    const double gi = ns * ns * ref[i].sigma_m * ref[i].sigma_m;
    const double gate_max = gi + w_max;  // >= gi + w_[j] for every j
    if (!finite || !p.allFinite() || !std::isfinite(gate_max)) {
      scan_all(i, p, gi);
      continue;
    }
    std::int32_t best_j = -1;
    double best = 0.0;
    auto visit = [&](std::int32_t jj) {  // false once no cur further along this side can be taken
      const std::size_t j = static_cast<std::size_t>(jj);
      const double dx = p.x() - refined_[j].x();
      const double dx2 = dx * dx;
      if (dx2 >= gate_max || (best_j >= 0 && dx2 > best)) return false;
      const double gate = gi + w_[j];
      if (dx2 >= gate) return true;
      const double dy = p.y() - refined_[j].y(), dz = p.z() - refined_[j].z();
      const double d2 = dx2 + dy * dy + dz * dz;  // the order of squaredNorm()
      if (d2 >= gate) return true;
      if (best_j < 0 || d2 < best || (d2 == best && jj < best_j)) {
        best_j = jj;
        best = d2;
      }
      return true;
    };
    const std::int32_t* split = std::lower_bound(order, order + nc, p.x(), [this](std::int32_t a, double x) {
      return refined_[static_cast<std::size_t>(a)].x() < x;
    });
    for (const std::int32_t* o = split; o != order + nc && visit(*o); ++o) {
    }
    for (const std::int32_t* o = split; o != order && visit(*(o - 1)); --o) {
    }
    nn_prev_[i] = best_j;
  }
  // Nearest prev for each cur among the prevs that chose it (ascending i, strictly nearer wins: O(n_p)).
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const std::int32_t j = nn_prev_[i];
    if (j < 0) continue;
    const Vec3d& c = refined_[static_cast<std::size_t>(j)];
    std::int32_t& best = nn_cur_[static_cast<std::size_t>(j)];
    if (best >= 0 && (ref[i].position_m - c).squaredNorm() >= (ref[static_cast<std::size_t>(best)].position_m - c).squaredNorm())
      continue;
    best = static_cast<std::int32_t>(i);
  }
  std::size_t n = 0;
  for (std::size_t j = 0; j < cur.size() && n < mp_.size(); ++j) {
    if (nn_cur_[j] < 0) continue;
    const match::Landmark3& a = ref[static_cast<std::size_t>(nn_cur_[j])];
    const match::Landmark3& b = cur[j];
    mp_[n] = a.position_m;
    mc_[n] = b.position_m;
    w_[n] = weight_for(a.sigma_m * a.sigma_m + b.sigma_m * b.sigma_m);
    pair_ref_[n] = nn_cur_[j];
    pair_cur_[n] = static_cast<std::int32_t>(j);
    ++n;
  }
  return n;
}

Result<motion::RigidEstimate> StereoVo::solve_pairs(std::size_t n) noexcept {
  const Span<const Vec3d> P(mp_.data(), n), C(mc_.data(), n);
  const Span<const double> W(w_.data(), n);
  const Span<double> scratch(scratch_.data(), n);
  if (config_.mode == VmeMode::k6D) {
    Result<motion::RigidEstimate> r = motion::estimate_rigid_6d(P, C, W);
    if (r && config_.irls) r = motion::refine_irls_6d(P, C, r.value(), config_.irls_config, scratch, W);
    return r;
  }
  Result<motion::RigidEstimate> r = motion::estimate_translation_3d(P, C, chain_R_, W);
  if (r && config_.irls) r = motion::refine_irls_3d(P, C, r.value(), config_.irls_config, scratch, W);
  return r;
}

std::size_t StereoVo::refine_pairs(const VoInput& in, const BoundedVector<match::Landmark3>& ref,
                                  const BoundedVector<match::Landmark3>& cur, std::size_t n,
                                  const Pose3& prev_T_cur) noexcept {
  if (ref_left_.empty() || ref_left_.width() != in.left.width() || ref_left_.height() != in.left.height()) return 0;
  const double f = config_.camera.focal_px;
  const double lat = config_.refined_lateral_sigma_px;
  const double lat_old = config_.lateral_sigma_px;
  // Depth variance of a landmark (its isotropic sigma minus the lateral term build_landmarks added).
  auto depth_var = [&](const match::Landmark3& l) {
    const double sxy = l.position_m.z() / f * lat_old;
    return std::max(0.0, l.sigma_m * l.sigma_m - sxy * sxy);
  };
  // The reference landmarks by x for the refiner's neighbour search (nn_prev_ is free outside icp_associate).
  const Span<const match::Landmark3> ref_span(ref.data(), ref.size());
  const Span<const std::int32_t> ref_by_x =
      TrackRefiner::sort_by_x(ref_span, nn_prev_) ? Span<const std::int32_t>(nn_prev_.data(), ref.size())
                                                  : Span<const std::int32_t>();
  std::size_t good = 0;
  for (std::size_t k = 0; k < n; ++k) {
    refined_s2_[k] = -1.0;  // not aligned
    const std::size_t ia = static_cast<std::size_t>(pair_ref_[k]);
    const match::Landmark3& a = ref[ia];
    const match::Landmark3& b = cur[static_cast<std::size_t>(pair_cur_[k])];
    Vec3d qd;
    if (!refiner_.refine(ref_left_, ref_span, ia, in.left, in.right, b, prev_T_cur, qd, ref_by_x)
             .is_ok()) {
      counters_.increment(VoCounter::kTrackAlignFailed);
      continue;
    }
    const double sz = static_cast<double>(
        vision::depth_sigma_m(config_.camera, static_cast<float>(qd.z()), config_.stereo.disparity_sigma_px));
    const double sa = a.position_m.z() / f * lat, sb = qd.z() / f * lat;
    refined_[k] = qd;
    refined_s2_[k] = depth_var(a) + sa * sa + sz * sz + sb * sb;
    ++good;
  }
  if (good < config_.min_matches) {
    counters_.increment(VoCounter::kStepNotRefined);
    return 0;
  }
  std::size_t m = 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (refined_s2_[k] < 0.0) continue;
    mp_[m] = mp_[k];
    mc_[m] = refined_[k];
    w_[m] = weight_for(refined_s2_[k]);
    pair_ref_[m] = pair_ref_[k];
    pair_cur_[m] = pair_cur_[k];
    ++m;
  }
  return m;
}

bool StereoVo::accept_input(const VoInput& in, VoStep& step) noexcept {
  const bool image_ok = !in.left.empty() && !in.right.empty() && in.left.width() == in.right.width() &&
                        in.left.height() == in.right.height() && in.left.width() <= config_.max_width &&
                        in.left.height() <= config_.max_height;
  const bool attitude_ok = is_rotation(in.R_prev_cur) && (!in.has_absolute_attitude || is_rotation(in.world_R_cam));
  const bool prior_ok = !in.has_translation_prior ||
                        (in.t_prev_cur_prior_m.allFinite() && std::isfinite(in.t_prior_sigma_m) && in.t_prior_sigma_m >= 0.0);
  if (!image_ok) counters_.increment(VoCounter::kBadImage);
  if (!attitude_ok) counters_.increment(VoCounter::kBadAttitude);
  if (!prior_ok) counters_.increment(VoCounter::kBadPrior);
  // Chain the prior since the reference frame.
  if (attitude_ok) {
    if (in.has_translation_prior && prior_ok) {
      chain_t_ = chain_R_ * in.t_prev_cur_prior_m + chain_t_;
      chain_sigma2_ += in.t_prior_sigma_m * in.t_prior_sigma_m;
    } else {
      chain_has_t_ = false;
    }
    chain_R_ = chain_R_ * in.R_prev_cur;
  }
  if (image_ok && attitude_ok) return true;
  step.flags |= kVoBadInput | kVoLost;
  counters_.increment(VoCounter::kLostFrames);
  if (!attitude_ok) {
    // Without a rotation the chain is broken: the next good frame restarts from scratch.
    have_prev_ = false;
    reset_chain();
    att_filter_.reset();  // restarts from the next good sample
    filter_stamp_ns_ = 0;
  }
  // With a good attitude the reference is kept and the chained prior carries this frame's motion.
  return false;
}

void StereoVo::reset_chain() noexcept {
  chain_R_ = Mat3d::Identity();
  chain_t_ = Vec3d::Zero();
  chain_sigma2_ = 0.0;
  chain_has_t_ = true;
}

bool StereoVo::front_end(const VoInput& in, BoundedVector<match::Landmark3>& lms, VoStep& step) noexcept {
  lms.clear();
  points_.clear();
  const Status hs = harris_.detect(in.left, corners_);
  step.corners = hs.is_ok() ? corners_.size() : 0;
  if (hs.is_ok()) {
    const Status ss = stereo_.match(in.left, in.right, Span<const vision::Corner>(corners_.data(), corners_.size()), points_);
    if (ss.is_ok() || ss.code() == StatusCode::kCapacityExceeded) build_landmarks(in, lms);
  }
  step.stereo_points = points_.size();
  step.landmarks = lms.size();
  if (lms.size() >= config_.min_stereo_points) return true;
  const bool few_corners = step.corners < config_.min_stereo_points;
  counters_.increment(few_corners ? VoCounter::kFewCorners : VoCounter::kFewStereo);
  // Without a reference yet this is still the first frame; with one, the old reference is kept and the
  // chained prior carries the motion to the next frame.
  step.flags |= (few_corners ? kVoFewCorners : kVoFewStereo) | kVoLost | (have_prev_ ? 0u : kVoFirstFrame);
  counters_.increment(VoCounter::kLostFrames);
  return false;
}

void StereoVo::start_reference(const VoInput& in, int next, VoStep& step) noexcept {
  step.flags |= kVoFirstFrame;
  const Mat3d* att = filter_frame(in, false, Mat3d::Identity(), Mat3d::Zero(), step);
  if (att != nullptr && integrator_.steps() == 0) {
    Pose3 p = integrator_.pose();
    p.R = *att;
    integrator_.reset(p);
  }
  filter_ref_R_ = att != nullptr ? *att : Mat3d::Identity();
  keep_reference_image(in.left);
  cur_ = next;
  have_prev_ = true;
  reset_chain();
}

match::MotionPrior StereoVo::chained_prior() const noexcept {
  match::MotionPrior prior;
  prior.R_prev_cur = chain_R_;
  if (chain_has_t_) {
    prior.t_prev_cur_m = chain_t_;
    prior.translation_sigma_m = std::sqrt(chain_sigma2_);
  } else {
    prior.t_prev_cur_m = Vec3d::Zero();
    prior.translation_sigma_m = config_.default_translation_sigma_m;
  }
  return prior;
}

std::uint32_t StereoVo::estimate_step(const BoundedVector<match::Landmark3>& ref, const BoundedVector<match::Landmark3>& lms,
                                      VoStep& step, motion::RigidEstimate& est, std::size_t& n_final_pairs) noexcept {
  n_final_pairs = 0;
  Result<Span<const match::Match>> mr = matcher_.match(Span<const match::Landmark3>(ref.data(), ref.size()),
                                                       Span<const match::Landmark3>(lms.data(), lms.size()), chained_prior());
  step.match_stats = matcher_.stats();
  if (!mr) {
    counters_.increment(VoCounter::kDegenerate);
    return kVoDegenerate;
  }
  const Span<const match::Match> matches = mr.value();
  step.matches = matches.size();
  if (matches.size() < config_.min_matches) {
    counters_.increment(VoCounter::kFewMatches);
    return kVoFewMatches;
  }
  const std::size_t n = matches.size();
  for (std::size_t k = 0; k < n; ++k) {
    const match::Landmark3& a = ref[matches[k].prev];
    const match::Landmark3& b = lms[matches[k].cur];
    mp_[k] = a.position_m;
    mc_[k] = b.position_m;
    w_[k] = weight_for(a.sigma_m * a.sigma_m + b.sigma_m * b.sigma_m);
    pair_ref_[k] = static_cast<std::int32_t>(matches[k].prev);
    pair_cur_[k] = static_cast<std::int32_t>(matches[k].cur);
  }
  std::size_t n_final = n;
  std::size_t n_buf = n;
  Result<motion::RigidEstimate> r = solve_pairs(n);
  for (int it = 0; r && it < config_.icp_iterations; ++it) {
    const std::size_t m = icp_associate(ref, lms, r->pose);
    n_buf = m;
    if (m < config_.min_matches) break;
    Result<motion::RigidEstimate> r2 = solve_pairs(m);
    if (!r2) break;
    r = r2;
    step.matches = m;
    n_final = m;
  }
  if (!r) {
    counters_.increment(VoCounter::kDegenerate);
    return kVoDegenerate;
  }
  est = r.value();
  n_final_pairs = n_buf == n_final ? n_final : 0;  // 0: the buffers no longer hold est's pairs
  return check_estimate(est, n_final, step);
}

std::uint32_t StereoVo::check_estimate(const motion::RigidEstimate& est, std::size_t n_final, VoStep& step) noexcept {
  step.inliers = est.inliers;
  step.rms_residual_m = est.rms_residual_m;
  // w = 1e-4 / s2 (weighted) -> predicted rms sigma from the weights' harmonic mean.
  double sum_s2 = 0.0;
  for (std::size_t k = 0; k < n_final; ++k) sum_s2 += config_.weighted ? 1e-4 / w_[k] : 0.0;
  const double pred = config_.weighted && n_final > 0 ? std::sqrt(sum_s2 / static_cast<double>(n_final)) : 0.0;
  step.normalized_residual = pred > 0.0 ? est.rms_residual_m / pred : 0.0;
  if (!(est.rms_residual_m <= config_.max_rms_residual_m) || !(step.normalized_residual <= config_.max_normalized_residual)) {
    counters_.increment(VoCounter::kHighResidual);
    return kVoHighResidual;
  }
  if (!(est.pose.t.norm() <= config_.max_step_m) || !(rotation_angle_rad(est.pose.R) <= config_.max_step_rotation_rad) ||
      !est.pose.is_finite()) {
    counters_.increment(VoCounter::kImplausibleStep);
    return kVoImplausible;
  }
  return 0;
}

std::size_t StereoVo::refine_estimate(const VoInput& in, const BoundedVector<match::Landmark3>& ref,
                                      const BoundedVector<match::Landmark3>& lms, std::size_t n_final_pairs,
                                      motion::RigidEstimate& est, VoStep& step) noexcept {
  if (!config_.refine_tracks || n_final_pairs == 0) return 0;
  const std::size_t m = refine_pairs(in, ref, lms, n_final_pairs, est.pose);
  if (m == 0) return 0;
  // The buffers now hold the aligned pairs.
  Result<motion::RigidEstimate> rr = solve_pairs(m);
  if (rr && config_.mode == VmeMode::k6D && config_.anisotropic_vo_rotation) {
    const Span<const Vec3d> P(mp_.data(), m), C(mc_.data(), m);
    Result<motion::RigidEstimate> ra = motion::refine_rigid_6d_stereo(P, C, rr.value(), stereo_point_model(true));
    if (ra) rr = ra;
  }
  if (rr && rr->pose.is_finite() && rr->pose.t.norm() <= config_.max_step_m &&
      rotation_angle_rad(rr->pose.R) <= config_.max_step_rotation_rad) {
    est.pose = rr->pose;
    est.covariance = rr->covariance;
    step.refined_pairs = m;
  }
  return m;
}

const Mat3d* StereoVo::filtered_attitude(const VoInput& in, std::size_t n_pairs, bool refined, motion::RigidEstimate& est,
                                         VoStep& step) noexcept {
  if (!filter_active(in)) return sensor_attitude(in);
  // 6D-VME on the final pairs gives this step's visual rotation for the attitude filter.
  const Span<const Vec3d> P(mp_.data(), n_pairs), C(mc_.data(), n_pairs);
  const Span<const double> W(w_.data(), n_pairs);
  Result<motion::RigidEstimate> r6 = motion::estimate_rigid_6d(P, C, W);
  if (r6 && config_.irls)
    r6 = motion::refine_irls_6d(P, C, r6.value(), config_.irls_config, Span<double>(scratch_.data(), n_pairs), W);
  if (r6 && config_.anisotropic_vo_rotation) {
    Result<motion::RigidEstimate> ra = motion::refine_rigid_6d_stereo(P, C, r6.value(), stereo_point_model(refined));
    if (ra) r6 = ra;
  }
  const bool vo_ok = n_pairs >= config_.min_matches && r6 && r6->pose.is_finite() &&
                     rotation_angle_rad(r6->pose.R) <= config_.max_step_rotation_rad;
  const Mat3d R6 = vo_ok ? r6->pose.R : Mat3d::Identity();
  const Mat3d cov_right = vo_ok ? Mat3d(R6.transpose() * r6->covariance.topLeftCorner<3, 3>() * R6) : Mat3d::Zero();
  step.has_vo_rotation = vo_ok;
  step.vo_R_prev_cur = R6;
  step.vo_rotation_cov_right = cov_right;
  const Mat3d ref_R = filter_ref_R_;
  const bool was_init = att_filter_.initialised();
  const Mat3d* att = filter_frame(in, vo_ok, R6, cov_right, step);
  if (config_.corrected_step_rotation && was_init && att_filter_.initialised() && step.attitude_corrected) {
    // 3D-VME again with the corrected step rotation (same pairs, same weights).
    const Mat3d R_step = ref_R.transpose() * (*att);
    Result<motion::RigidEstimate> r3 = motion::estimate_translation_3d(P, C, R_step, W);
    if (r3 && config_.irls)
      r3 = motion::refine_irls_3d(P, C, r3.value(), config_.irls_config, Span<double>(scratch_.data(), n_pairs), W);
    if (r3 && r3->pose.is_finite() && r3->pose.t.norm() <= config_.max_step_m) {
      est.pose = r3->pose;
      est.covariance = r3->covariance;
    }
  }
  return att;
}

void StereoVo::integrate_step(const VoInput& in, const BoundedVector<match::Landmark3>& ref,
                              const BoundedVector<match::Landmark3>& lms, std::size_t n_final_pairs,
                              motion::RigidEstimate& est, VoStep& step) noexcept {
  // Track refinement: the final pairs re-measured by patch alignment, the step re-estimated on them.
  const std::size_t m = refine_estimate(in, ref, lms, n_final_pairs, est, step);
  const std::size_t n_pairs = m > 0 ? m : n_final_pairs;
  const bool refined = step.refined_pairs > 0;
  const Mat3d* att = filtered_attitude(in, n_pairs, refined, est, step);
  const Mat3d cov_t = est.covariance.bottomRightCorner<3, 3>();
  if (integrator_.add_step(est.pose, cov_t, att).is_ok()) {
    step.visual = true;
    step.prev_T_cur = est.pose;
    step.covariance = est.covariance;
  } else {
    finish_lost(step, kVoDegenerate, att);  // dead-reckon with the attitude this frame already has
  }
}

Result<VoStep> StereoVo::process(const VoInput& in) noexcept {
  if (!ready_) return Status(StatusCode::kNotReady, "StereoVo::process before init");
  VoStep step;
  if (frames_since_filter_ < 1000000u) ++frames_since_filter_;
  const int next = 1 - cur_;
  BoundedVector<match::Landmark3>& lms = landmarks_[next];
  if (!accept_input(in, step) || !front_end(in, lms, step)) {
    step.world_T_cur = integrator_.pose();
    return step;
  }
  if (!have_prev_) {
    start_reference(in, next, step);
    step.world_T_cur = integrator_.pose();
    return step;
  }
  const BoundedVector<match::Landmark3>& ref = landmarks_[cur_];
  motion::RigidEstimate est;
  std::size_t n_final_pairs = 0;  // pairs in mp_/mc_/w_ that est was computed from (0: inconsistent)
  const std::uint32_t why = estimate_step(ref, lms, step, est, n_final_pairs);
  if (why != 0) {
    finish_lost(step, why, filter_frame(in, false, Mat3d::Identity(), Mat3d::Zero(), step));
  } else {
    integrate_step(in, ref, lms, n_final_pairs, est, step);
  }
  filter_ref_R_ = (step.attitude_corrected ? (config_.use_filtered_orientation ? att_filter_.corrected() : filter_out_R_)
                                           : (in.has_absolute_attitude ? in.world_R_cam : Mat3d::Identity()));
  // This frame becomes the reference (it has enough landmarks), so the next good frame recovers.
  keep_reference_image(in.left);
  cur_ = next;
  reset_chain();
  step.world_T_cur = integrator_.pose();
  return step;
}

}  // namespace qnav::vo
