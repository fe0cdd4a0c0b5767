// SimPacer: paces the sim backend's mission against a wall clock (sim.speed, issue #31). Mission time
// t is due at the ABSOLUTE wall time start_wall + (t - start_mission) / speed, computed from the
// mission's first step every time (never from the previous wake-up), so a long mission does not drift.
// A step that goes more than kLateToleranceNs after its deadline is late: counted (late_steps,
// max_late_ns), never skipped; it still goes, with its own mission time (the message times).
// speed 0: every step is due at once (as fast as the pipeline takes it).
// Pacing only waits: the caller's lockstep with the daemon decides first whether a step may go, then
// due() whether it is time; the mission's times and the daemon's answers do not depend on the speed.
// O(1), no heap, no allocation. Driven by one thread (the io thread); the counters are relaxed
// atomics other threads may read.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>

#include "firmware/qnavd/messages.hpp"
#include "hal/core/clock.hpp"

namespace qnav::daemon {

// Mission time for the sim backend (set by the I/O thread, read by every thread).
class SimClock final : public hal::Clock {
 public:
  std::int64_t now_ns() const noexcept override { return t_ns_.load(std::memory_order_acquire); }
  void set(std::int64_t t) noexcept { t_ns_.store(t, std::memory_order_release); }

 private:
  std::atomic<std::int64_t> t_ns_{1000000000};
};

class SimPacer {
 public:
  static constexpr std::int64_t kLateToleranceNs = 10000000;  // 10 ms of wall time
  // Between two steps the io thread wakes at least this often (wall) to carry the daemon's frames
  // to the vehicle and to let mission time follow the wall (SimVehicle).
  static constexpr std::int64_t kPollSliceNs = 2000000;

  SimPacer(hal::Clock& wall, double speed) noexcept : wall_(wall), speed_(speed > 0.0 ? speed : 0.0) {}
  bool paced() const noexcept { return speed_ > 0.0; }
  double speed() const noexcept { return speed_; }
  bool started() const noexcept { return started_; }
  // Anchors the pace: mission time mission_ns is now. Called once, at the mission's first step.
  void start(std::int64_t mission_ns) noexcept {
    wall_start_ns_ = wall_.now_ns();
    mission_start_ns_ = mission_ns;
    started_ = true;
  }
  // Wall time at which mission time t is due.
  std::int64_t deadline_ns(std::int64_t mission_ns) const noexcept {
    return wall_start_ns_ + static_cast<std::int64_t>(static_cast<double>(mission_ns - mission_start_ns_) / speed_);
  }
  // The mission time the wall clock stands at now (paced only).
  std::int64_t mission_now_ns() const noexcept {
    return mission_start_ns_ + static_cast<std::int64_t>(static_cast<double>(wall_.now_ns() - wall_start_ns_) * speed_);
  }
  // True when the step at mission time t may go now, and then counts it (steps, late ones). False:
  // not yet; its deadline is kept for sleep().
  bool due(std::int64_t mission_ns) noexcept {
    if (!paced()) {
      steps_.fetch_add(1, std::memory_order_relaxed);
      return true;
    }
    const std::int64_t deadline = deadline_ns(mission_ns);
    const std::int64_t now = wall_.now_ns();
    if (now < deadline) {
      pending_deadline_ns_ = deadline;
      return false;
    }
    pending_deadline_ns_ = -1;
    steps_.fetch_add(1, std::memory_order_relaxed);
    const std::int64_t late = now - deadline;
    if (late > kLateToleranceNs) late_steps_.fetch_add(1, std::memory_order_relaxed);
    if (late > max_late_ns_.load(std::memory_order_relaxed)) max_late_ns_.store(late, std::memory_order_relaxed);
    return true;
  }
  // The sim vehicle's step at mission time t on `clock`: true when it goes now (and then io's
  // sim_late_steps / sim_max_late_us are updated, io may be null). While it waits and `follow` is set
  // (a pass's next sample), mission time follows the wall up to just before t, in steps of the poll
  // slice, so the daemon's periodic outputs (NAV_STATUS every 100 ms) keep their periods in wall time
  // too; the samples' own times do not change. Between passes (follow = false) the clock moves only
  // by the handshake's ticks, whose mission-time lengths the lockstep fixes.
  bool pace(SimClock& clock, std::int64_t t, bool follow, IoCounters* io) noexcept {
    if (due(t)) {
      if (io != nullptr) {
        io->sim_late_steps.store(late_steps(), std::memory_order_relaxed);
        io->sim_max_late_us.store(static_cast<std::uint32_t>(std::min<std::int64_t>(max_late_ns() / 1000, UINT32_MAX)),
                                  std::memory_order_relaxed);
      }
      return true;
    }
    if (follow) {
      const std::int64_t step_ns = static_cast<std::int64_t>(static_cast<double>(kPollSliceNs) * speed());
      const std::int64_t m = std::min(mission_now_ns(), t - 1);
      if (m >= clock.now_ns() + step_ns) clock.set(m);
    }
    return false;
  }
  // A step is waiting for its deadline (the last due() said not yet).
  bool waiting() const noexcept { return pending_deadline_ns_ >= 0; }
  // Sleeps to that step's deadline, at most to now + max_ns (an absolute wake-up either way), so the
  // caller still polls its buses that often. False, without sleeping, when no step waits for a
  // deadline still ahead (the caller is waiting for something else: the lockstep).
  bool sleep(std::int64_t max_ns) noexcept {
    if (!waiting()) return false;
    const std::int64_t now = wall_.now_ns();
    if (pending_deadline_ns_ <= now) {
      pending_deadline_ns_ = -1;
      return false;
    }
    wall_.sleep_until_ns(std::min(pending_deadline_ns_, now + max_ns));
    return true;
  }

  std::uint64_t steps() const noexcept { return steps_.load(std::memory_order_relaxed); }
  std::uint32_t late_steps() const noexcept { return late_steps_.load(std::memory_order_relaxed); }
  std::int64_t max_late_ns() const noexcept { return max_late_ns_.load(std::memory_order_relaxed); }
  std::int64_t wall_elapsed_ns() const noexcept { return started_ ? wall_.now_ns() - wall_start_ns_ : 0; }
  std::int64_t mission_start_ns() const noexcept { return mission_start_ns_; }

 private:
  hal::Clock& wall_;
  double speed_;
  bool started_ = false;
  std::int64_t wall_start_ns_ = 0, mission_start_ns_ = 0;
  std::int64_t pending_deadline_ns_ = -1;
  std::atomic<std::uint64_t> steps_{0};
  std::atomic<std::uint32_t> late_steps_{0};
  std::atomic<std::int64_t> max_late_ns_{0};
};

}  // namespace qnav::daemon
