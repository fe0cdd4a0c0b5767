// SimClosedLoop: the sim vehicle's autopilot in a closed-loop pass (sim.pass.closed_loop, a simulated
// repeat; part of SimVehicle, sim_vehicle.hpp; driven by the io thread only). While qnavd teaches, the
// autopilot logs its own dead reckoning (every kLogStepM); when the repeat starts it reads the taught
// route's node poses (the route file: the numbers NAV_STATUS.NodeIndex points at) into its taught
// track, then steers with pipeline::RouteAutopilot on the QNAV_ROUTE_GUIDANCE / STATUS frames it hears
// on the bus (on_frame), flying pipeline::ClosedLoopVehicle (dynamics, current, drifting compass and
// DVL: pipeline::follow_scenario for sim.seed, as `qnav route follow --sim`). Each ping is rendered
// from the TRUE pose; the AHRS and DVL report its dead reckoning. A twin flies the same start, drift
// and current on dead reckoning alone (no pings). At the pass's end: one `sim_closed_loop` line (truth
// cross-track of both) on the io log and stderr; sim.closed_loop_csv the tracks.
// Owns: the teach log, the taught track, the vehicles and autopilots, the CSV file. Memory: the teach
// log is reserved at init (length / 10 m + margin); the track, the node poses and the per-ping records
// are allocated when a closed-loop pass starts. Time: one vehicle and one twin step per ping.
#pragma once

#include <cstdio>
#include <vector>

#include "drivers/sidescan/sim_trajectory.hpp"
#include "firmware/pipeline/closed_loop.hpp"
#include "firmware/pipeline/closed_loop_vehicle.hpp"
#include "firmware/pipeline/route_autopilot.hpp"
#include "firmware/pipeline/sim_survey.hpp"
#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/sim_sensors.hpp"
#include "hal/sim/fault_file_store.hpp"
#include "nav/route/route_types.hpp"

namespace qnav::daemon {

class SimClosedLoop {
 public:
  static constexpr double kLogStepM = 10.0;  // the autopilot logs its pose every 10 m of the teach
  static constexpr int kCsvEvery = 25;       // a CSV row every 25 pings (5 s)

  SimClosedLoop(const DaemonConfig& config, const SimClock& clock) noexcept : cfg_(config), clock_(clock) {}
  ~SimClosedLoop();
  SimClosedLoop(const SimClosedLoop&) = delete;
  SimClosedLoop& operator=(const SimClosedLoop&) = delete;
  // Reserves the teach log and opens sim.closed_loop_csv (a bad path is a start-up error).
  Status init();
  // The io thread's log (the passes' summary lines); null = stderr only.
  void set_log(std::FILE* log) noexcept { log_ = log; }
  // A pass starts; teach_logging: it is a simulated teach pass, whose pings the autopilot logs.
  void begin_pass(bool teach_logging) noexcept;
  void log_teach_pose(const Pose2& nav) noexcept;
  // The closed-loop pass `pass` starts now (its pings' seed pass_seed), on the taught route in store.
  Status start(std::uint32_t pass, std::uint64_t pass_seed, const pipeline::SimSurvey& survey, hal::FaultFileStore* store);
  bool active() const noexcept { return c_.active; }
  // A frame on the bus: the autopilot steers on the guidance it hears (bad frames are counted by it).
  void on_frame(const hal::CanFrame& f) noexcept { c_.ap.on_frame(f, clock_.now_ns()).ignore(); }
  // The next ping instant (the dead reckoning the sensors report, the truth) and the pose the sonar
  // renders it from; false (after the summary) when the vehicle has stopped.
  bool next(SimSample& out, sidescan::TrajectorySample& render, double altitude_m, std::int64_t pass_start_ns) noexcept;

 private:
  void finish(std::int64_t pass_start_ns) noexcept;
  struct Pass {
    // The teach log (daemon's teach frame: the pass's dead reckoning from its first ping).
    bool logging = false, have_log = false;
    Pose2 nav0{}, prev{}, last{};
    double dist_m = 0.0, since_m = 0.0;
    std::vector<Pose2> log;
    std::vector<double> log_dist_m;
    // The pass.
    bool active = false, twin_done = false;
    std::vector<route::NodeMeta> meta;
    std::vector<Pose2> track;
    std::vector<std::uint32_t> node_at;
    std::vector<Vec2d> truth_poly;
    double length_m = 0.0, dt_s = 0.2, max_travel_m = 0.0, swath_m = 0.0, spacing_m = 0.0;
    bool reverse = false;
    pipeline::ClosedLoopVehicle veh, twin;
    pipeline::RouteAutopilot ap, twin_ap;
    std::uint32_t index = 0;
    std::vector<double> xt_qnav, xt_dr;        // |truth cross-track| per ping
    std::vector<double> flown_qnav, flown_dr;  // true distance flown per ping
    double along_m = 0.0, twin_along_m = 0.0;
    std::FILE* csv = nullptr;
    std::uint64_t seed = 0;
    std::uint32_t pass = 0;
  };
  const DaemonConfig& cfg_;
  const SimClock& clock_;
  std::FILE* log_ = nullptr;
  Pass c_;
};

}  // namespace qnav::daemon
