// qnav route: route teach and repeat (route-following paper) on the side-scan simulator or XTF files.
//   qnav route train  --sim --out FILE [--length-m 2000] [--seed N] [--force] -> route file (durable; taught
//                     under FILE.new, renamed over FILE only when complete: the old route survives a kill)
//   qnav route info   FILE                                                -> header, end (closed cleanly / cut off),
//                     torn tail, every damaged node
//   qnav route repeat --route FILE --sim [--offset-pct P] [--reverse] [--csv OUT] [--seed N] [--length-m M]
//   qnav route eval   [--json] [--out DIR] [--length-m 2000] [--seabeds 3] [--quick] -> Table I, Fig. 5/7/9/10 data
//   qnav route framing [--json] [--length-m 1000] [--quick] [--seabed N] [--only R:S] -> tiles in metres at 2, 5, 15 pings/s, 2 speeds
//   qnav route xtf    --xtf FILE [--train A:B] [--repeat C:D] [--csv OUT]  -> real data: teach on pings A..B,
//                     repeat on the shifted window C..D of the same pass
//   qnav route train|repeat --sonar FILE ...                            -> routes from recorded XTF / JSF passes
//   qnav route camera [--json] [--length-m 12] [--seed 7]               -> the same on a downward camera over
//                     the synthetic Mars yard: teach, repeat forwards / reverse at 0-40 % of the footprint
//   qnav route follow --sim ...                                         -> the closed loop (route_follow.cpp)
// Train, info, repeat (simulated) and the command line of every subcommand live here; eval, the
// recorded passes and the camera route in firmware/qnav/commands/route/ (route_cmd.hpp).
#include "firmware/cli/cli_app.hpp"
#include "firmware/qnav/command.hpp"
#include "firmware/qnav/commands/route/route_cmd.hpp"
#include "firmware/qnav/commands/route_follow.hpp"

namespace route_cmd {

RouteOptions g_opt;

const char* opt_or_null(const std::string& s) { return s.empty() ? nullptr : s.c_str(); }

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }
// CPU time of this thread (the machine is shared: wall time includes other people's work).
double cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

// Collects the tiles of one simulated pass.
Status fly(pipeline::RouteTilePipeline& pipe, const pipeline::SimSurvey& w, const sidescan::TrajectoryConfig& t, std::vector<pipeline::RouteTile>& out) {
  out.clear();
  return pipe.run_sim_pass(w.seabed, w.sonar_for(t.seed), t, [&out](const pipeline::RouteTile& tile) {
    out.push_back(tile);
    return true;
  });
}


// A usage error the parser cannot see (a combination of options): named, exit 2.
int usage(const char* cmd, const char* what) {
  std::fprintf(stderr, "qnav route %s: %s (qnav help route %s)\n", cmd, what, cmd);
  return 2;
}

// ---- route files: teaching never destroys a route before its replacement is complete ----

// The reader's non-zero counters, "name=N ..." ("none" when all are zero).
std::string counter_text(const route::RouteFormatCounters& c) {
  std::string t;
  for (std::size_t i = 0; i < c.size(); ++i)
    if (c.count_at(i) > 0) t += (t.empty() ? "" : " ") + std::string(c.name_at(i)) + "=" + std::to_string(c.count_at(i));
  return t.empty() ? "none" : t;
}

// Starts teaching the route `out`: the nodes go to OUT.new (durable node by node) and replace OUT
// only at finish_route's commit, so a kill or power cut at any moment leaves the old route whole.
// Without --force an existing OUT is refused before anything is taught. A previous run's OUT.new
// (cut off) is kept as OUT.new.kept.<n>. Reports and returns false on error.
bool begin_route(tools::RouteFileWriter& w, const char* cmd, const char* out, const route::RouteParams& p, bool force,
                 tools::RouteWriterOptions o) {
  o.replace_existing = force;
  tools::RouteReplaceReport rep;
  const Status s = w.create_replacement(out, p, o, &rep);
  if (!s) {
    std::fprintf(stderr, "qnav route %s: %s: %s%s\n", cmd, out, s.message(),
                 !force && s.code() == StatusCode::kInvalidArgument ? " (--force replaces it; the old route stays until the new one is complete)" : "");
    return false;
  }
  if (rep.previous_kept)
    std::fprintf(stderr, "qnav route %s: a previous unfinished run's %s was kept as %s\n", cmd, rep.temp_path, rep.kept_path);
  return true;
}

