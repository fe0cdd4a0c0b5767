// The state of qnavd's closed-loop sim passes (sim.pass.closed_loop; SimVehicle, sim_vehicle.hpp):
// the taught track the vehicle's autopilot logs while qnavd teaches, and, in the pass, the vehicle,
// its RouteAutopilot on qnavd's frames, and the twin flown on dead reckoning alone. The law, the
// vehicle and the drift are firmware/pipeline's (closed_loop.hpp, route_autopilot.hpp), the ones
// `qnav route follow --sim` flies.
// Memory: the teach log reserved at SimVehicle::init (length / 10 m + margin); the track, the node
// poses and the per-ping cross-track records are allocated when a closed-loop pass starts.
#pragma once

#include <cstdio>
#include <vector>

#include "firmware/pipeline/closed_loop.hpp"
#include "firmware/pipeline/closed_loop_vehicle.hpp"
#include "firmware/pipeline/route_autopilot.hpp"
#include "nav/route/route_types.hpp"

namespace qnav::daemon {

struct SimVehicle::ClosedLoopPass {
  static constexpr double kLogStepM = 10.0;  // the autopilot logs its pose every 10 m of the teach
  static constexpr int kCsvEvery = 25;       // a CSV row every 25 pings (5 s)
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
  std::vector<double> xt_qnav, xt_dr;          // |truth cross-track| per ping
  std::vector<double> flown_qnav, flown_dr;    // true distance flown per ping
  double along_m = 0.0, twin_along_m = 0.0;
  std::FILE* csv = nullptr;
  std::uint64_t seed = 0;
  std::uint32_t pass = 0;
  ~ClosedLoopPass() {
    if (csv) std::fclose(csv);
  }
};

}  // namespace qnav::daemon
