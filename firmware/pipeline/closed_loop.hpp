// The closed route-following loop on the simulator (`qnav route follow --sim`, issue 27):
//   teach_closed_loop_route(): a route taught on the SimSurvey (as `qnav route train --sim`), kept in
//     memory with the teach pass's dead-reckoned ends;
//   run_closed_loop(): one repeat flown by a ClosedLoopVehicle whose RouteAutopilot steers either on
//     qnav (kQnav: pings rendered from the TRUE pose -> RouteTilePipeline at the dead-reckoned pose ->
//     RouteRepeater -> QNAV_ROUTE_GUIDANCE/STATUS through QnavCanPublisher onto a sim CAN bus -> the
//     autopilot decodes them off its own node), or on dead reckoning alone against the taught track
//     (kDeadReckoning: the nodes' poses in the teach's dead-reckoned frame, the vehicle's dead
//     reckoning continuing that frame from the route's start or end).
// Truth cross-track is measured against the taught track (the survey's waypoints), + to the right
// of the direction of travel. A run ends when the autopilot stops (RouteEnd, or the baseline past the
// taught track's end) or after max_travel_factor x the route length.
// Memory: per run a tile pipeline and a repeater (allocated at the start of the run), and the
// result's per-ping samples. Tool-side code (allocates); the pieces it wires are the daemon's.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "firmware/pipeline/closed_loop_vehicle.hpp"
#include "firmware/pipeline/route_autopilot.hpp"
#include "firmware/pipeline/route_tile_pipeline.hpp"
#include "firmware/pipeline/sim_survey.hpp"
#include "nav/route/route_types.hpp"

namespace qnav::pipeline {

struct TaughtSimRoute {
  SimSurvey survey;
  std::vector<RouteTile> tiles;
  route::RouteParams params{};
  std::vector<route::NodeMeta> meta;
  double spacing_m = 0.0;
  double tile_age_s = 0.0;       // age of a tile's pose when the tile is finished (half a tile of pings)
  Pose2 nav_start{}, nav_end{};  // the teach pass's dead-reckoned first and last poses
  std::vector<Pose2> track;      // the autopilot's taught track: the teach's dead-reckoned poses every track_step_m,
  std::vector<std::uint32_t> node_at;  // with every node's pose inserted (node i = track[node_at[i]]), teach frame
  std::uint64_t seed = 0;
};
// track_step_m: how often the autopilot logs its dead-reckoned pose while teaching.
Status teach_closed_loop_route(double length_m, std::uint64_t seed, TaughtSimRoute& out, double track_step_m = 10.0);

struct ClosedLoopScenario {
  bool reverse = false;
  double start_offset_m = 0.0;     // start this far right of the route (direction of travel)
  VehicleDynamicsConfig dynamics;  // including the current
  DriftConfig drift;
  RouteAutopilotConfig autopilot;  // guidance_age_s is set from the route's tile age for kQnav
  double max_travel_factor = 1.3;
  std::uint64_t pass_seed = 1;  // the repeat's sonar speckle
};

enum class Guide : std::uint8_t { kQnav, kDeadReckoning };
const char* to_string(Guide g) noexcept;

struct TrackSample {
  double t_s = 0.0;
  Pose2 truth{}, dr{};
  double cross_track_m = 0.0;  // truth, + right of the direction of travel
  double along_m = 0.0;        // truth, along the taught track in the direction of travel
  double travelled_m = 0.0;
  AutopilotMode mode = AutopilotMode::kHoldCourse;
  bool dvl_lost = false;
};

struct ClosedLoopResult {
  std::vector<double> abs_cross_track_m;  // one per ping
  double max_cross_track_m = 0.0;
  double end_offset_m = 0.0;  // true distance from the stop to the taught track's end
  double end_along_m = 0.0;   // along-track of the stop minus the route length (+ past the end)
  bool stopped = false;       // the autopilot stopped (RouteEnd) before the travel limit
  double travelled_m = 0.0;
  double join_distance_m = 0.0;  // travel before |cross-track| stays within join_band_m (-1: never)
  std::uint32_t tiles = 0, steer_fixes = 0, fixes = 0;
  double dropout_s = 0.0;
};

// join_band_m: the band for join_distance_m (10 % of the swath in `route follow`).
Status run_closed_loop(const TaughtSimRoute& route, const ClosedLoopScenario& scenario, Guide guide, double join_band_m,
                       ClosedLoopResult& out, const std::function<void(const TrackSample&)>& on_sample = {});

// The truth reference: signed cross-track (+ right of the polyline's direction) and along-track of p
// against a polyline (nearest segment, clamped). Exposed for the tests.
void polyline_offsets(const std::vector<Vec2d>& poly, const Vec2d& p, double& along_m, double& cross_m,
                      double& heading_rad) noexcept;

}  // namespace qnav::pipeline
