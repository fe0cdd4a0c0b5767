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
#include "nav/core/span.hpp"
#include "nav/route/route_types.hpp"

namespace qnav::pipeline {

struct TaughtSimRoute {
  SimSurvey survey;
  std::vector<RouteTile> tiles;
  route::RouteParams params{};
  std::vector<route::NodeMeta> meta;
  double spacing_m = 0.0;
  double tile_age_s = 0.0;       // age of a tile's pose when the tile is finished (half a tile of pings)
  double tile_age_m = 0.0;       // the same as dead-reckoned travel (half the tile length; 0: tiles by ping count)
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
  RouteAutopilotConfig autopilot;  // guidance_age_s (and, in run_closed_loop, guidance_age_m) set from the route's tile age for kQnav
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

// The autopilot's taught track from its own log of a teach (qnavd's sim vehicle, the HIL player):
// log[i] = its dead-reckoned pose (teach frame) when it had flown log_dist_m[i] (increasing); each
// node's pose (nodes[j].pose, the route file's numbers) inserted where the log passed the node's
// along-track distance (nodes[j].along_m), so node j = track[node_at[j]]. Allocates the outputs.
void taught_track_from_log(const std::vector<Pose2>& log, const std::vector<double>& log_dist_m,
                           const std::vector<route::NodeMeta>& nodes, std::vector<Pose2>& track,
                           std::vector<std::uint32_t>& node_at);

// The drift and current of a closed-loop run for a seed, as `qnav route follow --sim` flies them and
// qnavd's closed-loop sim passes (sim.pass.closed_loop) too: compass bias +-heading_bias_deg (the sign
// alternates with the seed), DVL scale error +-dvl_scale_pct (the sign alternates every 2 seeds), a
// current of current_mps in a seeded direction (seed x golden ratio of a turn + a quarter), DVL
// dropouts every dropout_every_s on average. pass_seed: repeat_pass_seed(seed) (+1 in reverse).
struct FollowDrift {
  double heading_bias_deg = 1.0, dvl_scale_pct = 1.0, current_mps = 0.2, dropout_every_s = 600.0;
};
ClosedLoopScenario follow_scenario(std::uint64_t seed, bool reverse, double start_offset_m, const FollowDrift& drift);

// The start of one closed-loop run, shared by run_closed_loop and qnavd's sim vehicle: the vehicle at
// the start of truth_poly (the taught track's truth in the direction of travel, >= 2 points) offset
// sc.start_offset_m to starboard, pointing along its first segment; its dead reckoning starts there
// (kQnav) or at the taught track's start in the teach frame (kDeadReckoning: it believes it starts
// where the teach began, or ended); the autopilot reset on the taught track (track, node_at: borrowed,
// as RouteAutopilot::reset) with its frame fixed for kDeadReckoning (and for kQnav with
// follow_track_on_hold: "at the track's start, pointing along it"). guidance_age_s: qnav's tile age.
Status start_closed_loop(Span<const Pose2> track, Span<const std::uint32_t> node_at, const std::vector<Vec2d>& truth_poly,
                         const ClosedLoopScenario& sc, Guide guide, double guidance_age_s, double speed_mps,
                         std::int64_t t_ns, ClosedLoopVehicle& veh, RouteAutopilot& ap);
// One control step of dt_s: the autopilot's command flown by the vehicle, its dead reckoning back to
// the autopilot. False (nothing flown) once the autopilot stops or the vehicle has flown max_travel_m.
bool closed_loop_step(ClosedLoopVehicle& veh, RouteAutopilot& ap, double dt_s, double max_travel_m) noexcept;

// join_band_m: the band for join_distance_m (10 % of the swath in `route follow`).
Status run_closed_loop(const TaughtSimRoute& route, const ClosedLoopScenario& scenario, Guide guide, double join_band_m,
                       ClosedLoopResult& out, const std::function<void(const TrackSample&)>& on_sample = {});

// The truth reference: signed cross-track (+ right of the polyline's direction) and along-track of p
// against a polyline (nearest segment, clamped). Exposed for the tests.
void polyline_offsets(const std::vector<Vec2d>& poly, const Vec2d& p, double& along_m, double& cross_m,
                      double& heading_rad) noexcept;

}  // namespace qnav::pipeline
