// NavHealth: the nav thread's outputs and health (F Prime's health and telemetry components).
// Consumes: every loop, the state of the other components (connect(): read-only references, the
//   topology's wiring) and the io thread's counters; stage timings from the worker (stage_time()).
// Produces: the fault bits (update(): sensor loss only where the sensor is used, bus-off, deadline
//   misses, software faults, leak, route damaged), QNAV_NAV_STATUS, QNAV_HEALTH, QNAV_HEARTBEAT on the
//   publisher (values in the DBC ranges), and the health log line every daemon.health_period_s.
// Memory: fixed members, no heap. Time: O(1) per loop (a few frames set, one log line per period).
#pragma once

#include <cstdint>

#include "drivers/qnavcan/publisher.hpp"
#include "firmware/pipeline/route_tile_pipeline.hpp"
#include "firmware/qnavd/components/component.hpp"
#include "firmware/qnavd/components/map_component.hpp"
#include "firmware/qnavd/components/nav_inputs.hpp"
#include "firmware/qnavd/components/nav_source.hpp"
#include "firmware/qnavd/components/route_repeat.hpp"
#include "firmware/qnavd/components/route_teach.hpp"
#include "firmware/qnavd/components/vo_component.hpp"
#include "firmware/qnavd/deployment.hpp"
#include "firmware/qnavd/messages.hpp"

namespace qnav::daemon {

// The worker's own counts (what it took off the queues and how it dispatched them).
struct NavCounters {
  std::uint32_t pings = 0, tiles = 0, pings_out_of_order = 0;
  std::uint32_t frames = 0, frames_out_of_order = 0;
  std::uint32_t mode_refused = 0, teach_no_odometry = 0, nav_resets = 0;
};

// The worker's mode state as the outputs report it.
struct NavModeState {
  drivers::qnavcan::Mode mode = drivers::qnavcan::Mode::kIdle;
  ModeReject last_reject = ModeReject::kNone;
  std::int64_t last_ping_ns = -1;
  route::LocaliserStep step;  // the last repeat tile's filter step (cleared when a repeat is left)
};

// The topology's connections NavHealth reads.
struct NavParts {
  const NavInputs* inputs = nullptr;
  const RouteTeach* teach = nullptr;
  const RouteRepeat* repeat = nullptr;
  const VoComponent* vo = nullptr;
  const MapComponent* map = nullptr;
  const NavSource* source = nullptr;
  const pipeline::RouteTilePipeline* tiles = nullptr;
  const IoCounters* io = nullptr;
  const NavCounters* counters = nullptr;
  const NavModeState* state = nullptr;
};

class NavHealth {
 public:
  explicit NavHealth(const NavContext& ctx) noexcept : ctx_(ctx) {}
  void init(const NavParts& parts, drivers::qnavcan::QnavCanPublisher& publisher, std::int64_t cpu_now_ns) noexcept;

  // A stage ran from t0_ns to now (cpu clock): its maximum, its budget misses, the busy time.
  void stage_time(Stage s, std::int64_t t0_ns, std::int64_t now_ns) noexcept;
  void start_window(std::int64_t cpu_now_ns) noexcept { busy_ns_ = 0, busy_window_start_ns_ = cpu_now_ns; }
  // The fault bits at the nav clock's now; raises what each loss means for the repeat's guidance.
  std::uint16_t update(RouteRepeat& repeat) noexcept;
  void publish() noexcept;
  // The health log line (and the MAVLink counters, a software fault's record); the CPU load window.
  void log(std::int64_t cpu_now_ns) noexcept;

  std::uint16_t faults() const noexcept { return faults_; }
  std::uint32_t deadline_misses() const noexcept { return deadline_misses_; }
  // Pings the tile pipeline's corrector refused as damaged (range, samples, altitude).
  std::uint32_t pings_rejected() const noexcept;

 private:
  const NavContext& ctx_;  // the worker's: its log is set in NavWorker::init
  NavParts p_{};
  drivers::qnavcan::QnavCanPublisher* publisher_ = nullptr;
  std::uint16_t faults_ = 0;
  bool leak_logged_ = false;  // the `leak` event is logged once, when the detector latches
  std::uint32_t deadline_misses_ = 0, software_faults_logged_ = 0;
  std::uint32_t stage_misses_[static_cast<int>(Stage::kCount)] = {};
  std::int64_t stage_max_ns_[static_cast<int>(Stage::kCount)] = {};
  std::uint32_t budgets_us_[static_cast<int>(Stage::kCount)] = {};
  std::int64_t busy_ns_ = 0, busy_window_start_ns_ = 0;
  double cpu_load_pct_ = 0.0;
};

}  // namespace qnav::daemon
