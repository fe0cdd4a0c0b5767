#include "drivers/sidescan/sim_trajectory.hpp"

#include <cmath>

#include "nav/sonar/sonar_types.hpp"

namespace qnav::sidescan {

Status Trajectory::init(const TrajectoryConfig& c) noexcept {
  if (c.waypoints_ne.size() < 2) return Status(StatusCode::kInvalidArgument, "trajectory needs >= 2 waypoints");
  if (!(c.speed_mps > 0.0 && c.speed_mps < 100.0) || !(c.ping_rate_hz > 0.0 && c.ping_rate_hz < 1000.0))
    return Status(StatusCode::kInvalidArgument, "speed or ping rate out of range");
  if (!(c.altitude_m > 0.0) || !std::isfinite(c.lateral_offset_m) || !(c.start_along_m >= 0.0))
    return Status(StatusCode::kInvalidArgument, "altitude <= 0, bad offset or start");
  cfg_ = c;
  cum_.clear();
  double L = 0.0;
  (void)cum_.push_back(0.0);
  for (std::size_t i = 1; i < c.waypoints_ne.size(); ++i) {
    if (!c.waypoints_ne[i].allFinite()) return Status(StatusCode::kInvalidArgument, "waypoint not finite");
    L += (c.waypoints_ne[i] - c.waypoints_ne[i - 1]).norm();
    (void)cum_.push_back(L);
  }
  if (!(L > 0.0)) return Status(StatusCode::kInvalidArgument, "route has zero length");
  length_m_ = L;
  index_ = 0;
  rng_ = c.seed * 0x9E3779B97F4A7C15ULL + 0x632BE59BD9B4E019ULL;
  if (rng_ == 0) rng_ = 1;
  yaw_ = 0.0;
  started_ = false;
  return Status::ok();
}

std::uint32_t Trajectory::pings_total() const noexcept {
  const double travel = length_m_ - cfg_.start_along_m;
  if (travel < 0.0) return 0;
  return static_cast<std::uint32_t>(std::floor(travel / cfg_.speed_mps * cfg_.ping_rate_hz)) + 1;
}

void Trajectory::route_at(double s, Vec2d& p, double& heading_rad) const noexcept {
  const auto& w = cfg_.waypoints_ne;
  std::size_t seg = 0;
  while (seg + 2 < w.size() && s > cum_[seg + 1]) ++seg;
  const double len = cum_[seg + 1] - cum_[seg];
  const Vec2d d = w[seg + 1] - w[seg];
  const double t = len > 0.0 ? (s - cum_[seg]) / len : 0.0;
  p = w[seg] + t * d;
  heading_rad = std::atan2(d.y(), d.x());
}

double Trajectory::gauss() noexcept {
  auto u = [this]() {
    rng_ ^= rng_ << 13;
    rng_ ^= rng_ >> 7;
    rng_ ^= rng_ << 17;
    return (static_cast<double>(rng_ >> 11) + 0.5) * (1.0 / 9007199254740992.0);
  };
  const double u1 = u(), u2 = u();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
}

bool Trajectory::next(TrajectorySample& out) noexcept {
  const double dt = 1.0 / cfg_.ping_rate_hz;
  const double travel = cfg_.start_along_m + index_ * cfg_.speed_mps * dt;
  if (travel > length_m_ + 1e-9 || cum_.size() < 2) return false;
  const double s = cfg_.reverse ? length_m_ - travel : travel;
  Vec2d p;
  double route_heading;
  route_at(s, p, route_heading);
  p += cfg_.lateral_offset_m * sonar::starboard_unit(route_heading);
  if (cfg_.yaw_walk_rad_per_sqrt_s > 0.0 && started_) {
    yaw_ += cfg_.yaw_walk_rad_per_sqrt_s * std::sqrt(dt) * gauss();
    if (yaw_ > cfg_.max_yaw_rad) yaw_ = cfg_.max_yaw_rad;
    if (yaw_ < -cfg_.max_yaw_rad) yaw_ = -cfg_.max_yaw_rad;
  }
  Pose2 truth{p.x(), p.y(), wrap_angle_rad(route_heading + (cfg_.reverse ? kPi : 0.0) + yaw_)};
  const double herr = cfg_.heading_bias_rad + (cfg_.heading_noise_rad > 0.0 ? cfg_.heading_noise_rad * gauss() : 0.0);
  if (!started_) {
    nav_ = truth;
    started_ = true;
  } else {
    const Vec2d d = truth.translation() - prev_truth_.translation();
    const double c = std::cos(herr), sn = std::sin(herr);
    Vec2d dn(c * d.x() - sn * d.y(), sn * d.x() + c * d.y());
    dn *= (1.0 + cfg_.speed_scale_error);
    if (cfg_.speed_noise_mps > 0.0) dn += cfg_.speed_noise_mps * dt * gauss() * sonar::forward_unit(truth.heading_rad + herr);
    nav_.x_m += dn.x();
    nav_.y_m += dn.y();
  }
  nav_.heading_rad = wrap_angle_rad(truth.heading_rad + herr);
  prev_truth_ = truth;
  out.index = index_;
  out.stamp_ns = cfg_.start_stamp_ns + static_cast<std::uint64_t>(std::llround(index_ * dt * 1e9));
  out.truth = truth;
  out.nav = nav_;
  out.along_route_m = s;
  out.altitude_m = static_cast<float>(cfg_.altitude_m);
  ++index_;
  return true;
}

}  // namespace qnav::sidescan