// Ends teaching: when taught is ok, the end mark, fsync and the atomic rename over OUT (directory
// fsync'ed); otherwise OUT is left untouched and the nodes taught so far stay durable in OUT.new
// (without an end mark: it reads as cut off). Reports; true when committed.
bool finish_route(tools::RouteFileWriter& w, const char* cmd, const char* out, Status taught) {
  char temp[tools::kRoutePathBytes];
  std::snprintf(temp, sizeof temp, "%s", w.path());
  if (taught) {
    const Status c = w.commit();
    if (c) return true;
    std::fprintf(stderr, "qnav route %s: %s: commit failed: %s (the %u nodes taught stay in %s; %s is unchanged)\n", cmd, out, c.message(),
                 w.node_count(), temp, out);
    return false;
  }
  const std::uint32_t n = w.node_count();
  const Status a = w.abandon();
  std::fprintf(stderr, "qnav route %s: %s (%s is unchanged; the %u nodes taught %s in %s)\n", cmd, taught.message(), out, n,
               a ? "stay" : "may not all be durable", temp);
  return false;
}

// How the route file ends, one line (stdout for info, stderr as a warning for repeat). true when
// the route was closed cleanly and has no torn tail.
bool report_route_end(FILE* f, const char* prefix, const tools::RouteFileReader& r) {
  bool clean = true;
  switch (r.end()) {
    case tools::RouteEnd::kClosedCleanly:
      std::fprintf(f, "%sformat version %u, closed cleanly (end mark: %u nodes)\n", prefix, r.format_version(), r.end_mark_nodes());
      break;
    case tools::RouteEnd::kCutOff:
      std::fprintf(f, "%sCUT OFF: no end mark: the teach was killed or lost power before it closed the route; its %u complete nodes are usable\n",
                   prefix, r.file_nodes());
      clean = false;
      break;
    case tools::RouteEnd::kCountMismatch:
      std::fprintf(f, "%sCUT OFF: the end mark records %u nodes but the file holds %u\n", prefix, r.end_mark_nodes(), r.file_nodes());
      clean = false;
      break;
    case tools::RouteEnd::kNoEndMarkV1:
      std::fprintf(f, "%sno end marker: version 1 (a complete route and a cut-off one look the same)\n", prefix);
      clean = false;
      break;
  }
  if (r.torn_bytes() > 0) {
    if (r.file_nodes() > 0)
      std::fprintf(f, "%storn tail: %llu bytes after node %u, the last complete one: the partial node %u was dropped\n", prefix,
                   static_cast<unsigned long long>(r.torn_bytes()), r.file_nodes() - 1, r.file_nodes());
    else
      std::fprintf(f, "%storn tail: %llu bytes after the header: the partial node 0 was dropped\n", prefix,
                   static_cast<unsigned long long>(r.torn_bytes()));
    clean = false;
  }
  return clean;
}

// Opens a route to repeat by the one policy qnavd uses (drivers/route_store/route_open.hpp): how it
// ends is reported (a warning when cut off or torn: still usable), a damaged node is named with why,
// and with at least 2 good nodes before it the repeat goes on over that good prefix (warning with the
// counters), otherwise it is refused. Reports and returns false when the route cannot be used.
bool open_route_for_repeat(const char* path, tools::RouteFileReader& reader, std::vector<route::NodeMeta>& meta) {
  using drivers::route_store::RepeatOpen;
  const drivers::route_store::RepeatOpenReport r = drivers::route_store::open_route_for_repeat(reader, path, meta, static_cast<std::size_t>(-1));
  char prefix[600];
  std::snprintf(prefix, sizeof prefix, "qnav route repeat: WARNING: %s: ", path);
  if (r.outcome == RepeatOpen::kDamaged) {
    std::fprintf(stderr, "qnav route repeat: %s: node %u is damaged: %s; fewer than 2 good nodes before it: refused (counters: %s)\n", path,
                 r.first_bad_node, r.why.message(), counter_text(reader.counters()).c_str());
    return false;
  }
  if (!drivers::route_store::usable(r.outcome)) {
    std::fprintf(stderr, "qnav route repeat: %s: %s\n", path, r.why.message());
    return false;
  }
  if (r.cut_off || r.torn_bytes > 0) report_route_end(stderr, prefix, reader);  // still usable: a warning
  if (r.outcome == RepeatOpen::kGoodPrefix)
    std::fprintf(stderr,
                 "%snode %u is damaged: %s; repeating on the good prefix, nodes 0..%u (%u later nodes not used; counters: %s nodes_unused=%u)\n",
                 prefix, r.first_bad_node, r.why.message(), r.first_bad_node - 1, r.file_nodes - r.first_bad_node,
                 counter_text(reader.counters()).c_str(), r.file_nodes - r.first_bad_node);
  return true;
}


