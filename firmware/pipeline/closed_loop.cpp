#include "firmware/pipeline/closed_loop.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include "drivers/qnavcan/publisher.hpp"
#include "firmware/pipeline/route_can.hpp"
#include "firmware/pipeline/route_defaults.hpp"
#include "firmware/pipeline/route_repeat_session.hpp"
#include "hal/sim/memory_file_store.hpp"
#include "firmware/pipeline/vector_node_source.hpp"
#include "hal/sim/manual_clock.hpp"
#include "hal/sim/sim_can.hpp"

namespace qnav::pipeline {

namespace qc = drivers::qnavcan;

const char* to_string(Guide g) noexcept { return g == Guide::kQnav ? "qnav" : "dead_reckoning"; }

void polyline_offsets(const std::vector<Vec2d>& poly, const Vec2d& p, double& along_m, double& cross_m,
                      double& heading_rad) noexcept {
  along_m = cross_m = heading_rad = 0.0;
  double best = 1e300, cum = 0.0;
  for (std::size_t i = 0; i + 1 < poly.size(); ++i) {
    const Vec2d d = poly[i + 1] - poly[i];
    const double len = d.norm();
    if (!(len > 0.0)) continue;
    const Vec2d u = d / len;
    double t = (p - poly[i]).dot(u);
    // The first segment extends backwards and the last forwards: a vehicle before the start or past
    // the end is measured against the track's extension (along < 0 or > length).
    const double lo = i == 0 ? -1e300 : 0.0, hi = i + 2 == poly.size() ? 1e300 : len;
    t = std::clamp(t, lo, hi);
    const Vec2d foot = poly[i] + t * u;
    const double dist = (p - foot).norm();
    if (dist < best) {
      best = dist;
      along_m = cum + t;
      cross_m = (p - poly[i]).dot(Vec2d(-u.y(), u.x()));  // starboard of the segment's direction
      heading_rad = std::atan2(u.y(), u.x());
    }
    cum += len;
  }
}

namespace {
double poly_length(const std::vector<Vec2d>& poly) {
  double l = 0.0;
  for (std::size_t i = 0; i + 1 < poly.size(); ++i) l += (poly[i + 1] - poly[i]).norm();
  return l;
}
}  // namespace

Status teach_closed_loop_route(double length_m, std::uint64_t seed, TaughtSimRoute& out, double track_step_m) {
  out.seed = seed;
  QNAV_RETURN_IF_ERROR(out.survey.init(length_m, seed));
  auto pipe = std::make_unique<RouteTilePipeline>();
  QNAV_RETURN_IF_ERROR(pipe->init(default_route_tile_config()));
  const RouteTileConfig& tc = pipe->config();
  out.spacing_m = tile_stride_m(tc, out.survey.route.speed_mps, out.survey.route.ping_rate_hz);
  out.params = side_scan_route_params(tc, out.spacing_m, out.survey.swath_m);
  out.tile_age_s = tile_age_s(tc, out.survey.route.speed_mps, out.survey.route.ping_rate_hz);
  out.tile_age_m = tile_age_m(tc);
  const sidescan::TrajectoryConfig t0 = out.survey.pass(0.0, false, teach_pass_seed(seed));
  out.tiles.clear();
  QNAV_RETURN_IF_ERROR(
      pipe->run_sim_pass(out.survey.seabed, out.survey.sonar_for(t0.seed), t0, [&out](const RouteTile& t) {
        out.tiles.push_back(t);
        return true;
      }));
  if (out.tiles.size() < 2)
    return Status(StatusCode::kInvalidArgument, "closed loop: the taught route has fewer than 2 nodes");
  out.meta.clear();
  for (std::size_t i = 0; i < out.tiles.size(); ++i) {
    route::NodeMeta m = out.tiles[i].node.meta;
    m.index = static_cast<std::uint32_t>(i);
    out.meta.push_back(m);
  }
  // The autopilot's log of the teach: its dead-reckoned pose every track_step_m, and each node's
  // pose (the tile centre's) where the pass reached it (the same trajectory, without rendering).
  sidescan::Trajectory traj;
  QNAV_RETURN_IF_ERROR(traj.init(t0));
  sidescan::TrajectorySample s;
  out.track.clear();
  out.node_at.clear();
  std::size_t next_node = 0;
  double since = 0.0;
  Pose2 prev{};
  bool first = true;
  while (traj.next(s)) {
    const double step = first ? 0.0 : (s.nav.translation() - prev.translation()).norm();
    since += step;
    const double travelled = s.along_route_m;  // the nodes' along_m is the teach's nav distance ~ the route's
    while (next_node < out.meta.size() && out.tiles[next_node].truth_along_m <= travelled) {
      out.node_at.push_back(static_cast<std::uint32_t>(out.track.size()));
      out.track.push_back(out.meta[next_node].pose);
      ++next_node;
      since = 0.0;
    }
    if (first || since >= track_step_m) {
      out.track.push_back(s.nav);
      since = 0.0;
    }
    if (first) out.nav_start = s.nav;
    first = false;
    prev = s.nav;
    out.nav_end = s.nav;
  }
  while (next_node < out.meta.size()) {
    out.node_at.push_back(static_cast<std::uint32_t>(out.track.size()));
    out.track.push_back(out.meta[next_node++].pose);
  }
  out.track.push_back(out.nav_end);
  return Status::ok();
}

void taught_track_from_log(const std::vector<Pose2>& log, const std::vector<double>& log_dist_m,
                           const std::vector<route::NodeMeta>& nodes, std::vector<Pose2>& track,
                           std::vector<std::uint32_t>& node_at) {
  track.clear();
  node_at.clear();
  std::size_t j = 0;
  for (std::size_t i = 0; i < log.size() && i < log_dist_m.size(); ++i) {
    for (; j < nodes.size() && nodes[j].along_m <= log_dist_m[i]; ++j) {
      node_at.push_back(static_cast<std::uint32_t>(track.size()));
      track.push_back(nodes[j].pose);
    }
    track.push_back(log[i]);
  }
  for (; j < nodes.size(); ++j) {  // nodes past the log's end (the log stops at the teach's last ping)
    node_at.push_back(static_cast<std::uint32_t>(track.size()));
    track.push_back(nodes[j].pose);
  }
}

ClosedLoopScenario follow_scenario(std::uint64_t seed, bool reverse, double start_offset_m, const FollowDrift& d) {
  ClosedLoopScenario sc;
  sc.reverse = reverse;
  sc.start_offset_m = start_offset_m;
  sc.drift.heading_bias_rad = deg_to_rad(d.heading_bias_deg) * (seed % 2 ? 1.0 : -1.0);
  sc.drift.dvl_scale_error = d.dvl_scale_pct / 100.0 * ((seed / 2) % 2 ? -1.0 : 1.0);
  sc.drift.dropout_every_s = d.dropout_every_s;
  sc.drift.seed = seed * 31 + (reverse ? 17 : 3);
  const double current_dir = 2.0 * kPi * std::fmod(static_cast<double>(seed) * 0.6180339887498949 + 0.25, 1.0);
  sc.dynamics.current_ne = d.current_mps * Vec2d(std::cos(current_dir), std::sin(current_dir));
  sc.pass_seed = repeat_pass_seed(seed) + (reverse ? 1 : 0);
  return sc;
}

Status start_closed_loop(Span<const Pose2> track, Span<const std::uint32_t> node_at, const std::vector<Vec2d>& truth_poly,
                         const ClosedLoopScenario& sc, Guide guide, double guidance_age_s, double speed_mps,
                         std::int64_t t_ns, ClosedLoopVehicle& veh, RouteAutopilot& ap) {
  if (truth_poly.size() < 2 || track.size() < 2)
    return Status(StatusCode::kInvalidArgument, "closed loop: the taught track needs >= 2 points");
  const bool qnav = guide == Guide::kQnav;
  const Vec2d d0 = truth_poly[1] - truth_poly[0];
  const double h0 = std::atan2(d0.y(), d0.x());
  const Vec2d p0 = truth_poly[0] + sc.start_offset_m * Vec2d(-std::sin(h0), std::cos(h0));
  const Pose2 truth0{p0.x(), p0.y(), h0};
  const std::size_t n = track.size();
  const Pose2& track0 = sc.reverse ? track[n - 1] : track[0];
  const Pose2 dr0 = qnav ? truth0 : Pose2{track0.x_m, track0.y_m, h0};
  veh.reset(sc.dynamics, sc.drift, truth0, dr0, speed_mps, t_ns);
  RouteAutopilotConfig apc = sc.autopilot;
  apc.cruise_speed_mps = speed_mps;
  apc.guidance_age_s = qnav ? guidance_age_s : 0.0;
  if (!qnav) apc.guidance_age_m = 0.0;
  apc.reverse = sc.reverse;
  QNAV_RETURN_IF_ERROR(ap.reset(apc, track, node_at, veh.t_ns(), veh.dr_pose()));
  if (!qnav) {
    ap.set_frame(Pose2{});  // dead reckoning IS the teach frame
  } else if (apc.follow_track_on_hold) {
    // Until qnav's first fix: "I am at the track's start, pointing along it" (its first segment).
    const Vec2d a = track[sc.reverse ? n - 1 : 0].translation(), b = track[sc.reverse ? n - 2 : 1].translation();
    const Vec2d d = b - a;
    const Pose2 start_teach{a.x(), a.y(), std::atan2(d.y(), d.x())};
    ap.set_frame(start_teach.compose(veh.dr_pose().inverse()));
  }
  return Status::ok();
}

bool closed_loop_step(ClosedLoopVehicle& veh, RouteAutopilot& ap, double dt_s, double max_travel_m) noexcept {
  const AutopilotCommand cmd = ap.command();
  if (cmd.mode == AutopilotMode::kStopped || veh.travelled_m() > max_travel_m) return false;
  veh.step(dt_s, cmd.heading_rad, cmd.speed_mps);
  ap.on_nav(veh.t_ns(), veh.dr_pose(), veh.sideslip_rad());
  return true;
}

Status run_closed_loop(const TaughtSimRoute& route, const ClosedLoopScenario& sc, Guide guide, double join_band_m,
                       ClosedLoopResult& out, const std::function<void(const TrackSample&)>& on_sample) {
  out = ClosedLoopResult{};
  const SimSurvey& w = route.survey;
  const bool qnav = guide == Guide::kQnav;
  // The taught track (truth) in the direction of travel.
  std::vector<Vec2d> truth_poly(w.route.waypoints_ne.begin(), w.route.waypoints_ne.end());
  if (sc.reverse) std::reverse(truth_poly.begin(), truth_poly.end());
  const double length = poly_length(truth_poly);
  const double dt = 1.0 / w.route.ping_rate_hz;
  const double speed = w.route.speed_mps;
  const float altitude = static_cast<float>(w.route.altitude_m);
  ClosedLoopVehicle veh;
  RouteAutopilot ap;
  ClosedLoopScenario scq = sc;  // the autopilot allows for half a tile of its own travel (tiles in metres)
  scq.autopilot.guidance_age_m = route.tile_age_m;
  QNAV_RETURN_IF_ERROR(start_closed_loop(Span<const Pose2>(route.track.data(), route.track.size()),
                                         Span<const std::uint32_t>(route.node_at.data(), route.node_at.size()),
                                         truth_poly, scq, guide, route.tile_age_s, speed, 0, veh, ap));

  // qnav's side: tiles -> repeater -> CAN publisher on a sim bus; the autopilot is another node.
  std::unique_ptr<RouteTilePipeline> pipe;
  hal::MemoryFileStore no_files(Span<std::uint8_t>{});
  std::unique_ptr<RouteRepeatSession> rep;
  std::unique_ptr<sidescan::SideScanSimulator> sim;
  hal::ManualClock clock;
  hal::SimCanNetwork net(clock);
  hal::SimCanBus qnav_node, autopilot_node;
  qc::QnavCanPublisher publisher(qnav_node);
  VectorNodeSource<RouteTile> source(&route.tiles);
  if (qnav) {
    pipe = std::make_unique<RouteTilePipeline>();
    QNAV_RETURN_IF_ERROR(pipe->init(default_route_tile_config()));
    // The repeat component qnavd runs (no experiences: the route is held in memory, no files).
    rep = std::make_unique<RouteRepeatSession>(no_files);
    RepeatSessionConfig rc;
    rc.localiser = default_localiser_config(sc.reverse ? route::RouteDirection::kReverse : route::RouteDirection::kForward, route.meta.size() + 8);
    rc.max_nodes = route.meta.size();
    QNAV_RETURN_IF_ERROR(rep->init(rc));
    QNAV_RETURN_IF_ERROR(rep->start(route.params, Span<const route::NodeMeta>(route.meta.data(), route.meta.size()), source, sc.reverse));
    sim = std::make_unique<sidescan::SideScanSimulator>();
    QNAV_RETURN_IF_ERROR(sim->init(w.sonar_for(sc.pass_seed), &w.seabed));
    QNAV_RETURN_IF_ERROR(qnav_node.attach(net));
    QNAV_RETURN_IF_ERROR(autopilot_node.attach(net));
  }
  std::uint32_t seq = 0;
  Status step_status;
  const RouteTileSink sink = [&](const RouteTile& t) {
    // Unlike qnavd, the filter keeps the odometry motion model through the vehicle's DVL dropouts:
    // tried in this loop (`route follow --sim --length-m 2000 --seeds 1:4`, before the guidance age
    // was counted in metres), it made the reverse runs worse (p95 2.8 -> 3.7 m, max 6.2 -> 8.6 m).
    route::LocaliserStep st;
    step_status = rep->step(t, false, st).step;
    if (!step_status) return false;
    // The next tile framed on the taught nodes (a reverse pass brought into step with them), as
    // qnavd and `route repeat` frame theirs.
    pipe->set_next_stride_m(rep->next_stride_m(st, pipe->config().tiles.tile_stride_m));
    qc::RouteGuidance g;
    qc::RouteStatus s;
    route_can_messages(st, rep->repeater().localiser().node_spacing_m(), seq++, g, s);
    publisher.set(g);
    publisher.set(s);
    ++out.tiles;
    return true;
  };

  std::vector<double> travelled;
  const double max_travel = sc.max_travel_factor * length;
  double along = 0.0, cross = 0.0, hdg = 0.0;
  for (std::uint32_t k = 1;; ++k) {
    if (!closed_loop_step(veh, ap, dt, max_travel)) {
      out.stopped = ap.command().mode == AutopilotMode::kStopped;
      break;
    }
    const std::int64_t t = veh.t_ns();
    const Pose2 dr = veh.dr_pose();
    polyline_offsets(truth_poly, veh.truth().translation(), along, cross, hdg);
    if (qnav) {
      PingTruth pt;
      pt.pose = veh.truth();
      pt.along_m = sc.reverse ? length - along : along;
      pt.lateral_m = sc.reverse ? -cross : cross;
      bool stop = false;
      QNAV_RETURN_IF_ERROR(pipe->push_sim_ping(*sim, k, static_cast<std::uint64_t>(t), altitude, dr, pt, sink, &stop));
      if (!step_status) return step_status;
      clock.set_ns(t);
      publisher.poll(t);
      hal::CanRxFrame rx;
      while (autopilot_node.receive(rx, 0))
        ap.on_frame(rx.frame, t).ignore();  // decode errors are counted by the autopilot
    }
    out.abs_cross_track_m.push_back(std::fabs(cross));
    travelled.push_back(veh.travelled_m());
    out.max_cross_track_m = std::max(out.max_cross_track_m, std::fabs(cross));
    if (on_sample) {
      TrackSample smp;
      smp.t_s = static_cast<double>(t) * 1e-9;
      smp.truth = veh.truth();
      smp.dr = dr;
      smp.cross_track_m = cross;
      smp.along_m = along;
      smp.travelled_m = veh.travelled_m();
      smp.mode = ap.command().mode;
      smp.dvl_lost = veh.dvl_lost();
      on_sample(smp);
    }
  }
  out.travelled_m = veh.travelled_m();
  out.end_offset_m = (veh.truth().translation() - truth_poly.back()).norm();
  out.end_along_m = along - length;
  out.fixes = ap.counters().get(AutopilotCounter::kFixes);
  out.steer_fixes = ap.counters().get(AutopilotCounter::kSteerFixes);
  out.dropout_s = veh.dropout_total_s();
  out.join_distance_m = 0.0;
  for (std::size_t i = out.abs_cross_track_m.size(); i-- > 0;) {
    if (out.abs_cross_track_m[i] > join_band_m) {
      out.join_distance_m = i + 1 < travelled.size() ? travelled[i + 1] : -1.0;
      break;
    }
  }
  return Status::ok();
}

}  // namespace qnav::pipeline
