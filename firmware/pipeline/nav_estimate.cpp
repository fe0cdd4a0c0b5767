#include "firmware/pipeline/nav_estimate.hpp"

#include <algorithm>
#include <cmath>

namespace qnav::pipeline {

void NavEstimate::reset() noexcept {
  n_m_ = e_m_ = 0.0;
  have_base_ = false;
  ++reset_counter_;
}

void NavEstimate::track(const Pose2& dr) noexcept {
  if (!std::isfinite(dr.x_m) || !std::isfinite(dr.y_m)) return;
  if (have_base_) {
    n_m_ += dr.x_m - base_.x_m;
    e_m_ += dr.y_m - base_.y_m;
  }
  base_ = dr;
  have_base_ = true;
}

void NavEstimate::add_increment(double dn_m, double de_m, double dd_m) noexcept {
  if (!std::isfinite(dn_m) || !std::isfinite(de_m) || !std::isfinite(dd_m)) return;
  n_m_ += dn_m;
  e_m_ += de_m;
  down_m_ += dd_m;
}

bool NavEstimate::apply_fix(double north_m, double east_m) noexcept {
  if (!std::isfinite(north_m) || !std::isfinite(east_m)) {
    ++rejected_fixes_;
    return false;
  }
  ++fixes_;
  last_jump_m_ = std::hypot(north_m - n_m_, east_m - e_m_);
  max_jump_m_ = std::max(max_jump_m_, last_jump_m_);
  const bool moved = last_jump_m_ > jump_threshold_m_;
  n_m_ = north_m;
  e_m_ = east_m;
  if (moved) {
    ++reset_counter_;
    ++jumps_;
  }
  return moved;
}

Vec2d NavEstimate::route_fix_position(const route::NodeMeta& node, bool reverse, double along_m, double cross_m) noexcept {
  const double h = node.pose.heading_rad + (reverse ? 3.14159265358979323846 : 0.0);
  const double c = std::cos(h), s = std::sin(h);
  // direction of travel (c, s) in (north, east); its starboard (-s, c)
  return Vec2d(node.pose.x_m + along_m * c - cross_m * s, node.pose.y_m + along_m * s + cross_m * c);
}

}  // namespace qnav::pipeline