int cmd_train() {
  const char* out = g_opt.out.c_str();
  const double length_m = g_opt.length_m;
  const long seed = g_opt.seed;
  if (const char* file = opt_or_null(g_opt.sonar)) return cmd_train_file(file);
  if (!g_opt.sim) {
    std::fprintf(stderr, "qnav route train: give --sim or --sonar FILE (XTF or JSF)\n");
    return 2;
  }
  pipeline::SimSurvey w;
  pipeline::RouteTilePipeline pipe;
  Status s = w.init(length_m, static_cast<std::uint64_t>(seed));
  if (s) s = pipe.init(pipeline::default_route_tile_config());
  if (!s) {
    std::fprintf(stderr, "qnav route train: %s\n", s.message());
    return 1;
  }
  const auto& tc = pipe.config();
  const double spacing = pipeline::tile_stride_m(tc, w.route.speed_mps, w.route.ping_rate_hz);
  tools::RouteFileWriter writer;
  if (!begin_route(writer, "train", out, pipeline::side_scan_route_params(tc, spacing, w.swath_m), g_opt.force)) return 1;
  const auto t0 = Clock::now();
  std::size_t kps = 0;
  Status ws;
  const sidescan::TrajectoryConfig tc0 = w.pass(0.0, false, pipeline::teach_pass_seed(static_cast<std::uint64_t>(seed)));
  s = pipe.run_sim_pass(w.seabed, w.sonar_for(tc0.seed), tc0, [&](const pipeline::RouteTile& t) {
    ws = writer.append(t.node);
    kps += t.node.keypoints.size();
    return ws.is_ok();
  });
  if (s && !ws) s = ws;
  if (!finish_route(writer, "train", out, s)) return 1;
  std::printf("route %s: %u nodes, spacing %.1f m, swath %.1f m, %.1f keypoints/node, trained in %.1f s (fsync per node)\n", out,
              writer.node_count(), spacing, w.swath_m, writer.node_count() ? static_cast<double>(kps) / writer.node_count() : 0.0,
              ms_since(t0) / 1000.0);
  return 0;
}

int cmd_info() {
  const char* path = g_opt.info_file.c_str();
  if (const std::string e = qnav::cli::input_file_problem(path); !e.empty()) {
    std::fprintf(stderr, "qnav route info: %s\n", e.c_str());
    return 1;
  }
  tools::RouteFileReader r;
  const Status s = r.open(path);
  if (!s) {
    std::fprintf(stderr, "qnav route info: %s: %s\n", path, s.message());
    return 1;
  }
  const route::RouteParams& p = r.params();
  std::printf("route %s: sensor %s, %u nodes, spacing %.2f m, tile %.1f x %.1f m, pixel %.2f m, depth %.1f m, <= %u keypoints/node\n", path,
              route::to_string(p.sensor), r.node_count(), static_cast<double>(p.node_spacing_m), static_cast<double>(p.tile_length_m),
              static_cast<double>(p.tile_width_m), static_cast<double>(p.pixel_m), static_cast<double>(p.depth_m), p.max_keypoints);
  report_route_end(stdout, "", r);
  // Every record checked in full (CRC, magic, index, every field and keypoint); every damaged one named.
  std::uint32_t damaged = 0, first_bad = r.node_count();
  std::vector<route::NodeMeta> meta(r.node_count());
  for (std::uint32_t i = 0; i < r.node_count(); ++i) {
    const Status ms = r.load_meta(i, meta[i]);
    if (ms) continue;
    std::printf("DAMAGED: node %u: %s\n", i, ms.message());
    first_bad = std::min(first_bad, i);
    ++damaged;
  }
  if (damaged > 0) {
    std::printf("%u of %u nodes damaged (counters: %s); ", damaged, r.node_count(), counter_text(r.counters()).c_str());
    if (first_bad >= 2)
      std::printf("route repeat uses the good prefix, nodes 0..%u\n", first_bad - 1);
    else
      std::printf("fewer than 2 good nodes before node %u: route repeat refuses this route\n", first_bad);
    std::fflush(stdout);
    std::fprintf(stderr, "qnav route info: %s: %u of %u nodes damaged (the first: node %u)\n", path, damaged, r.node_count(), first_bad);
    return 1;
  }
  std::printf("all %u records pass their CRC and field checks\n", r.node_count());
  const bool exp_ok = print_route_experiences(path, r);
  // The spacing the localiser's motion model divides odometry by, from the nodes just read.
  if (meta.size() >= 2)
    std::printf("node spacing flown: %.2f m (dead-reckoned, first to last node; the header's nominal %.2f m)\n",
                route::odometry_node_spacing_m(p, Span<const route::NodeMeta>(meta.data(), meta.size())),
                static_cast<double>(p.node_spacing_m));
  return exp_ok ? 0 : 1;
}

