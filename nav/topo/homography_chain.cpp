#include "nav/topo/homography_chain.hpp"

#include <algorithm>
#include <cmath>

namespace qnav::topo {

namespace {

constexpr std::size_t kSlackPerBuffer = 64;

template <typename T>
std::size_t bytes_of(std::size_t n) noexcept {
  return n * sizeof(T) + alignof(T) + kSlackPerBuffer;
}

bool corner_before(const vision::Corner& a, const vision::Corner& b) noexcept {
  if (a.score != b.score) return a.score > b.score;
  if (a.y != b.y) return a.y < b.y;
  if (a.x != b.x) return a.x < b.x;
  return a.level < b.level;
}

// Jacobian of pi(H [p; 1]) at p; false when p maps to infinity.
bool jacobian_at(const Mat3d& H, const Vec2d& p, Vec2d& mapped, Eigen::Matrix2d& J) noexcept {
  const Vec3d u = H * Vec3d(p.x(), p.y(), 1.0);
  if (!(std::abs(u.z()) > 1e-12)) return false;
  const double x = u.x() / u.z(), y = u.y() / u.z();
  J(0, 0) = (H(0, 0) - x * H(2, 0)) / u.z();
  J(0, 1) = (H(0, 1) - x * H(2, 1)) / u.z();
  J(1, 0) = (H(1, 0) - y * H(2, 0)) / u.z();
  J(1, 1) = (H(1, 1) - y * H(2, 1)) / u.z();
  mapped = Vec2d(x, y);
  return mapped.allFinite() && J.allFinite();
}

}  // namespace

const char* to_string(StepStatus s) noexcept {
  switch (s) {
    case StepStatus::kOk: return "ok";
    case StepStatus::kBadInput: return "bad_input";
    case StepStatus::kFewKeypoints: return "few_keypoints";
    case StepStatus::kFewMatches: return "few_matches";
    case StepStatus::kDegenerate: return "degenerate";
  }
  return "?";
}

static match::RatioMatchConfig ratio_config(const HomographyChainConfig& c) noexcept {
  match::RatioMatchConfig r = c.ratio;
  r.max_query = c.max_keypoints;
  r.max_train = c.max_keypoints;
  r.search_radius_px = c.predicted_radius_px;
  return r;
}

static vision::HarrisConfig harris_config(const HomographyChainConfig& c) noexcept {
  vision::HarrisConfig h = c.harris;
  h.max_width = c.max_width;
  h.max_height = c.max_height;
  h.max_corners = c.corners_per_level;
  if (h.border_px < h.block_radius + 1) h.border_px = h.block_radius + 1;
  return h;
}

std::size_t HomographyChain::arena_bytes(const HomographyChainConfig& c) noexcept {
  if (c.max_width <= 0 || c.max_height <= 0 || c.pyramid_levels < 1 || c.pyramid_levels > 4) return 0;
  std::size_t total = 4096;
  for (int l = 0; l < c.pyramid_levels; ++l) {
    const std::size_t px = static_cast<std::size_t>(c.max_width >> l) * static_cast<std::size_t>(c.max_height >> l);
    total += bytes_of<std::uint8_t>(px) + 2 * bytes_of<float>(px);  // level, gradient planes
  }
  total += vision::HarrisDetector::arena_bytes(harris_config(c));
  total += match::RatioMatcher::arena_bytes(ratio_config(c));
  const std::size_t cpl = static_cast<std::size_t>(c.corners_per_level > 0 ? c.corners_per_level : 0);
  total += bytes_of<vision::Corner>(cpl) + bytes_of<vision::Corner>(cpl * static_cast<std::size_t>(c.pyramid_levels));
  const float cell = c.min_separation_px > 0.0f ? c.min_separation_px / 1.41421356f : 1.0f;
  const std::size_t gw = static_cast<std::size_t>(static_cast<float>(c.max_width) / cell) + 2;
  const std::size_t gh = static_cast<std::size_t>(static_cast<float>(c.max_height) / cell) + 2;
  total += bytes_of<std::int32_t>(gw * gh);
  const std::size_t k = c.max_keypoints;
  total += 2 * bytes_of<vision::OrientedDescriptor>(k) + bytes_of<match::DescriptorMatch>(k);
  total += 5 * bytes_of<Vec2d>(k) + 2 * bytes_of<std::uint8_t>(k) + bytes_of<double>(k);
  return total;
}

Status HomographyChain::init(const HomographyChainConfig& c, Arena& arena) noexcept {
  ready_ = false;
  if (c.max_width < 32 || c.max_height < 32 || c.max_width > kMaxImageSide || c.max_height > kMaxImageSide)
    return Status(StatusCode::kInvalidArgument, "homography chain: max image size out of range");
  if (c.pyramid_levels < 1 || c.pyramid_levels > 4)
    return Status(StatusCode::kInvalidArgument, "homography chain: pyramid_levels not in 1..4");
  if (c.corners_per_level < 8 || c.max_keypoints < 8 || c.max_keypoints > 65535)
    return Status(StatusCode::kInvalidArgument, "homography chain: keypoint caps out of range");
  if (!(c.min_separation_px >= 1.0f) || !(c.descriptor_scale >= 0.25f && c.descriptor_scale <= vision::kOrientedMaxScale) ||
      c.border_px < 0 || !(c.predicted_radius_px > 0.0f))
    return Status(StatusCode::kInvalidArgument, "homography chain: separation, descriptor scale, border or radius out of range");
  if (c.min_inliers < motion::kHomographyMinPairs || c.min_matches < motion::kHomographyMinPairs || c.min_keypoints < 4)
    return Status(StatusCode::kInvalidArgument, "homography chain: floors below the 4 pairs a homography needs");
  if (!(c.min_scale > 0.0 && c.min_scale < 1.0 && c.max_scale > 1.0) || !(c.max_perspective > 0.0) ||
      !(c.min_overlap >= 0.0 && c.min_overlap <= 1.0) || c.max_keyframe_gap < 1)
    return Status(StatusCode::kInvalidArgument, "homography chain: scale, perspective, overlap or keyframe limits out of range");
  if (!(c.dark_mean >= 0.0) || !(c.saturated_fraction > 0.0 && c.saturated_fraction <= 1.0) || !(c.min_stddev >= 0.0))
    return Status(StatusCode::kInvalidArgument, "homography chain: frame check limits out of range");
  if (!std::isfinite(c.camera.fx) || !std::isfinite(c.camera.fy) || !std::isfinite(c.camera.cx) ||
      !std::isfinite(c.camera.cy) || c.camera.fx < 0.0 || c.camera.fy < 0.0)
    return Status(StatusCode::kInvalidArgument, "homography chain: camera intrinsics not finite or negative");
  config_ = c;

  vision::PyramidConfig pc;
  pc.max_width = c.max_width;
  pc.max_height = c.max_height;
  pc.levels = c.pyramid_levels;
  QNAV_RETURN_IF_ERROR(pyramid_.init(pc, arena));
  QNAV_RETURN_IF_ERROR(harris_.init(harris_config(c), arena));
  QNAV_RETURN_IF_ERROR(matcher_.init(ratio_config(c), arena));
  for (int l = 0; l < c.pyramid_levels; ++l) {
    const std::size_t px = static_cast<std::size_t>(c.max_width >> l) * static_cast<std::size_t>(c.max_height >> l);
    grad_mag_[l] = arena.allocate<float>(px);
    grad_ang_[l] = arena.allocate<float>(px);
    if (grad_mag_[l].empty() || grad_ang_[l].empty())
      return Status(StatusCode::kCapacityExceeded, "homography chain: arena too small");
  }

  const std::size_t cpl = static_cast<std::size_t>(c.corners_per_level);
  Span<vision::Corner> cs = arena.allocate<vision::Corner>(cpl);
  Span<vision::Corner> acs = arena.allocate<vision::Corner>(cpl * static_cast<std::size_t>(c.pyramid_levels));
  cell_px_ = c.min_separation_px / 1.41421356f;
  grid_w_ = static_cast<int>(static_cast<float>(c.max_width) / cell_px_) + 2;
  grid_h_ = static_cast<int>(static_cast<float>(c.max_height) / cell_px_) + 2;
  grid_ = arena.allocate<std::int32_t>(static_cast<std::size_t>(grid_w_) * static_cast<std::size_t>(grid_h_));
  const std::size_t k = c.max_keypoints;
  Span<vision::OrientedDescriptor> da = arena.allocate<vision::OrientedDescriptor>(k);
  Span<vision::OrientedDescriptor> db = arena.allocate<vision::OrientedDescriptor>(k);
  Span<match::DescriptorMatch> ms = arena.allocate<match::DescriptorMatch>(k);
  predicted_ = arena.allocate<Vec2d>(k);
  src_ = arena.allocate<Vec2d>(k);
  dst_ = arena.allocate<Vec2d>(k);
  src_f_ = arena.allocate<Vec2d>(k);
  dst_f_ = arena.allocate<Vec2d>(k);
  mask_ = arena.allocate<std::uint8_t>(k);
  mask2_ = arena.allocate<std::uint8_t>(k);
  scratch_ = arena.allocate<double>(k);
  if (cs.empty() || acs.empty() || grid_.empty() || da.empty() || db.empty() || ms.empty() || predicted_.empty() ||
      src_.empty() || dst_.empty() || src_f_.empty() || dst_f_.empty() || mask_.empty() || mask2_.empty() || scratch_.empty())
    return Status(StatusCode::kCapacityExceeded, "homography chain: arena too small");
  corners_ = BoundedVector<vision::Corner>(cs);
  all_corners_ = BoundedVector<vision::Corner>(acs);
  desc_a_ = BoundedVector<vision::OrientedDescriptor>(da);
  desc_b_ = BoundedVector<vision::OrientedDescriptor>(db);
  key_ = &desc_a_;
  cur_ = &desc_b_;
  last_ = cur_;
  matches_ = BoundedVector<match::DescriptorMatch>(ms);
  ready_ = true;
  reset();
  return Status::ok();
}

void HomographyChain::reset() noexcept {
  have_reference_ = false;
  have_prediction_ = false;
  frame_count_ = 0;
  key_frame_index_ = 0;
  keyframes_ = 0;
  key_w_ = key_h_ = 0;
  H_0_key_ = Mat3d::Identity();
  H_key_last_ = Mat3d::Identity();
  pose_ = ChainPose{};
  mpp_sum_ = 0.0;
  mpp_count_ = 0;
  key_->clear();
  cur_->clear();
}

std::uint8_t HomographyChain::check_frame(ConstImageViewU8 f) const noexcept {
  std::uint64_t n = 0, sum = 0, sumsq = 0, bright = 0;
  for (int y = 1; y < f.height(); y += 2) {
    const std::uint8_t* row = f.row(y);
    for (int x = 1; x < f.width(); x += 2) {
      const std::uint32_t v = row[x];
      sum += v;
      sumsq += v * v;
      bright += v >= 250 ? 1u : 0u;
      ++n;
    }
  }
  if (n == 0) return kFrameSize;
  const double mean = static_cast<double>(sum) / static_cast<double>(n);
  const double var = static_cast<double>(sumsq) / static_cast<double>(n) - mean * mean;
  std::uint8_t bits = 0;
  if (mean < config_.dark_mean) bits |= kFrameDark;
  if (static_cast<double>(bright) > config_.saturated_fraction * static_cast<double>(n)) bits |= kFrameSaturated;
  if (std::sqrt(std::max(var, 0.0)) < config_.min_stddev) bits |= kFrameTextureless;
  return bits;
}

Status HomographyChain::extract(ConstImageViewU8 frame, BoundedVector<vision::OrientedDescriptor>& out) noexcept {
  out.clear();
  all_corners_.clear();
  for (vision::GradientPlanes& p : planes_) p = vision::GradientPlanes{};
  QNAV_RETURN_IF_ERROR(pyramid_.build(frame));
  const int levels = std::min(pyramid_.levels_built(), config_.pyramid_levels);
  for (int l = 0; l < levels; ++l) {
    const ConstImageViewU8 img = pyramid_.level(l);
    if (img.width() <= 2 * harris_.config().border_px + 2 || img.height() <= 2 * harris_.config().border_px + 2) break;
    const Status s = harris_.detect(img, corners_);
    if (!s) continue;  // e.g. a level too small: the other levels still count
    if (!corners_.empty() &&
        !vision::compute_gradient_planes(img, grad_mag_[l], grad_ang_[l], planes_[l]).is_ok())
      continue;  // planes sized for max_width x max_height: only a frame that lies gets here
    const float sc = vision::ImagePyramid::scale(l);
    for (const vision::Corner& c : corners_) {
      vision::Corner c0 = c;
      c0.x = (c.x + 0.5f) * sc - 0.5f;
      c0.y = (c.y + 0.5f) * sc - 0.5f;
      c0.level = static_cast<std::int16_t>(l);
      if (!all_corners_.push_back(c0)) break;
    }
  }
  std::sort(all_corners_.begin(), all_corners_.end(), corner_before);

  for (std::int32_t& g : grid_) g = -1;
  const float border = static_cast<float>(config_.border_px);
  const float w = static_cast<float>(frame.width()), h = static_cast<float>(frame.height());
  const float sep2 = config_.min_separation_px * config_.min_separation_px;
  for (std::size_t i = 0; i < all_corners_.size() && !out.full(); ++i) {
    const vision::Corner& c = all_corners_[i];
    if (!(c.x >= border && c.y >= border && c.x < w - 1.0f - border && c.y < h - 1.0f - border)) continue;
    const int gx = static_cast<int>(c.x / cell_px_), gy = static_cast<int>(c.y / cell_px_);
    if (gx < 0 || gy < 0 || gx >= grid_w_ || gy >= grid_h_) continue;
    bool close = false;
    for (int yy = std::max(gy - 2, 0); yy <= std::min(gy + 2, grid_h_ - 1) && !close; ++yy)
      for (int xx = std::max(gx - 2, 0); xx <= std::min(gx + 2, grid_w_ - 1); ++xx) {
        const std::int32_t j = grid_[static_cast<std::size_t>(yy) * static_cast<std::size_t>(grid_w_) + static_cast<std::size_t>(xx)];
        if (j < 0) continue;
        const float dx = out[static_cast<std::size_t>(j)].x - c.x, dy = out[static_cast<std::size_t>(j)].y - c.y;
        if (dx * dx + dy * dy < sep2) {
          close = true;
          break;
        }
      }
    if (close) continue;
    const int l = c.level;
    const float sc = vision::ImagePyramid::scale(l);
    const float xl = (c.x + 0.5f) / sc - 0.5f, yl = (c.y + 0.5f) / sc - 0.5f;
    vision::OrientedDescriptor* d = out.emplace_back();
    if (d == nullptr) break;
    if (!vision::compute_oriented_descriptor(planes_[l], xl, yl, config_.descriptor_scale, *d)) {
      (void)out.pop_back();
      continue;
    }
    d->x = c.x;
    d->y = c.y;
    d->scale = sc * config_.descriptor_scale;
    grid_[static_cast<std::size_t>(gy) * static_cast<std::size_t>(grid_w_) + static_cast<std::size_t>(gx)] =
        static_cast<std::int32_t>(out.size() - 1);
  }
  return Status::ok();
}

void HomographyChain::update_pose_outputs(ChainPose& p, double altitude_m) noexcept {
  const Vec2d c = principal_point();
  Vec2d mapped;
  Eigen::Matrix2d J;
  if (jacobian_at(p.H_0_cur, c, mapped, J)) {
    p.position_px = mapped;
    p.heading_rad = std::atan2(J(1, 0) - J(0, 1), J(0, 0) + J(1, 1));
    p.scale = std::sqrt(std::abs(J.determinant()));
  }
  if (std::isfinite(altitude_m) && altitude_m > 0.0 && config_.camera.fx > 0.0 && p.scale > 0.0) {
    mpp_sum_ += altitude_m / (config_.camera.fx * p.scale);
    ++mpp_count_;
  }
  p.metric = mpp_count_ > 0;
  p.position_m = p.metric ? Vec2d((p.position_px - c) * metres_per_px()) : Vec2d::Zero();
}

Vec2d HomographyChain::principal_point() const noexcept {
  const double cx = config_.camera.cx >= 0.0 ? config_.camera.cx : 0.5 * (key_w_ - 1);
  const double cy = config_.camera.cy >= 0.0 ? config_.camera.cy : 0.5 * (key_h_ - 1);
  return Vec2d(cx, cy);
}

double HomographyChain::overlap_of(const Mat3d& H_key_cur, int w, int h) const noexcept {
  // Keyframe grid points that fall inside the current frame (mapped by H_cur_key = H_key_cur^-1).
  const Mat3d H_cur_key = H_key_cur.inverse();
  constexpr int kN = 16;
  int inside = 0;
  for (int j = 0; j < kN; ++j)
    for (int i = 0; i < kN; ++i) {
      const Vec2d p((i + 0.5) * key_w_ / kN, (j + 0.5) * key_h_ / kN);
      Vec2d q;
      if (motion::apply_homography(H_cur_key, p, q) && q.x() >= 0.0 && q.y() >= 0.0 && q.x() < w && q.y() < h) ++inside;
    }
  return static_cast<double>(inside) / (kN * kN);
}

Status HomographyChain::process(ConstImageViewU8 frame, double altitude_m, ChainStep& step) noexcept {
  step = ChainStep{};
  step.pose = pose_;
  last_matches_ = 0;
  if (!ready_) return Status(StatusCode::kNotReady, "homography chain: process before init");
  step.frame_index = frame_count_++;
  step.keyframe_index = key_frame_index_;
  if (frame.empty() || frame.width() > config_.max_width || frame.height() > config_.max_height ||
      frame.width() < 32 || frame.height() < 32 ||
      (have_reference_ && (frame.width() != key_w_ || frame.height() != key_h_))) {
    step.status = StepStatus::kBadInput;
    step.bad_input = kFrameSize;
    return Status::ok();
  }
  step.bad_input = check_frame(frame);
  if (step.bad_input != 0) {
    step.status = StepStatus::kBadInput;
    return Status::ok();
  }
  last_ = cur_;
  if (!extract(frame, *cur_)) {
    step.status = StepStatus::kBadInput;
    step.bad_input = kFrameSize;
    return Status::ok();
  }
  step.keypoints = static_cast<std::uint32_t>(cur_->size());
  if (cur_->size() < config_.min_keypoints) {
    step.status = StepStatus::kFewKeypoints;
    return Status::ok();
  }
  if (!have_reference_) {
    take_reference(frame, altitude_m, step);
    return Status::ok();
  }
  Mat3d H;
  if (!match_to_keyframe(step) || !fit_to_keyframe(step, H) || !plausible(H, frame, step)) return Status::ok();
  chain_pose(H, altitude_m, step);
  return Status::ok();
}

void HomographyChain::take_reference(ConstImageViewU8 frame, double altitude_m, ChainStep& step) noexcept {
  std::swap(key_, cur_);
  last_ = key_;
  key_w_ = frame.width();
  key_h_ = frame.height();
  have_reference_ = true;
  key_frame_index_ = step.frame_index;
  keyframes_ = 1;
  H_0_key_ = Mat3d::Identity();
  H_key_last_ = Mat3d::Identity();
  have_prediction_ = true;
  pose_ = ChainPose{};
  update_pose_outputs(pose_, altitude_m);
  step.reference = true;
  step.new_keyframe = true;
  step.keyframe_index = step.frame_index;
  step.overlap = 1.0;
  step.pose = pose_;
}

bool HomographyChain::match_to_keyframe(ChainStep& step) noexcept {
  // Ratio-test matching: query = current frame, train = keyframe.
  const Span<const vision::OrientedDescriptor> query(cur_->data(), cur_->size());
  const Span<const vision::OrientedDescriptor> train(key_->data(), key_->size());
  bool matched = false;
  if (have_prediction_) {
    for (std::size_t i = 0; i < cur_->size(); ++i) {
      Vec2d q;
      const Vec2d p((*cur_)[i].x, (*cur_)[i].y);
      predicted_[i] = motion::apply_homography(H_key_last_, p, q) ? q : Vec2d(std::nan(""), std::nan(""));
    }
    const Status s = matcher_.match_predicted(query, Span<const Vec2d>(predicted_.data(), cur_->size()), train, matches_);
    matched = (s.is_ok() || s == StatusCode::kCapacityExceeded) && matches_.size() >= config_.min_matches;
    step.predicted = matched;
  }
  if (!matched) {
    const Status s = matcher_.match(query, train, matches_);
    (void)s;  // a full output keeps what fitted; too few is judged below
  }
  step.matches = static_cast<std::uint32_t>(matches_.size());
  if (matches_.size() < config_.min_matches) {
    step.status = StepStatus::kFewMatches;
    return false;
  }
  const std::size_t n = matches_.size();
  for (std::size_t i = 0; i < n; ++i) {
    const vision::OrientedDescriptor& q = (*cur_)[matches_[i].query];
    const vision::OrientedDescriptor& t = (*key_)[matches_[i].train];
    src_[i] = Vec2d(q.x, q.y);
    dst_[i] = Vec2d(t.x, t.y);
  }
  last_matches_ = n;
  return true;
}

bool HomographyChain::fit_to_keyframe(ChainStep& step, Mat3d& H) noexcept {
  const std::size_t n = last_matches_;
  Span<const Vec2d> src(src_.data(), n), dst(dst_.data(), n);
  if (config_.fundamental_filter) {
    Result<match::FundamentalConsensus> f = match::robust_fundamental_both(
        src, dst, config_.fundamental_ransac, config_.fundamental_lmeds, Span<std::uint8_t>(mask_.data(), n),
        Span<std::uint8_t>(mask2_.data(), n), Span<double>(scratch_.data(), n));
    if (f.is_ok() && f->inliers >= config_.min_inliers) {
      std::size_t m = 0;
      for (std::size_t i = 0; i < n; ++i)
        if (mask_[i] != 0) {
          src_f_[m] = src_[i];
          dst_f_[m] = dst_[i];
          ++m;
        }
      step.fundamental_inliers = static_cast<std::uint32_t>(m);
      src = Span<const Vec2d>(src_f_.data(), m);
      dst = Span<const Vec2d>(dst_f_.data(), m);
    }
  }
  Result<match::RobustHomography> rh = match::robust_homography(src, dst, config_.homography,
                                                                Span<std::uint8_t>(mask_.data(), src.size()),
                                                                Span<double>(scratch_.data(), src.size()));
  if (!rh.is_ok()) {
    step.status = rh.status() == StatusCode::kNotFound ? StepStatus::kFewMatches : StepStatus::kDegenerate;
    return false;
  }
  step.inliers = rh->inliers;
  step.rms_px = rh->fit.rms_transfer_px;
  if (rh->inliers < config_.min_inliers) {
    step.status = StepStatus::kFewMatches;
    return false;
  }
  H = rh->fit.H;
  if (!H.allFinite() || !(std::abs(H(2, 2)) > 1e-12)) {
    step.status = StepStatus::kDegenerate;
    return false;
  }
  H /= H(2, 2);
  step.H_key_cur = H;
  return true;
}

bool HomographyChain::plausible(const Mat3d& H, ConstImageViewU8 frame, ChainStep& step) const noexcept {
  // Plausibility: scale and orientation of the affine part at the principal point, perspective terms
  // with the image half-width as unit.
  const Vec2d c = principal_point();
  Vec2d mapped;
  Eigen::Matrix2d J;
  const double half = 0.5 * std::max(key_w_, key_h_);
  Mat3d N = Mat3d::Identity();
  N(0, 0) = N(1, 1) = 1.0 / half;
  N(0, 2) = -c.x() / half;
  N(1, 2) = -c.y() / half;
  Mat3d Hn = N * H * N.inverse();
  if (std::abs(Hn(2, 2)) > 1e-12) Hn /= Hn(2, 2);
  if (!jacobian_at(H, c, mapped, J) || !(J.determinant() > 0.0) ||
      !(std::sqrt(J.determinant()) >= config_.min_scale && std::sqrt(J.determinant()) <= config_.max_scale) ||
      !(std::abs(Hn(2, 0)) <= config_.max_perspective && std::abs(Hn(2, 1)) <= config_.max_perspective)) {
    step.status = StepStatus::kDegenerate;
    return false;
  }
  step.overlap = overlap_of(H, frame.width(), frame.height());
  if (step.overlap <= 0.0) {
    step.status = StepStatus::kDegenerate;
    return false;
  }
  return true;
}

void HomographyChain::chain_pose(const Mat3d& H, double altitude_m, ChainStep& step) noexcept {
  // Eq. 2: H_0<-cur = H_0<-key H_key<-cur.
  Mat3d H0 = H_0_key_ * H;
  if (!H0.allFinite() || !(std::abs(H0(2, 2)) > 1e-12)) {
    step.status = StepStatus::kDegenerate;
    return;
  }
  H0 /= H0(2, 2);
  pose_.H_0_cur = H0;
  update_pose_outputs(pose_, altitude_m);
  H_key_last_ = H;
  have_prediction_ = true;

  if (step.overlap < config_.min_overlap || step.inliers < config_.keyframe_min_inliers ||
      step.frame_index - key_frame_index_ >= config_.max_keyframe_gap) {
    std::swap(key_, cur_);
    last_ = key_;
    H_0_key_ = H0;
    H_key_last_ = Mat3d::Identity();
    key_frame_index_ = step.frame_index;
    ++keyframes_;
    step.new_keyframe = true;
  }
  step.pose = pose_;
}

}  // namespace qnav::topo
