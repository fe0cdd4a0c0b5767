#include "nav/route/registration.hpp"

#include <cmath>
#include <cstring>

namespace qnav::route {

std::size_t Registrar::arena_bytes(const RegistrationConfig& c) noexcept {
  const std::size_t n = c.fc.max_points;
  return match::FcMatcher2d::arena_bytes(c.fc) + 4 * n * sizeof(Vec2d) + 2 * n * kDescriptorBytes +
         n * sizeof(match::Match2d) + n + n * sizeof(double) + 512;
}

Status Registrar::init(const RegistrationConfig& c, Arena& arena) noexcept {
  if (c.fc.max_points < 2 || c.fc.max_points > kMaxKeypointsPerNode || c.fc.max_descriptor_bytes < kDescriptorBytes || c.min_matches < 2)
    return Status(StatusCode::kInvalidArgument, "registration: bad configuration");
  QNAV_RETURN_IF_ERROR(matcher_.init(c.fc, arena));
  const std::size_t n = c.fc.max_points;
  pos_a_ = arena.allocate<Vec2d>(n);
  pos_b_ = arena.allocate<Vec2d>(n);
  src_ = arena.allocate<Vec2d>(n);
  dst_ = arena.allocate<Vec2d>(n);
  desc_a_ = arena.allocate<std::int8_t>(n * kDescriptorBytes);
  desc_b_ = arena.allocate<std::int8_t>(n * kDescriptorBytes);
  matches_ = arena.allocate<match::Match2d>(n);
  mask_ = arena.allocate<std::uint8_t>(n);
  scratch_ = arena.allocate<double>(n);
  if (pos_a_.empty() || pos_b_.empty() || src_.empty() || dst_.empty() || desc_a_.empty() || desc_b_.empty() ||
      matches_.empty() || mask_.empty() || scratch_.empty())
    return Status(StatusCode::kCapacityExceeded, "registration: arena too small");
  config_ = c;
  ready_ = true;
  return Status::ok();
}

namespace {
std::size_t pack(const RouteNode& node, std::size_t cap, Span<Vec2d> pos, Span<std::int8_t> desc, bool& finite) noexcept {
  const std::size_t n = node.keypoints.size() < cap ? node.keypoints.size() : cap;
  finite = true;
  for (std::size_t i = 0; i < n; ++i) {
    const RouteKeypoint& k = node.keypoints[i];
    if (!std::isfinite(k.x_m) || !std::isfinite(k.y_m)) finite = false;
    pos[i] = Vec2d(k.x_m, k.y_m);
    std::memcpy(desc.data() + i * kDescriptorBytes, k.descriptor, kDescriptorBytes);
  }
  return n;
}
}  // namespace

Status Registrar::register_tile(const RouteNode& sensed, const RouteNode& node, RegistrationResult& out) noexcept {
  out = RegistrationResult{};
  last_n_ = 0;
  if (!ready_) return Status(StatusCode::kNotReady, "registration: not initialised");
  const double dtheta = wrap_angle_rad(sensed.meta.pose.heading_rad - node.meta.pose.heading_rad);
  bool fa = true, fb = true;
  const std::size_t na = pack(sensed, config_.fc.max_points, pos_a_, desc_a_, fa);
  const std::size_t nb = pack(node, config_.fc.max_points, pos_b_, desc_b_, fb);
  if (!fa || !fb || !std::isfinite(dtheta)) {
    counters_.increment(RegistrationCounter::kBadInput);
    return Status(StatusCode::kInvalidArgument, "registration: keypoint or heading not finite");
  }
  match::KeypointSet2d a{Span<const Vec2d>(pos_a_.data(), na), Span<const std::int8_t>(desc_a_.data(), na * kDescriptorBytes), kDescriptorBytes};
  match::KeypointSet2d b{Span<const Vec2d>(pos_b_.data(), nb), Span<const std::int8_t>(desc_b_.data(), nb * kDescriptorBytes), kDescriptorBytes};
  BoundedVector<match::Match2d> m(matches_);
  QNAV_RETURN_IF_ERROR(matcher_.match(a, b, dtheta, m));
  out.matches = static_cast<std::uint32_t>(m.size());
  if (m.size() < config_.min_matches) {
    counters_.increment(RegistrationCounter::kTooFewMatches);
    return Status::ok();
  }
  for (std::size_t i = 0; i < m.size(); ++i) {
    src_[i] = pos_a_[m[i].a];
    dst_[i] = pos_b_[m[i].b];
  }
  last_n_ = m.size();
  Result<match::RobustRigid2d> r = match::robust_rigid2d(Span<const Vec2d>(src_.data(), m.size()), Span<const Vec2d>(dst_.data(), m.size()),
                                                         config_.robust, mask_, scratch_);
  if (!r) {
    counters_.increment(RegistrationCounter::kNoConsensus);
    return Status::ok();
  }
  // The heading is known: a fit whose rotation disagrees with it by far is a chance consensus.
  if (std::abs(wrap_angle_rad(r->fit.pose.heading_rad - dtheta)) > config_.max_heading_disagreement_rad) {
    counters_.increment(RegistrationCounter::kHeadingDisagrees);
    return Status::ok();
  }
  out.ok = true;
  out.inliers = r->inliers;
  out.sensed_to_node = r->fit.pose;
  out.covariance = r->fit.covariance;
  out.rms_m = r->fit.rms_m;
  return Status::ok();
}

}  // namespace qnav::route