// The per-tile CSV of `route repeat`: --csv FILE or stdout, header written. nullptr (reported) if FILE
// cannot be opened; close with close_csv.
FILE* open_repeat_csv() {
  const char* csv = opt_or_null(g_opt.csv);
  if (csv != nullptr) {
    const std::string e = qnav::cli::make_parent_dirs(csv);
    if (!e.empty()) {
      std::fprintf(stderr, "qnav route repeat: %s\n", e.c_str());
      return nullptr;
    }
  }
  FILE* f = csv ? std::fopen(csv, "w") : stdout;
  if (f == nullptr) {
    std::fprintf(stderr, "qnav route repeat: cannot write %s: %s\n", csv, std::strerror(errno));
    return nullptr;
  }
  std::fprintf(f, "tile,true_node,estimate,probability,entropy,confident,inliers,status,side,true_side,cross_track_m,along_track_m,heading_error_rad,"
                 "waypoint_bearing_rad,cross_track_sigma_m,offsets,ping_first,ping_last\n");
  return f;
}

// One row of that CSV (true_node -1 and true_side "unknown" when there is no truth); ping_first /
// ping_last: the recorded pings (file index, or the simulated pass's ping number) the tile was built from.
void write_repeat_row(FILE* f, long tile, int true_node, const route::LocaliserStep& st, const char* true_side, long ping_first, long ping_last) {
  const route::GuidanceOutput& g = st.guidance;
  std::fprintf(f, "%ld,%d,%u,%.4f,%.4f,%d,%u,%s,%s,%s,%.2f,%.2f,%.4f,%.4f,%.2f,%s,%ld,%ld\n", tile, true_node, st.estimate, static_cast<double>(st.probability),
               st.entropy, st.confident ? 1 : 0, st.best_inliers, route::to_string(g.status), route::to_string(g.side), true_side, g.cross_track_m,
               g.along_track_m, g.heading_error_rad, g.waypoint_bearing_rad, g.cross_track_sigma_m, route::to_string(g.offsets), ping_first, ping_last);
}

// false (reported) if the data did not reach the file (disk full, I/O error).
bool close_csv(FILE* f) {
  const bool had_error = std::ferror(f) != 0;
  const bool closed = f == stdout ? std::fflush(f) == 0 : std::fclose(f) == 0;
  const bool ok = !had_error && closed;
  if (!ok) std::fprintf(stderr, "qnav route repeat: writing the CSV failed\n");
  return ok;
}

// Nearest trained node (by true along-route distance) to a sensed tile.
int true_node(const std::vector<double>& node_truth_along, double along) {
  int best = -1;
  double bd = 1e300;
  for (std::size_t i = 0; i < node_truth_along.size(); ++i) {
    const double d = std::abs(node_truth_along[i] - along);
    if (d < bd) {
      bd = d;
      best = static_cast<int>(i);
    }
  }
  return best;
}

route::RouteSide expected_side(double lateral_m, bool reverse, double deadband) {
  if (std::abs(lateral_m) <= deadband) return route::RouteSide::kOnRoute;
  const bool right_of_forward = lateral_m > 0;
  return (right_of_forward != reverse) ? route::RouteSide::kStarboard : route::RouteSide::kPort;
}

