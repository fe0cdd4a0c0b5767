// RouteTilePipeline::push_sim_ping and run_sim_pass: simulated pings (the side-scan simulator over a
// seabed) through the tile pipeline. In a file of its own so that a program that never flies a simulated pass (the
// flight binary qnavd) does not link the simulator.
#include <memory>

#include "firmware/pipeline/route_tile_pipeline.hpp"

namespace qnav::pipeline {

Status RouteTilePipeline::push_sim_ping(sidescan::SideScanSimulator& sim, std::uint32_t index, std::uint64_t stamp_ns, float altitude_m,
                                        const Pose2& nav, const PingTruth& truth, const RouteTileSink& sink, bool* stop) {
  Result<sonar::SonarPing> p = sim.ping(truth.pose, altitude_m, index, stamp_ns);
  if (!p) return p.status();
  sonar::SonarPing ping = *p;
  ping.ping_number = index;
  ping.altitude_m = altitude_m;
  return push_ping(ping, nav, truth, sink, stop);
}

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
    PingTruth truth;
    truth.along_m = s.along_route_m;
    truth.pose = s.truth;
    truth.lateral_m = trajectory.lateral_offset_m;
    QNAV_RETURN_IF_ERROR(push_sim_ping(*sim, s.index, s.stamp_ns, s.altitude_m, s.nav, truth, sink, &stop));
  }
  return Status::ok();
}

}  // namespace qnav::pipeline
