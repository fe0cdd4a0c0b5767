#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "drivers/route_store/route_file.hpp"
#include "drivers/route_store/route_open.hpp"
#include "firmware/qnavd/sim_closed_loop.hpp"
#include "firmware/tools/stats.hpp"

namespace qnav::daemon {

namespace {
double percentile(std::vector<double> v, double q) {
  double out = 0.0;
  return tools::percentile_of(v, q, out) ? out : 0.0;
}
}  // namespace

SimClosedLoop::~SimClosedLoop() {
  if (c_.csv) std::fclose(c_.csv);
}

Status SimClosedLoop::init() {
  Pass& c = c_;
  const std::size_t n = static_cast<std::size_t>(2.0 * cfg_.sim_length_m / kLogStepM) + 64;
  c.log.reserve(n);
  c.log_dist_m.reserve(n);
  if (!cfg_.sim_closed_loop_csv.empty()) {  // opened here: a bad path is a start-up error, not a skipped pass
    c.csv = std::fopen(cfg_.sim_closed_loop_csv.c_str(), "w");
    if (c.csv == nullptr) {
      std::fprintf(stderr, "qnavd: sim.closed_loop_csv %s: %s\n", cfg_.sim_closed_loop_csv.c_str(), std::strerror(errno));
      return Status(StatusCode::kIoError, "sim: cannot write sim.closed_loop_csv (see the line above)");
    }
    std::fprintf(c.csv, "seed,track,t_s,north_m,east_m,cross_track_m,along_m,travelled_m,mode,dvl_lost\n");
  }
  return Status::ok();
}

void SimClosedLoop::begin_pass(bool teach_logging) noexcept {
  c_.logging = teach_logging;
  if (c_.logging) c_.have_log = false;
}

void SimClosedLoop::log_teach_pose(const Pose2& nav) noexcept {
  Pass& c = c_;
  if (!c.logging) return;
  if (!c.have_log) {
    // qnavd's dead reckoning restarts at the mode command and the pass's first ping moves it by
    // nothing: the teach frame is this pass's dead reckoning less its first ping's position.
    c.nav0 = nav;
    c.prev = nav;
    c.dist_m = c.since_m = 0.0;
    c.log.clear();
    c.log_dist_m.clear();
    c.have_log = true;
  }
  const double step = (nav.translation() - c.prev.translation()).norm();
  c.dist_m += step;
  c.since_m += step;
  c.prev = nav;
  c.last = Pose2{nav.x_m - c.nav0.x_m, nav.y_m - c.nav0.y_m, nav.heading_rad};
  if (c.log.empty() || c.since_m >= kLogStepM) {
    if (c.log.size() < c.log.capacity()) {  // reserved at init: the teach allocates nothing per ping
      c.log.push_back(c.last);
      c.log_dist_m.push_back(c.dist_m);
    }
    c.since_m = 0.0;
  }
}

Status SimClosedLoop::start(std::uint32_t pass, std::uint64_t pass_seed, const pipeline::SimSurvey& survey, hal::FaultFileStore* store) {
  Pass& c = c_;
  const SimPass& p = cfg_.sim_mission[pass];
  if (!c.have_log || c.log.size() < 2)
    return Status(StatusCode::kInvalidArgument, "sim closed loop: no simulated teach pass was flown before this pass");
  // The taught track: the teach log up to the teach's last ping, and the route's node poses.
  std::vector<Pose2> log = c.log;
  std::vector<double> dist = c.log_dist_m;
  log.push_back(c.last);
  dist.push_back(c.dist_m);
  char path[1024];
  std::snprintf(path, sizeof path, "%s/route_%u.qroute", cfg_.route_dir.c_str(), static_cast<unsigned>(cfg_.route_id));
  if (store == nullptr) return Status(StatusCode::kInvalidArgument, "sim closed loop: no route store");
  drivers::route_store::RouteFileReader reader(*store);
  const drivers::route_store::RepeatOpenReport r = drivers::route_store::open_route_for_repeat(reader, path, c.meta, cfg_.max_nodes);
  if (r.outcome != drivers::route_store::RepeatOpen::kOk && r.outcome != drivers::route_store::RepeatOpen::kGoodPrefix) {
    std::fprintf(stderr, "sim closed loop: %s: %s\n", path, r.why.message());
    return Status(StatusCode::kNotFound, "sim closed loop: the taught route cannot be read (see the line above)");
  }
  pipeline::taught_track_from_log(log, dist, c.meta, c.track, c.node_at);
  c.spacing_m = 0.0;
  for (std::size_t i = 0; i + 1 < c.meta.size(); ++i)
    c.spacing_m += (c.meta[i + 1].pose.translation() - c.meta[i].pose.translation()).norm() / static_cast<double>(c.meta.size() - 1);
  // The truth: the survey's waypoints in the direction of travel.
  c.truth_poly.assign(survey.route.waypoints_ne.begin(), survey.route.waypoints_ne.end());
  c.reverse = p.reverse;
  if (c.reverse) std::reverse(c.truth_poly.begin(), c.truth_poly.end());
  c.length_m = 0.0;
  for (std::size_t i = 0; i + 1 < c.truth_poly.size(); ++i) c.length_m += (c.truth_poly[i + 1] - c.truth_poly[i]).norm();
  c.swath_m = survey.swath_m;
  c.seed = cfg_.sim_seed;
  c.pass = pass;
  // The drift of `qnav route follow --sim` for this seed, the start offset of the pass.
  pipeline::ClosedLoopScenario sc = pipeline::follow_scenario(cfg_.sim_seed, p.reverse, p.offset_pct / 100.0 * c.swath_m, pipeline::FollowDrift{});
  sc.pass_seed = pass_seed;
  sc.autopilot.guidance_age_m = pipeline::tile_age_m(cfg_.tiles);  // half a tile of its own travel (0: by ping count)
  c.dt_s = 1.0 / survey.route.ping_rate_hz;
  c.max_travel_m = sc.max_travel_factor * c.length_m;
  const double age_s = pipeline::tile_age_s(cfg_.tiles, survey.route.speed_mps, survey.route.ping_rate_hz);
  const Span<const Pose2> track(c.track.data(), c.track.size());
  const Span<const std::uint32_t> node_at(c.node_at.data(), c.node_at.size());
  // The first ping one ping period after the last sample between passes (sample times strictly increase).
  const std::int64_t t0 = clock_.now_ns();
  QNAV_RETURN_IF_ERROR(pipeline::start_closed_loop(track, node_at, c.truth_poly, sc, pipeline::Guide::kQnav, age_s,
                                                   survey.route.speed_mps, t0, c.veh, c.ap));
  QNAV_RETURN_IF_ERROR(pipeline::start_closed_loop(track, node_at, c.truth_poly, sc, pipeline::Guide::kDeadReckoning, age_s,
                                                   survey.route.speed_mps, t0, c.twin, c.twin_ap));
  const std::size_t pings = static_cast<std::size_t>(c.max_travel_m / (survey.route.speed_mps * c.dt_s)) + 16;
  for (std::vector<double>* v : {&c.xt_qnav, &c.xt_dr, &c.flown_qnav, &c.flown_dr}) {
    v->clear();
    v->reserve(pings);
  }
  c.index = 0;
  c.twin_done = false;
  c.active = true;
  if (c.csv) {
    for (const Vec2d& w : survey.route.waypoints_ne)
      std::fprintf(c.csv, "%llu,taught,0,%.2f,%.2f,0,0,0,,0\n", static_cast<unsigned long long>(c.seed), w.x(), w.y());
  }
  std::fprintf(stderr, "sim autopilot: pass %u flies in closed loop on qnavd's guidance: %zu nodes, taught track of %zu poses, %s\n", pass,
               c.meta.size(), c.track.size(), c.reverse ? "reverse" : "forward");
  return Status::ok();
}

namespace {
void csv_row(std::FILE* f, std::uint64_t seed, const char* track, const pipeline::ClosedLoopVehicle& v, double cross, double along,
             pipeline::AutopilotMode mode, std::int64_t t0_ns) {
  if (f == nullptr) return;
  std::fprintf(f, "%llu,%s,%.1f,%.2f,%.2f,%.2f,%.1f,%.1f,%s,%d\n", static_cast<unsigned long long>(seed), track,
               static_cast<double>(v.t_ns() - t0_ns) * 1e-9, v.truth().x_m, v.truth().y_m, cross, along, v.travelled_m(),
               pipeline::to_string(mode), v.dvl_lost() ? 1 : 0);
}
}  // namespace

bool SimClosedLoop::next(SimSample& out, sidescan::TrajectorySample& render, double altitude_m, std::int64_t pass_start_ns) noexcept {
  Pass& c = c_;
  if (!c.active) return false;
  const std::int64_t t0 = pass_start_ns;
  if (!pipeline::closed_loop_step(c.veh, c.ap, c.dt_s, c.max_travel_m)) {
    finish(pass_start_ns);
    return false;
  }
  double along = 0.0, cross = 0.0, hdg = 0.0;
  pipeline::polyline_offsets(c.truth_poly, c.veh.truth().translation(), along, cross, hdg);
  c.along_m = along;
  c.xt_qnav.push_back(std::fabs(cross));
  c.flown_qnav.push_back(c.veh.travelled_m());
  if (c.index % kCsvEvery == 0) csv_row(c.csv, c.seed, "qnav", c.veh, cross, along, c.ap.command().mode, t0);
  // The twin on dead reckoning alone, in step with it.
  if (!c.twin_done) {
    c.twin_done = !pipeline::closed_loop_step(c.twin, c.twin_ap, c.dt_s, c.max_travel_m);
    if (!c.twin_done) {
      double ta = 0.0, tc = 0.0;
      pipeline::polyline_offsets(c.truth_poly, c.twin.truth().translation(), ta, tc, hdg);
      c.twin_along_m = ta;
      c.xt_dr.push_back(std::fabs(tc));
      c.flown_dr.push_back(c.twin.travelled_m());
      if (c.index % kCsvEvery == 0)
        csv_row(c.csv, c.seed, "dead_reckoning", c.twin, tc, ta, c.twin_ap.command().mode, t0);
    }
  }
  out.t_ns = c.veh.t_ns();
  out.nav = c.veh.dr_pose();
  out.ping_number = c.index;
  out.device_stamp_ns = static_cast<std::uint64_t>(out.t_ns);
  out.altitude_m = static_cast<float>(altitude_m);
  out.has_truth = true;
  out.truth.pose = c.veh.truth();
  out.truth.along_m = c.reverse ? c.length_m - along : along;  // along the route from its first waypoint
  out.truth.lateral_m = c.reverse ? -cross : cross;             // right of the route's forward direction
  out.recorded = nullptr;
  // The sonar renders from the true pose (SimSonar::emit_ping).
  render.truth = c.veh.truth();
  render.altitude_m = out.altitude_m;
  render.index = c.index;
  ++c.index;
  return true;
}

void SimClosedLoop::finish(std::int64_t pass_start_ns) noexcept {
  Pass& c = c_;
  if (!c.active) return;
  c.active = false;
  // The twin flies on to its own end (it needs no pings).
  double hdg = 0.0;
  while (!c.twin_done) {
    c.twin_done = !pipeline::closed_loop_step(c.twin, c.twin_ap, c.dt_s, c.max_travel_m);
    if (c.twin_done) break;
    double ta = 0.0, tc = 0.0;
    pipeline::polyline_offsets(c.truth_poly, c.twin.truth().translation(), ta, tc, hdg);
    c.twin_along_m = ta;
    c.xt_dr.push_back(std::fabs(tc));
    c.flown_dr.push_back(c.twin.travelled_m());
    if (c.xt_dr.size() % kCsvEvery == 1) csv_row(c.csv, c.seed, "dead_reckoning", c.twin, tc, ta, c.twin_ap.command().mode, pass_start_ns);
  }
  // Each track's last row is where it stopped.
  double fa = 0.0, fc = 0.0;
  pipeline::polyline_offsets(c.truth_poly, c.veh.truth().translation(), fa, fc, hdg);
  csv_row(c.csv, c.seed, "qnav", c.veh, fc, fa, c.ap.command().mode, pass_start_ns);
  pipeline::polyline_offsets(c.truth_poly, c.twin.truth().translation(), fa, fc, hdg);
  csv_row(c.csv, c.seed, "dead_reckoning", c.twin, fc, fa, c.twin_ap.command().mode, pass_start_ns);
  const Vec2d end = c.truth_poly.back();
  const double q_end = (c.veh.truth().translation() - end).norm(), d_end = (c.twin.truth().translation() - end).norm();
  const bool q_stopped = c.ap.command().mode == pipeline::AutopilotMode::kStopped;
  const bool d_stopped = c.twin_ap.command().mode == pipeline::AutopilotMode::kStopped;
  const auto mx = [](const std::vector<double>& v) { return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()); };
  // Join: the distance flown before |cross-track| stays within 10 % of the swath (-1: it never does),
  // as `qnav route follow` reports it.
  const auto join_m = [&c](const std::vector<double>& xt, const std::vector<double>& flown) {
    for (std::size_t i = xt.size(); i-- > 0;)
      if (xt[i] > 0.1 * c.swath_m) return i + 1 < flown.size() ? flown[i + 1] : -1.0;
    return 0.0;
  };
  char line[768];
  std::snprintf(line, sizeof line,
                "{\"event\":\"sim_closed_loop\",\"pass\":%u,\"reverse\":%s,\"swath_m\":%.2f,\"node_spacing_m\":%.2f,\"length_m\":%.0f,"
                "\"qnav\":{\"cross_track_p50_m\":%.2f,\"cross_track_p95_m\":%.2f,\"cross_track_max_m\":%.2f,\"end_offset_m\":%.2f,"
                "\"reached_end\":%s,\"travelled_m\":%.0f,\"join_m\":%.0f,\"steer_fixes\":%u,\"decode_errors\":%u},"
                "\"dead_reckoning\":{\"cross_track_p50_m\":%.2f,\"cross_track_p95_m\":%.2f,\"cross_track_max_m\":%.2f,"
                "\"end_offset_m\":%.2f,\"reached_end\":%s,\"travelled_m\":%.0f,\"join_m\":%.0f}}",
                c.pass, c.reverse ? "true" : "false", c.swath_m, c.spacing_m, c.length_m, percentile(c.xt_qnav, 0.5),
                percentile(c.xt_qnav, 0.95), mx(c.xt_qnav), q_end, q_stopped && q_end <= c.spacing_m ? "true" : "false",
                c.veh.travelled_m(), join_m(c.xt_qnav, c.flown_qnav), c.ap.counters().get(pipeline::AutopilotCounter::kSteerFixes),
                c.ap.counters().get(pipeline::AutopilotCounter::kDecodeErrors), percentile(c.xt_dr, 0.5), percentile(c.xt_dr, 0.95),
                mx(c.xt_dr), d_end, d_stopped && d_end <= c.spacing_m ? "true" : "false", c.twin.travelled_m(), join_m(c.xt_dr, c.flown_dr));
  std::fprintf(stderr, "sim autopilot: %s\n", line);
  if (log_ != nullptr) std::fprintf(log_, "%s\n", line);
  if (c.csv) std::fflush(c.csv);
}

}  // namespace qnav::daemon