int cmd_repeat() {
  const char* path = g_opt.route.c_str();
  const double offset_pct = g_opt.offset_pct, length_m = g_opt.length_m;
  const long seed = g_opt.seed;
  if (g_opt.learn && g_opt.no_experiences) return usage("repeat", "--learn and --no-experiences contradict each other");
  if (g_opt.learn && !g_opt.sonar.empty()) return usage("repeat", "--learn works with --sim only (recorded passes: not yet)");
  if (const char* file = opt_or_null(g_opt.sonar)) return cmd_repeat_file(file);
  if (!g_opt.sim) {
    std::fprintf(stderr, "qnav route repeat: give --sim or --sonar FILE (XTF or JSF)\n");
    return 2;
  }
  tools::RouteFileReader reader;
  std::vector<route::NodeMeta> meta;
  if (!open_route_for_repeat(path, reader, meta)) return 1;
  const bool reverse = g_opt.reverse;
  pipeline::SimSurvey w;
  pipeline::RouteTilePipeline pipe;
  Status s = w.init(length_m, static_cast<std::uint64_t>(seed));
  if (s) s = pipe.init(pipeline::default_route_tile_config());
  const route::LocaliserConfig lc =
      pipeline::default_localiser_config(reverse ? route::RouteDirection::kReverse : route::RouteDirection::kForward, meta.size() + 8);
  pipeline::RouteRepeatSession session(hal::host_file_store());
  if (s) s = session.init(repeat_session_config(lc, meta.size()));
  if (s) s = session.start(reader.params(), Span<const route::NodeMeta>(meta.data(), meta.size()), reader, reverse);
  if (!s) {
    std::fprintf(stderr, "qnav route repeat: %s\n", s.message());
    return 1;
  }
  if (!open_repeat_experiences(path, session)) return 1;
  // Node truth: trained on the route at zero offset, node i's tile centre is at along_m (nav) ~ truth.
  std::vector<double> node_along;
  for (const route::NodeMeta& m : meta) node_along.push_back(m.along_m);
  FILE* f = open_repeat_csv();
  if (f == nullptr) return 1;
  const bool csv = f != stdout;
  const double lateral = offset_pct / 100.0 * w.swath_m;
  int tiles = 0, ok1 = 0;
  double worst_ms = 0.0;
  const bool diag = std::getenv("QNAV_ROUTE_DIAG") != nullptr;
  ArenaStorage diag_arena(route::Registrar::arena_bytes(lc.registration));
  auto diag_reg = std::make_unique<route::Registrar>();
  if (diag) diag_reg->init(lc.registration, diag_arena).ignore();
  const long dump = g_opt.dump_tile;
  const sidescan::TrajectoryConfig tcr = w.pass(lateral, reverse, pipeline::repeat_pass_seed(static_cast<std::uint64_t>(seed)));
  Status step_status;
  s = pipe.run_sim_pass(w.seabed, w.sonar_for(tcr.seed), tcr, [&](const pipeline::RouteTile& t) {
    if (tiles == dump) {  // debug: the tile raster and its keypoints
      const sonar::SonarTile& raw = pipe.last_tile();
      tools::write_png_gray8("route_dump_tile.png", raw.intensity_u8).ignore();
      if (FILE* kf = std::fopen("route_dump_keypoints.csv", "w")) {
        std::fprintf(kf, "x_m,y_m,score,col,row\n");
        for (const route::RouteKeypoint& k : t.node.keypoints) {
          const Vec2d ne = t.node.meta.pose.apply(Vec2d(k.x_m, k.y_m));
          const Vec2d px = raw.ne_to_pixel(ne.x(), ne.y());
          std::fprintf(kf, "%.2f,%.2f,%.3f,%.1f,%.1f\n", static_cast<double>(k.x_m), static_cast<double>(k.y_m), static_cast<double>(k.score), px.x(), px.y());
        }
        std::fclose(kf);
      }
    }
    if (diag) {  // debug: registration against the true node
      route::RouteNode ref;
      route::RegistrationResult rr;
      const int tn0 = true_node(node_along, t.truth_along_m);
      if (tn0 >= 0 && reader.load(static_cast<std::uint32_t>(tn0), ref) && diag_reg->register_tile(t.node, ref, rr))
        std::fprintf(stderr, "diag tile %d node %d: kp %zu/%zu matches %u inliers %u ok %d T=(%.2f, %.2f, %.3f) rms %.2f\n", tiles, tn0,
                     t.node.keypoints.size(), ref.keypoints.size(), rr.matches, rr.inliers, rr.ok ? 1 : 0, rr.sensed_to_node.x_m,
                     rr.sensed_to_node.y_m, rr.sensed_to_node.heading_rad, rr.rms_m);
      if (rr.ok && std::getenv("QNAV_ROUTE_DIAG")[0] == '2')
        for (std::size_t i = 0; i < rr.inliers; ++i) {
          Vec2d a, b;
          if (diag_reg->last_inlier(i, a, b)) std::fprintf(stderr, "   inlier (%.1f, %.1f) -> (%.1f, %.1f)\n", a.x(), a.y(), b.x(), b.y());
        }
    }
    route::LocaliserStep st;
    const auto t0 = Clock::now();
    const pipeline::RepeatTileResult r = session.step(t, false, st);
    worst_ms = std::max(worst_ms, ms_since(t0));
    step_status = r.step ? r.learn : r.step;
    if (!step_status) return false;  // reported below: the pass stops, the command fails
    const double along_fwd = t.truth_along_m;
    const int tn = true_node(node_along, along_fwd);
    ok1 += std::abs(static_cast<int>(st.estimate) - tn) <= 1;
    write_repeat_row(f, tiles, tn, st, route::to_string(expected_side(lateral, reverse, lc.guidance.side_deadband_m)), t.ping_first, t.ping_last);
    pipe.set_next_stride_m(session.next_stride_m(st, pipe.config().tiles.tile_stride_m));
    ++tiles;
    return true;
  });
  const bool written = close_csv(f);
  session.end();
  if (s && !step_status) s = step_status;
  if (s && !written) return 1;
  if (!s) {
    std::fprintf(stderr, "qnav route repeat: %s\n", s.message());
    return 1;
  }
  std::fprintf(csv ? stdout : stderr, "repeat %s offset %.0f%% of swath (%.1f m)%s: %d tiles, estimate within +/-1 node on %d (%.1f%%), worst update %.1f ms\n",
               path, offset_pct, lateral, reverse ? " reverse" : "", tiles, ok1, tiles ? 100.0 * ok1 / tiles : 0.0, worst_ms);
  report_learned(csv ? stdout : stderr, session.experiences());
  return 0;
}


}  // namespace route_cmd

