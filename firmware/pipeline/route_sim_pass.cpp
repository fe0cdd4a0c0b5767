// RouteTilePipeline::run_sim_pass: a simulated pass (the side-scan simulator over a seabed) through
// the tile pipeline. In a file of its own so that a program that never flies a simulated pass (the
// flight binary qnavd) does not link the simulator.
#include <memory>

#include "firmware/pipeline/route_tile_pipeline.hpp"

namespace qnav::pipeline {

Status RouteTilePipeline::run_sim_pass(const sidescan::Seabed& seabed, const sidescan::SideScanSimConfig& sonar_cfg,
                                       const sidescan::TrajectoryConfig& trajectory, const RouteTileSink& sink) {
  reset_pass();
  truth_lateral_m_ = trajectory.lateral_offset_m;
  sidescan::Trajectory traj;
  QNAV_RETURN_IF_ERROR(traj.init(trajectory));
  auto sim = std::make_unique<sidescan::SideScanSimulator>();
  QNAV_RETURN_IF_ERROR(sim->init(sonar_cfg, &seabed));
  sidescan::TrajectorySample s;
  bool stop = false;
  while (!stop && traj.next(s)) {
    Result<sonar::SonarPing> p = sim->ping(s.truth, s.altitude_m, s.index, s.stamp_ns);
    if (!p) return p.status();
    sonar::SonarPing ping = *p;
    ping.ping_number = s.index;
    ping.altitude_m = s.altitude_m;
    PingTruth truth;
    truth.along_m = s.along_route_m;
    truth.pose = s.truth;
    truth.lateral_m = trajectory.lateral_offset_m;
    QNAV_RETURN_IF_ERROR(push_ping(ping, s.nav, truth, sink, &stop));
  }
  return Status::ok();
}

}  // namespace qnav::pipeline
