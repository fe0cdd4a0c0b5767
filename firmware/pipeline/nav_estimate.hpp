// NavEstimate: the one position estimate qnavd publishes over MAVLink (ODOMETRY, VISION_POSITION_DELTA,
// the GUIDED targets), in a north-aligned local frame (x north, y east, z down, metres).
//  Consumes: relative motion (dead reckoning: DVL body velocity x attitude heading, as
//    pipeline::DeadReckoner integrates it; or visual odometry increments in Mode = Vo) through
//    track() / add_increment(); absolute fixes through apply_fix(): in Repeat a route fix (the taught
//    node's position in the route's own frame plus the registered along- and cross-track offsets,
//    route_fix_position()).
//  Produces: the position (north_m, east_m, down_m), the fix count, and reset_counter, which changes
//    whenever a fix moves the position by more than jump_threshold_m.
//  How a fix is applied: as a JUMP, with reset_counter incremented, never blended. Why: ArduPilot
//    and PX4 treat a reset_counter change as "the external frame moved": they re-anchor their own
//    position to the new one at once and keep fusing velocity untouched. A blend would instead
//    present the correction as motion: a 5 m fix spread over 2 s reads as 2.5 m/s the vehicle never
//    had, which the EKF fuses against the DVL velocity (innovation spikes, a kick in position hold).
//    The jump also makes the published frame exactly the taught route's own frame after the first
//    route fix, so the GUIDED targets (the route's look-ahead waypoint, route frame) and ODOMETRY agree.
//  Memory: a few doubles, no heap. Time: O(1) per call. Pure (no OS, no I/O).
#pragma once

#include <cstdint>

#include "nav/core/geometry.hpp"
#include "nav/route/route_types.hpp"

namespace qnav::pipeline {

class NavEstimate {
 public:
  explicit NavEstimate(double jump_threshold_m = 0.05) noexcept : jump_threshold_m_(jump_threshold_m) {}

  // A new origin (the autopilot reset the navigation): position zero, the tracked source rebased,
  // reset_counter incremented.
  void reset() noexcept;
  // The dead-reckoned pose (north x_m, east y_m) of the relative source now: the estimate moves by its
  // change since the previous call. The first call after rebase() only sets the baseline.
  void track(const Pose2& dr) noexcept;
  // The tracked source restarted (DeadReckoner::reset, a switch between dead reckoning and VO): the
  // next track() sets a baseline, the estimate does not move.
  void rebase() noexcept { have_base_ = false; }
  // A relative move (north, east, down metres), e.g. a visual odometry increment.
  void add_increment(double dn_m, double de_m, double dd_m) noexcept;
  // The vehicle's depth (down, metres) from the depth sensor or the DVL: absolute, not a fix.
  void set_down(double down_m) noexcept { down_m_ = down_m; }
  // An absolute fix (north, east metres in the published frame). Returns true when it moved the
  // position by more than jump_threshold_m (reset_counter then changed). Non-finite: refused (false,
  // counted in rejected_fixes()).
  bool apply_fix(double north_m, double east_m) noexcept;

  // Where a route fix puts the vehicle: the node's pose in the route frame, plus along_m in the
  // direction of travel (the taught heading, reversed for a reverse repeat) and cross_m to its starboard.
  static Vec2d route_fix_position(const route::NodeMeta& node, bool reverse, double along_m, double cross_m) noexcept;

  double north_m() const noexcept { return n_m_; }
  double east_m() const noexcept { return e_m_; }
  double down_m() const noexcept { return down_m_; }
  std::uint8_t reset_counter() const noexcept { return reset_counter_; }
  std::uint32_t fixes() const noexcept { return fixes_; }
  std::uint32_t jumps() const noexcept { return jumps_; }
  std::uint32_t rejected_fixes() const noexcept { return rejected_fixes_; }
  // How far the last fix moved the position (m), and the largest such move.
  double last_jump_m() const noexcept { return last_jump_m_; }
  double max_jump_m() const noexcept { return max_jump_m_; }

 private:
  double jump_threshold_m_;
  double n_m_ = 0.0, e_m_ = 0.0, down_m_ = 0.0;
  Pose2 base_{};
  bool have_base_ = false;
  std::uint8_t reset_counter_ = 0;
  std::uint32_t fixes_ = 0, jumps_ = 0, rejected_fixes_ = 0;
  double last_jump_m_ = 0.0, max_jump_m_ = 0.0;
};

}  // namespace qnav::pipeline