namespace {
using namespace route_cmd;
// The options a recorded pass (--sonar / --xtf FILE) is cut into tiles with (open_file_pass).
void add_file_pass_options(CLI::App& c) {
  qnav::cli::add_text(c, "--nav", g_opt.nav, "navigation of a recorded pass: the position fixes, or dead reckoning", {"fix", "dr"});
  qnav::cli::add_number(c, "--tile-length-m", g_opt.tile_length_m, "along-track length of a tile of a recorded pass (0: 0.9 x the swath)", "m", 0,
                        5000);
  qnav::cli::add_number(c, "--tile-stride-m", g_opt.tile_stride_m, "a tile every this much travel on a recorded pass (0: 0.6 x the swath)", "m", 0,
                        5000);
  qnav::cli::add_number(c, "--lines", g_opt.lines, "frame tiles by ping count instead: pings per tile of a recorded pass (0: by distance)", "pings", 0,
                        2000);
  qnav::cli::add_number(c, "--stride", g_opt.stride, "with --lines: a tile every N pings (<= --lines; 0: --lines / 2)", "pings", 0, 2000);
  qnav::cli::add_number(c, "--heading-offset-deg", g_opt.heading_offset_deg, "added to the recorded compass heading", "deg", -360, 360);
}

void setup_route(CLI::App& cmd, qnav::cli::Runner& run) {
  using qnav::cli::add_flag;
  using qnav::cli::add_number;
  using qnav::cli::add_text;
  cmd.require_subcommand(1);
  CLI::App* t = cmd.add_subcommand("train", "teach a route (simulated survey with --sim, or a recorded XTF/JSF pass with --sonar FILE)\n"
                                            "into FILE.new, renamed over --out only when complete (the old route survives a kill)");
  add_text(*t, "--out", g_opt.out, "the route file to write")->required()->type_name("FILE");
  add_flag(*t, "--sim", g_opt.sim, "teach on the side-scan simulator's survey");
  add_text(*t, "--sonar", g_opt.sonar, "teach on a recorded pass (XTF or JSF) instead of --sim")->type_name("FILE");
  add_number(*t, "--length-m", g_opt.length_m, "length of the simulated route", "m", 200, 50000);
  add_number(*t, "--seed", g_opt.seed, "seed of the simulated seabed and pass", "", 0, 2147483647);
  add_flag(*t, "--force", g_opt.force, "replace an existing --out (the old route stays until the new one is complete)");
  add_text(*t, "--pings", g_opt.pings, "with --sonar: teach on pings A to B-1 (default: all)")->type_name("A:B");
  add_file_pass_options(*t);
  run.on(t, cmd_train);

  CLI::App* i = cmd.add_subcommand("info", "a route file's header, end (closed / cut off), torn tail and every damaged node; exit 1 if damaged");
  qnav::cli::add_positional(*i, "FILE", g_opt.info_file, "the route file");
  run.on(i, cmd_info);

  CLI::App* r = cmd.add_subcommand("repeat", "follow a taught route (simulated pass with --sim, or a recorded pass with --sonar FILE);\n"
                                             "a CSV row per tile (stdout, or --csv)");
  add_text(*r, "--route", g_opt.route, "the taught route file")->required()->type_name("FILE");
  add_flag(*r, "--sim", g_opt.sim, "repeat on a simulated pass");
  add_text(*r, "--sonar", g_opt.sonar, "repeat on a recorded pass (XTF or JSF) instead of --sim")->type_name("FILE");
  add_number(*r, "--offset-pct", g_opt.offset_pct, "lateral offset of the simulated pass", "% of the swath", -100, 100);
  add_flag(*r, "--reverse", g_opt.reverse, "the pass runs the route backwards");
  add_text(*r, "--csv", g_opt.csv, "write the per-tile CSV here (folders created) instead of stdout")->type_name("FILE");
  add_number(*r, "--seed", g_opt.seed, "seed of the simulated seabed and pass", "", 0, 2147483647);
  add_number(*r, "--length-m", g_opt.length_m, "length of the simulated route (as taught)", "m", 200, 50000);
  add_number(*r, "--dump-tile", g_opt.dump_tile, "debug: write tile N's raster and keypoints (route_dump_*); -1 none", "", -1, 1e9);
  add_text(*r, "--pings", g_opt.pings, "with --sonar: repeat on pings A to B-1 (default: all)")->type_name("A:B");
  add_flag(*r, "--learn", g_opt.learn, "append this pass's confidently localised tiles to the route's experiences (FILE.exp)");
  add_flag(*r, "--no-experiences", g_opt.no_experiences, "ignore FILE.exp (register against the taught nodes only)");
  add_number(*r, "--max-experiences", g_opt.max_experiences, "experiences per node (a new FILE.exp is created with it)", "", 1, 8);
  add_number(*r, "--learn-min-inliers", g_opt.learn_min_inliers, "with --learn: a tile is learnt only when registered with this many inliers", "", 5, 128);
  add_flag(*r, "--backfill", g_opt.backfill, "with --learn: also learn the tiles before each confirmed fix (since the previous one), placed by odometry from it");
  add_file_pass_options(*r);
  run.on(r, cmd_repeat);

  CLI::App* e = cmd.add_subcommand("eval", "the route-following paper's evaluation on the simulator (Table I, Fig. 5/7/9/10 data)");
  add_flag(*e, "--json", g_opt.json, "one JSON summary on stdout (the log on stderr)");
  add_text(*e, "--out", g_opt.eval_out, "folder for the CSV data (created as needed)")->type_name("DIR");
  add_number(*e, "--length-m", g_opt.length_m, "length of each simulated route", "m", 400, 20000);
  add_number(*e, "--seabeds", g_opt.seabeds, "simulated seabeds", "", 1, 20)
      ->description("simulated seabeds (default 3, 1 with --quick; 1..20)");
  add_flag(*e, "--quick", g_opt.quick, "fewer passes and one seabed (a smoke run)");
  add_flag(*e, "--multi-pass", g_opt.multi_pass, "the experiences experiment: learn reverse passes at 30 and 40 % of the swath, then repeat in reverse at 55-65 %");
  add_number(*e, "--max-experiences", g_opt.max_experiences, "with --multi-pass: experiences per node", "", 1, 8);
  add_flag(*e, "--changed-seabed", g_opt.changed_seabed, "the seabed changed since the teach (20/40/60 %): repeats at 20 % without, then after learning one repeat");
  add_number(*e, "--learn-min-inliers", g_opt.learn_min_inliers, "with --multi-pass: a tile is learnt only when registered with this many inliers", "", 5, 128);
  add_flag(*e, "--change-irregular", g_opt.change_irregular, "with --changed-seabed: changed discs of random radius and centre (default: a 12 m lattice of equal discs)");
  add_flag(*e, "--backfill", g_opt.backfill, "with --multi-pass / --changed-seabed: learning passes also learn the tiles before each confirmed fix");
  add_flag(*e, "--no-align", g_opt.no_align, "frame every repeat tile at the configured stride (no framing on the taught nodes)");
  run.on(e, cmd_eval);

  CLI::App* fr = cmd.add_subcommand("framing", "tiles in metres: the simulator at 2, 5 and 15 pings/s and 1.5 / 3 m/s with the default tiles,\n"
                                               "node +/-1 and side against 5 pings/s at 1.5 m/s");
  add_flag(*fr, "--json", g_opt.json, "one JSON summary on stdout (the log on stderr)");
  add_number(*fr, "--length-m", g_opt.framing_length_m, "length of each simulated route", "m", 400, 20000);
  add_flag(*fr, "--quick", g_opt.quick, "one offset (20 %) instead of 0, 20 and 40 % (a smoke run)");
  add_flag(*fr, "--no-align", g_opt.no_align, "frame every repeat tile at the configured stride (no framing on the taught nodes)");
  add_flag(*fr, "--no-speckle", g_opt.no_speckle, "the simulator's pings without speckle (what the sparse ping rates lose)");
  add_flag(*fr, "--no-ripples", g_opt.no_ripples, "the seabed without sand ripples");
  add_number(*fr, "--entry-prior", g_opt.framing_entry_prior,
             "share of the start belief on the route's entry end, as qnavd's route.entry_prior (default 0.5; 0: the uniform start route eval scores)", "", 0, 0.99);
  add_number(*fr, "--seabed", g_opt.framing_seabed, "the simulated seabed (default 1)", "", 1, 1000);
  add_text(*fr, "--only", g_opt.framing_only, "run one configuration (and the 5 pings/s, 1.5 m/s reference), e.g. 2:1.5")->type_name("RATE:SPEED");
  add_flag(*fr, "--trace-sides", g_opt.trace_sides, "a log line per scored tile whose side was decided wrong (registration, inliers, offsets)");
  run.on(fr, cmd_framing);

  CLI::App* x = cmd.add_subcommand("xtf", "real data: teach on pings A..B of a recorded pass, repeat on the shifted window C..D");
  add_text(*x, "--xtf", g_opt.xtf, "the recorded pass (XTF or JSF)")->required()->type_name("FILE");
  add_text(*x, "--train", g_opt.train, "taught pings A to B-1 (default 0:301)")->type_name("A:B");
  add_text(*x, "--repeat", g_opt.repeat, "repeated pings C to D-1 (default 90:461)")->type_name("C:D");
  add_text(*x, "--csv", g_opt.csv, "write a CSV row per repeated tile here (folders created)")->type_name("FILE");
  add_file_pass_options(*x);
  run.on(x, cmd_xtf);

  CLI::App* c = cmd.add_subcommand("camera", "teach and repeat on a downward camera over the synthetic Mars yard (forwards / reverse, 0-40 % offsets)");
  add_flag(*c, "--json", g_opt.json, "one JSON summary on stdout");
  add_number(*c, "--length-m", g_opt.camera_length_m, "length of the route", "m", 2, 200);
  add_number(*c, "--seed", g_opt.camera_seed, "seed of the synthetic yard", "", 0, 2147483647);
  run.on(c, cmd_camera);

  setup_route_follow(cmd, run);
}
}  // namespace

QNAV_CLI_COMMAND("route", "route teach and repeat: train, info, repeat, eval, framing, xtf, camera, follow (route-following paper)", setup_route);
