// qnav route: route teach and repeat (route-following paper) on the side-scan simulator or XTF files.
//   qnav route train  --sim --out FILE [--length-m 2000] [--seed N] [--force] -> route file (durable; taught
//                     under FILE.new, renamed over FILE only when complete: the old route survives a kill)
//   qnav route info   FILE                                                -> header, end (closed cleanly / cut off),
//                     torn tail, every damaged node
//   qnav route repeat --route FILE --sim [--offset-pct P] [--reverse] [--csv OUT] [--seed N] [--length-m M]
//   qnav route eval   [--json] [--out DIR] [--length-m 2000] [--seabeds 3] [--quick] -> Table I, Fig. 5/7/9/10 data
//   qnav route xtf    --xtf FILE [--train A:B] [--repeat C:D] [--csv OUT]  -> real data: teach on pings A..B,
//                     repeat on the shifted window C..D of the same pass
//   qnav route train|repeat --sonar FILE ...                            -> routes from recorded XTF / JSF passes
//   qnav route camera [--json] [--length-m 12] [--seed 7]               -> the same on a downward camera over
//                     the synthetic Mars yard: teach, repeat forwards / reverse at 0-40 % of the footprint
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <sys/stat.h>
#include <time.h>
#include <vector>

#include "firmware/cli/cli_app.hpp"
#include "firmware/qnav/command.hpp"
#include "firmware/tools/png_writer.hpp"
#include "drivers/route_store/route_open.hpp"
#include "firmware/tools/route_file.hpp"
#include "firmware/pipeline/route_defaults.hpp"
#include "firmware/pipeline/route_repeater.hpp"
#include "firmware/pipeline/route_tile_pipeline.hpp"
#include "firmware/pipeline/sim_survey.hpp"
#include "firmware/tools/sonar_file.hpp"
#include "drivers/sidescan/byte_source.hpp"
#include "drivers/sidescan/xtf_reader.hpp"
#include "drivers/stereo_sim/mars_yard.hpp"
#include "nav/route/camera_tile.hpp"
#include "nav/route/route_localiser.hpp"

namespace {

using namespace qnav;
using Clock = std::chrono::steady_clock;

// The options of every route subcommand (one invocation per process), filled by the strict parser
// (setup_route at the end of this file declares them with their units, defaults and ranges).
struct RouteOptions {
  std::string out, route, sonar, csv, xtf, pings, train, repeat, nav = "fix", info_file;
  std::string eval_out = "route_eval";
  double length_m = 2000.0, offset_pct = 0.0, heading_offset_deg = 0.0;
  double camera_length_m = 12.0;
  long seed = 1, camera_seed = 7, dump_tile = -1, seabeds = 0, lines = 100, stride = 50;
  bool sim = false, force = false, reverse = false, json = false, quick = false;
};
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

// An in-memory node source over taught tiles or frames (anything with a .node; eval and the camera
// route) -- the file path is exercised by train/repeat.
template <typename Taught>
class VectorNodeSource final : public route::NodeSource {
 public:
  explicit VectorNodeSource(const std::vector<Taught>* t) : taught_(t) {}
  std::uint32_t node_count() const noexcept override { return static_cast<std::uint32_t>(taught_->size()); }
  Status load(std::uint32_t i, route::RouteNode& out) noexcept override {
    if (i >= taught_->size()) return Status(StatusCode::kOutOfRange, "no such node");
    out = (*taught_)[i].node;
    out.meta.index = i;
    return Status::ok();
  }

 private:
  const std::vector<Taught>* taught_;
};
using TileSource = VectorNodeSource<pipeline::RouteTile>;

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
                 tools::RouteWriterOptions o = tools::RouteWriterOptions{}) {
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
  switch (r.outcome) {
    case RepeatOpen::kMissing:
    case RepeatOpen::kStorage:
    case RepeatOpen::kUnreadable:
    case RepeatOpen::kTooLong:
    case RepeatOpen::kTooShort:
      std::fprintf(stderr, "qnav route repeat: %s: %s\n", path, r.why.message());
      return false;
    case RepeatOpen::kDamaged:
      std::fprintf(stderr, "qnav route repeat: %s: node %u is damaged: %s; fewer than 2 good nodes before it: refused (counters: %s)\n", path,
                   r.first_bad_node, r.why.message(), counter_text(reader.counters()).c_str());
      return false;
    case RepeatOpen::kOk:
    case RepeatOpen::kGoodPrefix:
      break;
  }
  if (r.cut_off || r.torn_bytes > 0) report_route_end(stderr, prefix, reader);  // still usable: a warning
  if (r.outcome == RepeatOpen::kGoodPrefix)
    std::fprintf(stderr,
                 "%snode %u is damaged: %s; repeating on the good prefix, nodes 0..%u (%u later nodes not used; counters: %s nodes_unused=%u)\n",
                 prefix, r.first_bad_node, r.why.message(), r.first_bad_node - 1, r.file_nodes - r.first_bad_node,
                 counter_text(reader.counters()).c_str(), r.file_nodes - r.first_bad_node);
  return true;
}

int cmd_train_file(const char* path);
int cmd_repeat_file(const char* path);

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
  const double spacing = tc.tiles.scanline_stride * w.route.speed_mps / w.route.ping_rate_hz;
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
  // The spacing the localiser's motion model divides odometry by, from the nodes just read.
  if (meta.size() >= 2)
    std::printf("node spacing flown: %.2f m (dead-reckoned, first to last node; the header's nominal %.2f m)\n",
                route::odometry_node_spacing_m(p, Span<const route::NodeMeta>(meta.data(), meta.size())),
                static_cast<double>(p.node_spacing_m));
  return 0;
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
                 "waypoint_bearing_rad,cross_track_sigma_m,offsets\n");
  return f;
}

// One row of that CSV (true_node -1 and true_side "unknown" when there is no truth).
void write_repeat_row(FILE* f, long tile, int true_node, const route::LocaliserStep& st, const char* true_side) {
  const route::GuidanceOutput& g = st.guidance;
  std::fprintf(f, "%ld,%d,%u,%.4f,%.4f,%d,%u,%s,%s,%s,%.2f,%.2f,%.4f,%.4f,%.2f,%s\n", tile, true_node, st.estimate, static_cast<double>(st.probability),
               st.entropy, st.confident ? 1 : 0, st.best_inliers, route::to_string(g.status), route::to_string(g.side), true_side, g.cross_track_m,
               g.along_track_m, g.heading_error_rad, g.waypoint_bearing_rad, g.cross_track_sigma_m, route::to_string(g.offsets));
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
  route::LocaliserConfig lc = pipeline::default_localiser_config(reverse ? route::RouteDirection::kReverse : route::RouteDirection::kForward, meta.size() + 8);
  auto loc = std::make_unique<pipeline::RouteRepeater>();
  if (s) s = loc->init(lc);
  if (s) s = loc->start(reader.params(), Span<const route::NodeMeta>(meta.data(), meta.size()), reader);
  if (!s) {
    std::fprintf(stderr, "qnav route repeat: %s\n", s.message());
    return 1;
  }
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
    step_status = loc->step(t.node, tiles == 0 ? 0.0 : t.nav_step_m, st);
    worst_ms = std::max(worst_ms, ms_since(t0));
    if (!step_status) return false;  // reported below: the pass stops, the command fails
    const double along_fwd = t.truth_along_m;
    const int tn = true_node(node_along, along_fwd);
    ok1 += std::abs(static_cast<int>(st.estimate) - tn) <= 1;
    write_repeat_row(f, tiles, tn, st, route::to_string(expected_side(lateral, reverse, lc.guidance.side_deadband_m)));
    ++tiles;
    return true;
  });
  const bool written = close_csv(f);
  if (s && !step_status) s = step_status;
  if (s && !written) return 1;
  if (!s) {
    std::fprintf(stderr, "qnav route repeat: %s\n", s.message());
    return 1;
  }
  std::fprintf(csv ? stdout : stderr, "repeat %s offset %.0f%% of swath (%.1f m)%s: %d tiles, estimate within +/-1 node on %d (%.1f%%), worst update %.1f ms\n",
               path, offset_pct, lateral, reverse ? " reverse" : "", tiles, ok1, tiles ? 100.0 * ok1 / tiles : 0.0, worst_ms);
  return 0;
}

int cmd_eval();
int cmd_xtf();
int cmd_camera();

}  // namespace


// ---------------------------------------------------------------------------------------------------
// qnav route eval
namespace {

struct TileRecord {
  int seabed = 1;
  int pct = 0;
  bool reverse = false;
  int tile = 0;
  int truth = -1;
  route::LocaliserStep st;
  route::RouteSide want = route::RouteSide::kOnRoute;
  double true_cross_track_m = 0.0;  // the pass's offset, signed like GuidanceOutput::cross_track_m (exact on straight legs)
};

struct PassStats {
  int seabed = 1;
  int pct = 0;
  bool reverse = false;
  double lateral_m = 0.0;
  int tiles = 0, scored = 0, within1 = 0, side_n = 0, side_ok = 0, tracking = 0;
  int off_route = 0;  // scored tiles whose true side is port or starboard
  int dead_reckoned = 0;  // scored tiles steered on dead reckoning from the last fix
  double mean_entropy = 0.0;
  int reg_true_ok = 0;               // tiles that register (S > chance) on their true node
  double reg_true_mean_inliers = 0.0;
  int reg_false_ok = 0;              // tiles that register on a node 3+ away (chance consensus)
  int reg_true_right = 0;            // ... of reg_true_ok, with the transform right (simulator truth)
  double repeated_keypoints = 0.0;   // mean per tile: sensed keypoints with a node keypoint on the same spot
};

constexpr int kWarmupTiles = 2;  // tiles before scoring (uniform start; the paper's first tile copies eq. 9)

Status run_localiser(pipeline::RouteRepeater& loc, const std::vector<pipeline::RouteTile>& tiles, const std::vector<double>& node_along,
                     int pct, bool reverse, double lateral, double deadband, std::vector<TileRecord>* records, PassStats& ps,
                     std::vector<double>* step_ms, std::vector<double>* step_cpu_ms = nullptr) {
  ps.pct = pct;
  ps.reverse = reverse;
  ps.lateral_m = lateral;
  for (std::size_t k = 0; k < tiles.size(); ++k) {
    TileRecord r;
    r.pct = pct;
    r.reverse = reverse;
    r.tile = static_cast<int>(k);
    const auto t0 = Clock::now();
    const double c0 = cpu_ms();
    QNAV_RETURN_IF_ERROR(loc.step(tiles[k].node, k == 0 ? 0.0 : tiles[k].nav_step_m, r.st));
    if (step_cpu_ms) step_cpu_ms->push_back(cpu_ms() - c0);
    if (step_ms) step_ms->push_back(ms_since(t0));
    r.truth = true_node(node_along, tiles[k].truth_along_m);
    r.want = expected_side(lateral, reverse, deadband);
    r.true_cross_track_m = reverse ? -lateral : lateral;
    ++ps.tiles;
    ps.mean_entropy += r.st.entropy;
    if (static_cast<int>(k) >= kWarmupTiles) {
      ++ps.scored;
      ps.within1 += std::abs(static_cast<int>(r.st.estimate) - r.truth) <= 1;
      ps.off_route += r.want != route::RouteSide::kOnRoute;
      ps.tracking += r.st.guidance.status == route::GuidanceStatus::kTracking;
      ps.dead_reckoned += r.st.guidance.status == route::GuidanceStatus::kDeadReckoned;
      if (r.want != route::RouteSide::kOnRoute && r.st.guidance.side != route::RouteSide::kUnknown) {  // a side was given
        ++ps.side_n;
        ps.side_ok += r.st.guidance.side == r.want;
      }
    }
    if (records) records->push_back(r);
  }
  if (ps.tiles) ps.mean_entropy /= ps.tiles;
  return Status::ok();
}

// Registration alone, without the filter: each tile against its true node and against a node three
// away (a chance consensus there is what the measurement floor must absorb). With the simulator's
// true poses also: keypoints that repeat (a node keypoint within 1.5 m of the same seabed spot) and
// whether the registered transform is right (tile origin within 5 m of where the truth puts it).
void registration_at_truth(const route::RegistrationConfig& rc, const std::vector<pipeline::RouteTile>& train, const std::vector<pipeline::RouteTile>& tiles,
                           const std::vector<double>& node_along, PassStats& ps) {
  ArenaStorage arena(route::Registrar::arena_bytes(rc));
  auto reg = std::make_unique<route::Registrar>();
  if (!reg->init(rc, arena)) return;
  const int n = static_cast<int>(train.size());
  const double chance = static_cast<double>(rc.robust.min_inliers);
  double sum = 0.0, rep = 0.0;
  for (const pipeline::RouteTile& t : tiles) {
    const int tn = true_node(node_along, t.truth_along_m);
    if (tn < 0 || tn >= n) continue;
    const pipeline::RouteTile& node = train[static_cast<std::size_t>(tn)];
    route::RegistrationResult r;
    if (reg->register_tile(t.node, node.node, r)) {
      sum += r.inliers;
      ps.reg_true_ok += r.ok && r.inliers > chance;
      if (r.ok && r.inliers > chance && t.has_truth_pose && node.has_truth_pose) {
        const Vec2d truth = node.truth_pose.inverse().apply(t.truth_pose.translation());
        ps.reg_true_right += (r.sensed_to_node.translation() - truth).norm() < 5.0;
      }
    }
    if (t.has_truth_pose && node.has_truth_pose)
      for (const route::RouteKeypoint& a : t.node.keypoints) {
        const Vec2d wa = t.truth_pose.apply(Vec2d(a.x_m, a.y_m));
        for (const route::RouteKeypoint& b : node.node.keypoints)
          if ((node.truth_pose.apply(Vec2d(b.x_m, b.y_m)) - wa).norm() < 1.5) {
            rep += 1.0;
            break;
          }
      }
    const int far = tn + 3 < n ? tn + 3 : tn - 3;
    if (far >= 0 && reg->register_tile(t.node, train[static_cast<std::size_t>(far)].node, r)) ps.reg_false_ok += r.ok && r.inliers > chance;
  }
  ps.reg_true_mean_inliers = tiles.empty() ? 0.0 : sum / static_cast<double>(tiles.size());
  ps.repeated_keypoints = tiles.empty() ? 0.0 : rep / static_cast<double>(tiles.size());
}

struct SweepInputs {
  pipeline::RouteTilePipeline* pipe;
  const pipeline::SimSurvey* world;
  const std::vector<pipeline::RouteTile>* train;
  route::NodeSource* source;
  const route::RouteParams* params;
  Span<const route::NodeMeta> meta;
  const std::vector<double>* node_along;
  const std::vector<int>* pcts;
  int seabed;
  FILE* log;
};

// Repeat passes at every offset, forwards and in reverse, over one taught route. kidnap_src (if
// given) receives the 20% forward pass's tiles; eq5_within the paper's motion model on that pass.
Status offset_sweep(const SweepInputs& in, int& pass_seed, std::vector<TileRecord>& records, std::vector<PassStats>& stats,
                    std::vector<pipeline::RouteTile>* kidnap_src, double* eq5_within) {
  std::vector<pipeline::RouteTile> tiles;
  const std::size_t nodes = in.meta.size();
  for (int pct : *in.pcts) {
    for (bool rev : {false, true}) {
      const double lateral = pct / 100.0 * in.world->swath_m;
      const auto t0 = Clock::now();
      QNAV_RETURN_IF_ERROR(fly(*in.pipe, *in.world, in.world->pass(lateral, rev, static_cast<std::uint64_t>(++pass_seed)), tiles));
      route::LocaliserConfig lc = pipeline::default_localiser_config(rev ? route::RouteDirection::kReverse : route::RouteDirection::kForward, nodes);
      auto loc = std::make_unique<pipeline::RouteRepeater>();
      QNAV_RETURN_IF_ERROR(loc->init(lc));
      QNAV_RETURN_IF_ERROR(loc->start(*in.params, in.meta, *in.source));
      PassStats ps;
      ps.seabed = in.seabed;
      std::vector<TileRecord> rec;
      QNAV_RETURN_IF_ERROR(run_localiser(*loc, tiles, *in.node_along, pct, rev, lateral, lc.guidance.side_deadband_m, &rec, ps, nullptr));
      for (TileRecord& r : rec) {
        r.seabed = in.seabed;
        records.push_back(r);
      }
      registration_at_truth(lc.registration, *in.train, tiles, *in.node_along, ps);
      stats.push_back(ps);
      std::fprintf(in.log, "  seabed %d offset %2d%% (%5.1f m) %-7s: %3d tiles, node +/-1 %5.1f%%, side correct %d/%d, tracking %d/%d; registration alone: on the true node %d/%d (transform right %d, mean S %.1f, repeated keypoints %.1f), on a node 3 away %d (%.1f s)\n",
                   in.seabed, pct, lateral, rev ? "reverse" : "forward", ps.tiles, ps.scored ? 100.0 * ps.within1 / ps.scored : 0.0, ps.side_ok, ps.side_n,
                   ps.tracking, ps.scored, ps.reg_true_ok, ps.tiles, ps.reg_true_right, ps.reg_true_mean_inliers, ps.repeated_keypoints, ps.reg_false_ok,
                   ms_since(t0) / 1000.0);
      if (pct == 20 && !rev && kidnap_src != nullptr) *kidnap_src = tiles;
      if (pct == 20 && !rev && eq5_within != nullptr) {
        // The paper's motion model (eq. 5) on the same tiles, for comparison.
        route::LocaliserConfig lc5 = lc;
        lc5.filter.motion = route::MotionModel::kPaperEq5;
        auto l5 = std::make_unique<pipeline::RouteRepeater>();
        PassStats p5;
        if (l5->init(lc5) && l5->start(*in.params, in.meta, *in.source) &&
            run_localiser(*l5, tiles, *in.node_along, pct, rev, lateral, lc.guidance.side_deadband_m, nullptr, p5, nullptr))
          *eq5_within = p5.scored ? 100.0 * p5.within1 / p5.scored : 0.0;
      }
    }
  }
  if (kidnap_src != nullptr && kidnap_src->empty()) *kidnap_src = tiles;
  return Status::ok();
}

bool ensure_dir(const std::string& d) {
  struct stat st {};
  if (::stat(d.c_str(), &st) == 0) return S_ISDIR(st.st_mode);
  return ::mkdir(d.c_str(), 0755) == 0;
}

}  // namespace

namespace {
int cmd_eval() {
  const double length_m = g_opt.length_m;
  if (!(length_m >= 400.0 && length_m <= 20000.0)) return usage("eval", "--length-m: eval needs 400..20000 m");
  const bool json = g_opt.json;
  const bool quick = g_opt.quick;
  const long seabeds = g_opt.seabeds > 0 ? g_opt.seabeds : quick ? 1 : 3;
  const std::string out_dir = g_opt.eval_out;
  if (const std::string e = qnav::cli::make_dirs(out_dir); !e.empty() || !ensure_dir(out_dir)) {
    std::fprintf(stderr, "qnav route eval: %s\n", e.empty() ? ("cannot create " + out_dir).c_str() : e.c_str());
    return 1;
  }
  FILE* log = json ? stderr : stdout;
  const auto t_all = Clock::now();
  pipeline::SimSurvey w;
  pipeline::RouteTilePipeline pipe;
  Status s = w.init(length_m, 1);
  if (s) s = pipe.init(pipeline::default_route_tile_config());
  if (!s) {
    std::fprintf(stderr, "qnav route eval: %s\n", s.message());
    return 1;
  }
  // 1. Teach: a forward pass on the route, written durably node by node.
  std::vector<pipeline::RouteTile> train;
  auto t0 = Clock::now();
  s = fly(pipe, w, w.pass(0.0, false, 11), train);
  if (!s || train.size() < 2) {
    std::fprintf(stderr, "qnav route eval: training pass failed: %s\n", s ? "fewer than 2 tiles" : s.message());
    return 1;
  }
  const double fly_ms = ms_since(t0);
  const double spacing = (train.back().node.meta.along_m - train.front().node.meta.along_m) / static_cast<double>(train.size() - 1);
  const std::string route_path = out_dir + "/route_eval.qroute";
  tools::RouteFileWriter writer;
  if (!begin_route(writer, "eval", route_path.c_str(), pipeline::side_scan_route_params(pipe.config(), spacing, w.swath_m), true)) return 1;
  t0 = Clock::now();
  for (const pipeline::RouteTile& t : train)
    if (s) s = writer.append(t.node);
  const double append_ms = ms_since(t0) / static_cast<double>(train.size());
  if (!finish_route(writer, "eval", route_path.c_str(), s)) return 1;
  tools::RouteFileReader reader;
  s = reader.open(route_path.c_str());
  std::vector<route::NodeMeta> meta;
  std::uint32_t bad = 0;
  if (s) s = reader.read_all_meta(meta, &bad);
  if (!s) {
    std::fprintf(stderr, "qnav route eval: route file: %s\n", s.message());
    return 1;
  }
  std::vector<double> node_along;
  double kp_mean = 0.0;
  for (const pipeline::RouteTile& t : train) {
    node_along.push_back(t.truth_along_m);
    kp_mean += static_cast<double>(t.node.keypoints.size());
  }
  kp_mean /= static_cast<double>(train.size());
  std::fprintf(log, "taught: %zu nodes over %.0f m (spacing %.1f m, swath %.1f m, %.1f keypoints/node), pass %.1f s, append+fdatasync %.2f ms/node\n",
               train.size(), length_m, spacing, w.swath_m, kp_mean, fly_ms / 1000.0, append_ms);

  // 2. Repeat passes at lateral offsets, forwards and reverse: on this seabed (nodes read from the
  //    route file), then on further seabeds (each taught afresh, nodes in memory).
  std::vector<int> pcts = quick ? std::vector<int>{0, 20, 40} : std::vector<int>{0, 10, 20, 30, 40, 50};
  std::vector<TileRecord> records;
  std::vector<PassStats> stats;
  std::vector<pipeline::RouteTile> kidnap_src;
  const std::size_t nodes = meta.size();
  double eq5_within = -1.0;
  int pass_seed = 100;
  SweepInputs in{&pipe, &w, &train, &reader, &reader.params(), Span<const route::NodeMeta>(meta.data(), meta.size()), &node_along, &pcts, 1, log};
  s = offset_sweep(in, pass_seed, records, stats, &kidnap_src, &eq5_within);
  std::vector<double> seed_within;
  for (long sb = 2; s && sb <= seabeds; ++sb) {
    pipeline::SimSurvey w2;
    std::vector<pipeline::RouteTile> train2;
    s = w2.init(length_m, static_cast<std::uint64_t>(sb));
    if (s) s = fly(pipe, w2, w2.pass(0.0, false, 11 + 1000 * static_cast<std::uint64_t>(sb)), train2);
    if (!s || train2.size() < 2) break;
    const double sp2 = (train2.back().node.meta.along_m - train2.front().node.meta.along_m) / static_cast<double>(train2.size() - 1);
    const route::RouteParams p2 = pipeline::side_scan_route_params(pipe.config(), sp2, w2.swath_m);
    std::vector<route::NodeMeta> meta2;
    std::vector<double> along2;
    for (std::size_t i = 0; i < train2.size(); ++i) {
      meta2.push_back(train2[i].node.meta);
      meta2.back().index = static_cast<std::uint32_t>(i);
      along2.push_back(train2[i].truth_along_m);
    }
    TileSource src2(&train2);
    std::fprintf(log, "seabed %ld: taught %zu nodes (spacing %.1f m)\n", sb, train2.size(), sp2);
    SweepInputs in2{&pipe, &w2, &train2, &src2, &p2, Span<const route::NodeMeta>(meta2.data(), meta2.size()), &along2, &pcts, static_cast<int>(sb), log};
    s = offset_sweep(in2, pass_seed, records, stats, nullptr, nullptr);
  }
  if (!s) {
    std::fprintf(stderr, "qnav route eval: repeat pass failed: %s\n", s.message());
    return 1;
  }
  for (long sb = 1; sb <= seabeds; ++sb) {
    int sc = 0, wi = 0;
    for (const PassStats& p : stats)
      if (p.seabed == sb) {
        sc += p.scored;
        wi += p.within1;
      }
    seed_within.push_back(sc ? 100.0 * wi / sc : 0.0);
  }
  int scored = 0, within = 0, side_n = 0, side_ok = 0, tracking = 0, off_route = 0, dead_reckoned = 0;
  for (const PassStats& p : stats) {
    scored += p.scored;
    within += p.within1;
    tracking += p.tracking;
    dead_reckoned += p.dead_reckoned;
    if (p.pct > 5) {
      side_n += p.side_n;
      side_ok += p.side_ok;
      off_route += p.off_route;
    }
  }

  // 3. Kidnapped vehicle: after 8 tiles the vehicle is moved a third of the route ahead; odometry
  //    does not know. Tiles until the estimate is within +/-1 and stays there for 3 tiles.
  int relocalised = -1;
  {
    const std::size_t jump_from = 8, jump_to = 8 + kidnap_src.size() / 3;
    std::vector<pipeline::RouteTile> seq(kidnap_src.begin(), kidnap_src.begin() + static_cast<long>(std::min(jump_from, kidnap_src.size())));
    for (std::size_t i = jump_to; i < kidnap_src.size(); ++i) seq.push_back(kidnap_src[i]);
    route::LocaliserConfig lc = pipeline::default_localiser_config(route::RouteDirection::kForward, nodes);
    auto loc = std::make_unique<pipeline::RouteRepeater>();
    PassStats ps;
    std::vector<TileRecord> rec;
    if (loc->init(lc) && loc->start(reader.params(), Span<const route::NodeMeta>(meta.data(), meta.size()), reader) &&
        run_localiser(*loc, seq, node_along, 20, false, 0.2 * w.swath_m, lc.guidance.side_deadband_m, &rec, ps, nullptr)) {
      if (std::getenv("QNAV_ROUTE_DIAG"))
        for (const TileRecord& r : rec)
          std::fprintf(stderr, "kidnap tile %d truth %d est %u p %.2f inliers %u conf %d\n", r.tile, r.truth, r.st.estimate,
                       static_cast<double>(r.st.probability), r.st.best_inliers, r.st.confident ? 1 : 0);
      for (std::size_t k = jump_from; k + 2 < rec.size(); ++k) {
        bool ok = true;
        for (std::size_t j = k; j < k + 3; ++j) ok = ok && std::abs(static_cast<int>(rec[j].st.estimate) - rec[j].truth) <= 1;
        if (ok) {
          relocalised = static_cast<int>(k - jump_from) + 1;
          break;
        }
      }
    }
    std::fprintf(log, "kidnapped after tile %zu (moved %zu tiles ahead): re-localised after %d tiles\n", jump_from, jump_to - jump_from, relocalised);
  }

  // 4. Speed on a 10,000-node route read from a file through the node window.
  double upd_mean = -1, upd_p95 = -1, upd_max = -1, upd_cpu_mean = -1, upd_cpu_max = -1, window_mb = 0.0;
  {
    const std::string big = out_dir + "/route_10000.qroute";
    tools::RouteFileWriter bw;
    tools::RouteWriterOptions o;
    o.sync_each_node = false;
    Status bs = begin_route(bw, "eval", big.c_str(), pipeline::side_scan_route_params(pipe.config(), spacing, w.swath_m), true, o)
                    ? Status::ok()
                    : Status(StatusCode::kIoError, "cannot create the 10,000-node route");
    const double block_m = node_along.back() + spacing;
    for (std::uint32_t i = 0; i < 10000 && bs; ++i) {
      route::RouteNode n = train[i % train.size()].node;
      const double shift = block_m * static_cast<double>(i / train.size());
      n.meta.pose.x_m += shift;
      n.meta.along_m += shift;
      bs = bw.append(n);
    }
    if (!finish_route(bw, "eval", big.c_str(), bs) && bs) bs = Status(StatusCode::kIoError, "10,000-node route not committed");
    tools::RouteFileReader br;
    std::vector<route::NodeMeta> bmeta;
    if (bs) bs = br.open(big.c_str());
    if (bs) bs = br.read_all_meta(bmeta, nullptr);
    route::LocaliserConfig lc = pipeline::default_localiser_config(route::RouteDirection::kForward, 10000);
    auto loc = std::make_unique<pipeline::RouteRepeater>();
    window_mb = static_cast<double>(route::RouteLocaliser::arena_bytes(lc)) / 1e6;
    if (bs) bs = loc->init(lc);
    if (bs) bs = loc->start(br.params(), Span<const route::NodeMeta>(bmeta.data(), bmeta.size()), br);
    std::vector<double> ms, cms;
    PassStats ps;
    std::vector<double> along_big;  // truth unknown on the replicated route: scoring not used
    along_big.push_back(0.0);
    if (bs) bs = run_localiser(*loc, kidnap_src, along_big, 20, false, 0.0, 1.0, nullptr, ps, &ms, &cms);
    if (bs && !ms.empty()) {
      std::sort(ms.begin(), ms.end());
      double sum = 0;
      for (double v : ms) sum += v;
      upd_mean = sum / static_cast<double>(ms.size());
      upd_p95 = ms[static_cast<std::size_t>(0.95 * static_cast<double>(ms.size() - 1))];
      upd_max = ms.back();
      double cs = 0;
      for (double v : cms) cs += v;
      upd_cpu_mean = cs / static_cast<double>(cms.size());
      upd_cpu_max = *std::max_element(cms.begin(), cms.end());
    }
    std::remove(big.c_str());
    std::fprintf(log, "10,000-node route (file, %zu-node window): update wall mean %.2f ms, p95 %.2f ms, max %.2f ms; thread CPU mean %.2f ms, max %.2f ms over %zu tiles; localiser memory %.1f MB\n",
                 lc.window_slots, upd_mean, upd_p95, upd_max, upd_cpu_mean, upd_cpu_max, ms.size(), window_mb);
  }
  // 5. Prediction alone on 100,000 nodes.
  double pred_ms = -1, pred_cpu_ms = -1;
  {
    route::RouteFilterConfig fc;
    fc.max_nodes = 100000;
    ArenaStorage arena(route::RouteFilter::arena_bytes(fc));
    route::RouteFilter f;
    if (f.init(fc, arena) && f.reset(100000, spacing)) {
      const int reps = 200;
      t0 = Clock::now();
      const double c0 = cpu_ms();
      for (int i = 0; i < reps; ++i) f.predict(spacing).ignore();
      pred_cpu_ms = (cpu_ms() - c0) / reps;
      pred_ms = ms_since(t0) / reps;
    }
    std::fprintf(log, "prediction alone, 100,000 nodes: wall %.3f ms, thread CPU %.3f ms\n", pred_ms, pred_cpu_ms);
  }

  // 6. The paper's experiment shape: 15 training nodes, 8 sensed tiles (offset 25% of swath), every
  //    node registered each step (the paper's eq. 8 over the whole database). Table I, Fig. 5, 7, 9, 10.
  int paper_localised = 0, paper_side = 0;
  {
    const std::size_t a = train.size() / 3;
    const std::size_t n15 = std::min<std::size_t>(15, train.size() - a);
    std::vector<pipeline::RouteTile> sub(train.begin() + static_cast<long>(a), train.begin() + static_cast<long>(a + n15));
    std::vector<route::NodeMeta> sub_meta;
    std::vector<double> sub_along;
    for (std::size_t i = 0; i < sub.size(); ++i) {
      route::NodeMeta m = sub[i].node.meta;
      m.index = static_cast<std::uint32_t>(i);
      sub_meta.push_back(m);
      sub_along.push_back(sub[i].truth_along_m);
    }
    const double lateral = 0.25 * w.swath_m;
    std::vector<pipeline::RouteTile> pass;
    s = fly(pipe, w, w.pass(lateral, false, 999), pass);
    std::vector<pipeline::RouteTile> sensed;
    for (const pipeline::RouteTile& t : pass)
      if (t.truth_along_m >= sub_along[std::min<std::size_t>(5, sub_along.size() - 1)] - 0.5 * spacing && sensed.size() < 8) sensed.push_back(t);
    TileSource src(&sub);
    route::LocaliserConfig lc = pipeline::default_localiser_config(route::RouteDirection::kForward, 64);
    lc.filter.belief_registrations = static_cast<std::uint32_t>(sub.size());
    lc.filter.wide_search_registrations = 0;
    auto loc = std::make_unique<pipeline::RouteRepeater>();
    FILE* t1 = std::fopen((out_dir + "/route_table1.csv").c_str(), "w");
    FILE* f5 = std::fopen((out_dir + "/route_fig5.csv").c_str(), "w");
    FILE* f7 = std::fopen((out_dir + "/route_fig7.csv").c_str(), "w");
    FILE* f9 = std::fopen((out_dir + "/route_fig9.csv").c_str(), "w");
    if (s && t1 && f5 && f7 && f9 && loc->init(lc) &&
        loc->start(reader.params(), Span<const route::NodeMeta>(sub_meta.data(), sub_meta.size()), src)) {
      std::fprintf(t1, "sensed,estimate,truth,entropy,side,true_side,inliers\n");
      std::fprintf(f9, "sensed,true_north,true_east,node_north,node_east,cross_track_m,side,true_side,entropy,status\n");
      std::fprintf(log, "paper-shaped run (15 nodes, 8 sensed tiles, offset 25%% = %.1f m):\n  sensed  estimate  truth  entropy  side       true side\n", lateral);
      std::vector<float> mp(sub.size());
      sidescan::Trajectory tr;
      s = tr.init(w.route);
      for (std::size_t k = 0; k < sensed.size() && s; ++k) {
        route::LocaliserStep st;
        s = loc->step(sensed[k].node, k == 0 ? 0.0 : sensed[k].nav_step_m, st);
        if (!s) break;
        const int truth = true_node(sub_along, sensed[k].truth_along_m);
        const route::RouteSide want = expected_side(lateral, false, lc.guidance.side_deadband_m);
        paper_localised += std::abs(static_cast<int>(st.estimate) - truth) <= 0 ? 1 : 0;
        paper_side += st.guidance.side == want;
        std::fprintf(t1, "%zu,%u,%d,%.3f,%s,%s,%u\n", k + 1, st.estimate + 1, truth + 1, st.entropy, route::to_string(st.guidance.side),
                     route::to_string(want), st.best_inliers);
        std::fprintf(log, "  %6zu  %8u  %5d  %7.2f  %-9s  %s\n", k + 1, st.estimate + 1, truth + 1, st.entropy, route::to_string(st.guidance.side),
                     route::to_string(want));
        loc->localiser().filter().measurement_probability(Span<float>(mp.data(), mp.size())).ignore();
        for (std::size_t i = 0; i < sub.size(); ++i) {
          std::fprintf(f5, "%s%.5f", i ? "," : "", static_cast<double>(mp[i]));
          std::fprintf(f7, "%s%.5f", i ? "," : "", static_cast<double>(loc->localiser().filter().belief()[i]));
        }
        std::fprintf(f5, "\n");
        std::fprintf(f7, "\n");
        Vec2d tp, np;
        double th, nh;
        tr.route_at(sensed[k].truth_along_m, tp, th);
        tr.route_at(sub_along[st.estimate], np, nh);
        tp += lateral * sonar::starboard_unit(th);
        std::fprintf(f9, "%zu,%.2f,%.2f,%.2f,%.2f,%.2f,%s,%s,%.3f,%s\n", k + 1, tp.x(), tp.y(), np.x(), np.y(), st.guidance.cross_track_m,
                     route::to_string(st.guidance.side), route::to_string(want), st.entropy, route::to_string(st.guidance.status));
      }
      std::fprintf(log, "  localised (exact node) %d/8, side correct %d/8 (paper: 7/8 and 6/8)\n", paper_localised, paper_side);
    }
    for (FILE* f : {t1, f5, f7, f9})
      if (f) std::fclose(f);
  }

  // CSV outputs for the plots.
  if (FILE* f = std::fopen((out_dir + "/route_eval_offsets.csv").c_str(), "w")) {
    // One row per offset and direction, summed over the seabeds.
    std::fprintf(f, "offset_pct,lateral_m,direction,tiles,scored,within1_pct,side_correct,side_n,tracking_pct,mean_entropy,seabeds,registered_on_true_node_pct\n");
    for (int pct : pcts)
      for (bool rev : {false, true}) {
        PassStats a;
        int n = 0, reg = 0;
        for (const PassStats& p : stats)
          if (p.pct == pct && p.reverse == rev) {
            a.lateral_m = p.lateral_m;
            a.tiles += p.tiles;
            a.scored += p.scored;
            a.within1 += p.within1;
            a.side_ok += p.side_ok;
            a.side_n += p.side_n;
            a.tracking += p.tracking;
            a.mean_entropy += p.mean_entropy;
            reg += p.reg_true_ok;
            ++n;
          }
        if (n == 0) continue;
        std::fprintf(f, "%d,%.2f,%s,%d,%d,%.2f,%d,%d,%.2f,%.4f,%d,%.2f\n", pct, a.lateral_m, rev ? "reverse" : "forward", a.tiles, a.scored,
                     a.scored ? 100.0 * a.within1 / a.scored : 0.0, a.side_ok, a.side_n, a.scored ? 100.0 * a.tracking / a.scored : 0.0,
                     a.mean_entropy / n, n, a.tiles ? 100.0 * reg / a.tiles : 0.0);
      }
    std::fclose(f);
  }
  if (FILE* f = std::fopen((out_dir + "/route_eval_tiles.csv").c_str(), "w")) {
    std::fprintf(f, "offset_pct,direction,tile,true_node,estimate,probability,entropy,confident,inliers,status,side,true_side,cross_track_m,seabed,"
                    "cross_track_sigma_m,offsets,true_cross_track_m\n");
    for (const TileRecord& r : records)
      std::fprintf(f, "%d,%s,%d,%d,%u,%.4f,%.4f,%d,%u,%s,%s,%s,%.2f,%d,%.2f,%s,%.2f\n", r.pct, r.reverse ? "reverse" : "forward", r.tile, r.truth,
                   r.st.estimate, static_cast<double>(r.st.probability), r.st.entropy, r.st.confident ? 1 : 0, r.st.best_inliers,
                   route::to_string(r.st.guidance.status), route::to_string(r.st.guidance.side), route::to_string(r.want), r.st.guidance.cross_track_m,
                   r.seabed, r.st.guidance.cross_track_sigma_m, route::to_string(r.st.guidance.offsets), r.true_cross_track_m);
    std::fclose(f);
  }
  // Is the dead-reckoned cross-track sigma honest? Off-route scored tiles whose offsets came from
  // dead reckoning: the share within 2 sigma of the pass's offset (~95% if sigma is right).
  int dr_n = 0, dr_in = 0;
  for (const TileRecord& r : records)
    if (r.tile >= kWarmupTiles && r.pct > 5 && r.st.guidance.offsets == route::OffsetSource::kDeadReckoning) {
      ++dr_n;
      dr_in += std::abs(r.st.guidance.cross_track_m - r.true_cross_track_m) <= 2.0 * r.st.guidance.cross_track_sigma_m;
    }
  const double within_pct = scored ? 100.0 * within / scored : 0.0;
  const double side_pct = side_n ? 100.0 * side_ok / side_n : 0.0;
  const double tracking_pct = scored ? 100.0 * tracking / scored : 0.0;
  if (json) {
    std::printf("{\"node_within_1_pct\": %.2f, \"side_correct_pct\": %.2f, \"side_decided_tiles\": %d, \"tracking_pct\": %.2f, "
                "\"relocalised_within_tiles\": %d, \"update_ms_10000_nodes\": %.3f, \"update_ms_10000_nodes_p95\": %.3f, "
                "\"update_ms_10000_nodes_max\": %.3f, \"update_cpu_ms_10000_nodes\": %.3f, \"update_cpu_ms_10000_nodes_max\": %.3f, "
                "\"predict_ms_100000_nodes\": %.4f, \"predict_cpu_ms_100000_nodes\": %.4f, \"eq5_node_within_1_pct_at_20pct\": %.2f, "
                "\"paper_table_localised\": %d, \"paper_table_side_correct\": %d, \"scored_tiles\": %d, \"route_nodes\": %zu, "
                "\"route_length_m\": %.0f, \"node_spacing_m\": %.2f, \"swath_m\": %.2f, \"offsets_pct\": [",
                within_pct, side_pct, side_n, tracking_pct, relocalised, upd_mean, upd_p95, upd_max, upd_cpu_mean, upd_cpu_max, pred_ms, pred_cpu_ms, eq5_within, paper_localised,
                paper_side, scored, nodes, length_m, spacing, w.swath_m);
    for (std::size_t i = 0; i < pcts.size(); ++i) std::printf("%s%d", i ? ", " : "", pcts[i]);
    std::printf("], \"side_correct_pct_of_offset_tiles\": %.2f, \"offset_tiles\": %d, \"dead_reckoned_pct\": %.2f, \"seabeds\": %ld, "
                "\"node_within_1_pct_per_seabed\": [",
                off_route ? 100.0 * side_ok / off_route : 0.0, off_route, scored ? 100.0 * dead_reckoned / scored : 0.0, seabeds);
    for (std::size_t i = 0; i < seed_within.size(); ++i) std::printf("%s%.2f", i ? ", " : "", seed_within[i]);
    std::printf("], \"dead_reckoned_offset_tiles\": %d, \"dead_reckoned_cross_track_within_2sigma_pct\": %.2f, \"warmup_tiles\": %d, \"seconds\": %.1f}\n",
                dr_n, dr_n ? 100.0 * dr_in / dr_n : 0.0, kWarmupTiles, ms_since(t_all) / 1000.0);
  } else {
    std::printf("node within +/-1: %.1f%% of %d tiles; side correct %.1f%% of %d decided tiles (tracking %.1f%%); re-localised after %d tiles; "
                "update %.2f ms wall / %.2f ms CPU (10,000 nodes); predict %.3f ms wall / %.3f ms CPU (100,000 nodes); eq. 5 model at 20%%: %.1f%%; %.1f s\n",
                within_pct, scored, side_pct, side_n, tracking_pct, relocalised, upd_mean, upd_cpu_mean, pred_ms, pred_cpu_ms, eq5_within, ms_since(t_all) / 1000.0);
  }
  return 0;
}
}  // namespace

// ---------------------------------------------------------------------------------------------------
// qnav route xtf: real data. Teach on one window of pings of an XTF pass, repeat on a shifted,
// overlapping window of the same pass (the only real data we have is one pass). The tiles of the
// repeat are framed differently (shifted ping boundaries) and carry their own speckle-free copy of
// the same pings, so this checks registration and the filter on real seabed texture, not repeat
// -pass sonar physics.
namespace {

// ---- side-scan files (XTF / JSF) for train, repeat and xtf ----
struct FilePass {
  tools::FileData fd;
  tools::NavTrack track;
  pipeline::RouteTileConfig tiles;
  double swath_m = 0.0;
};

// Loads a file and derives its tile geometry from the median slant range: 300 ground bins per side
// (0.1 m for the Iver2's 30 m), 800 x 800 px rasters at the bin size, --lines pings per tile every
// --stride pings (defaults 100 / 50). Navigation from the fixes (--nav fix) or dead reckoning
// (--nav dr), --heading-offset-deg added to the compass; the bottom is detected in each ping.
int open_file_pass(const char* path, FilePass& out) {
  const double hoff_deg = g_opt.heading_offset_deg;
  const long lines = g_opt.lines, stride = g_opt.stride;
  const char* nav = g_opt.nav.c_str();
  if (stride > lines) {
    std::fprintf(stderr, "qnav route: --stride %ld is more than --lines %ld (a tile every --stride pings of --lines pings)\n", stride, lines);
    return 2;
  }
  if (const std::string e = qnav::cli::input_file_problem(path); !e.empty()) {
    std::fprintf(stderr, "qnav route: %s\n", e.c_str());
    return 1;
  }
  if (tools::load_sonar_file(path, out.fd) != 0) return 1;
  out.track = tools::build_track(out.fd, std::strcmp(nav, "dr") == 0, deg_to_rad(hoff_deg));
  tools::report_track("qnav route", path, out.track);
  std::vector<float> ranges;
  tools::collect_slant_ranges(out.fd, ranges);
  double range = 0.0;
  if (!tools::median_slant_range(ranges, range)) {
    std::fprintf(stderr, "qnav route: %s: no ping with a slant range\n", path);
    return 1;
  }
  out.tiles = pipeline::file_route_tile_config(range, static_cast<int>(lines), static_cast<int>(stride));
  out.swath_m = 2.0 * range;
  return 0;
}

// Tiles of pings [a, b) of a file. centre_ping (optional) receives each tile's centre ping index.
Status file_tiles(pipeline::RouteTilePipeline& pipe, const FilePass& fp, long a, long b, std::vector<pipeline::RouteTile>& out,
                  std::vector<double>* centre_ping) {
  pipe.reset_pass();
  out.clear();
  if (centre_ping) centre_ping->clear();
  bool stop = false;
  const double half = 0.5 * (fp.tiles.tiles.scanlines_per_tile - 1);
  for (long i = a; i < b && !stop; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    if (!fp.track.ok[k]) continue;
    sonar::SonarPing ping = tools::as_ping(fp.fd.pings[k], false);
    ping.ping_number = static_cast<std::uint32_t>(i - a);
    QNAV_RETURN_IF_ERROR(pipe.push_ping(ping, fp.track.pose[k], [&](const pipeline::RouteTile& t) {
      out.push_back(t);
      if (centre_ping) centre_ping->push_back(static_cast<double>(i) - half);  // the tile is the last scanlines_per_tile pings
      return true;
    }, &stop));
  }
  return Status::ok();
}

bool parse_range(const char* s, long& a, long& b) {
  if (s == nullptr) return true;
  char* end = nullptr;
  a = std::strtol(s, &end, 10);
  if (end == s || *end != ':') return false;
  const char* t = end + 1;
  b = std::strtol(t, &end, 10);
  return end != t && *end == '\0' && a >= 0 && b > a;
}

int cmd_xtf() {
  const char* path = g_opt.xtf.c_str();
  long ta = 0, tb = 301, ra = 90, rb = 461;  // ping 0 of the Iver2 file has no fix: 300 taught pings
  if (!parse_range(opt_or_null(g_opt.train), ta, tb)) return usage("xtf", "--train: give A:B, pings A to B-1 with 0 <= A < B");
  if (!parse_range(opt_or_null(g_opt.repeat), ra, rb)) return usage("xtf", "--repeat: give C:D, pings C to D-1 with 0 <= C < D");
  FilePass fp;
  if (const int rc = open_file_pass(path, fp); rc != 0) return rc;
  const long n = static_cast<long>(fp.fd.pings.size());
  if (n < 100) {
    std::fprintf(stderr, "qnav route xtf: %s: only %ld pings\n", path, n);
    return 1;
  }
  tb = std::min<long>(tb, n);
  rb = std::min<long>(rb, n);
  const pipeline::RouteTileConfig& tc = fp.tiles;
  pipeline::RouteTilePipeline pipe;
  Status s = pipe.init(tc);
  if (!s) {
    std::fprintf(stderr, "qnav route xtf: %s\n", s.message());
    return 1;
  }
  std::vector<pipeline::RouteTile> train, rep;
  std::vector<double> train_c, rep_c;
  s = file_tiles(pipe, fp, ta, tb, train, &train_c);
  if (s) s = file_tiles(pipe, fp, ra, rb, rep, &rep_c);
  if (!s || train.size() < 2 || rep.empty()) {
    std::fprintf(stderr, "qnav route xtf: %s (train %zu tiles, repeat %zu tiles)\n", s ? "too few tiles" : s.message(), train.size(), rep.size());
    return 1;
  }
  // The two windows share pings: put the repeat window's nav in the training frame by using the
  // same lat/lon origin (done above); node truth = the training tile whose centre ping is nearest.
  double spacing = 0.0;
  for (std::size_t i = 1; i < train.size(); ++i) spacing += train[i].node.meta.along_m - train[i - 1].node.meta.along_m;
  spacing /= static_cast<double>(train.size() - 1);
  std::vector<route::NodeMeta> meta;
  for (std::size_t i = 0; i < train.size(); ++i) {
    route::NodeMeta m = train[i].node.meta;
    m.index = static_cast<std::uint32_t>(i);
    meta.push_back(m);
  }
  TileSource src(&train);
  route::LocaliserConfig lc = pipeline::file_localiser_config(route::RouteDirection::kForward, 64, train.size(), spacing);
  auto loc = std::make_unique<pipeline::RouteRepeater>();
  route::RouteParams params = pipeline::side_scan_route_params(tc, spacing, fp.swath_m);
  s = loc->init(lc);
  if (s) s = loc->start(params, Span<const route::NodeMeta>(meta.data(), meta.size()), src);
  if (!s) {
    std::fprintf(stderr, "qnav route xtf: %s\n", s.message());
    return 1;
  }
  const char* csv = opt_or_null(g_opt.csv);
  if (csv != nullptr) {
    const std::string e = qnav::cli::make_parent_dirs(csv);
    if (!e.empty()) {
      std::fprintf(stderr, "qnav route xtf: %s\n", e.c_str());
      return 1;
    }
  }
  FILE* f = csv ? std::fopen(csv, "w") : nullptr;
  if (csv != nullptr && f == nullptr) {
    std::fprintf(stderr, "qnav route xtf: cannot write %s: %s\n", csv, std::strerror(errno));
    return 1;
  }
  if (f) std::fprintf(f, "tile,centre_ping,true_node,estimate,probability,entropy,inliers,status,cross_track_m,along_track_m\n");
  double kp = 0.0;
  for (const pipeline::RouteTile& t : train) kp += static_cast<double>(t.node.keypoints.size());
  std::printf("real XTF %s: %ld pings; taught pings %ld..%ld -> %zu nodes (spacing %.1f m, %.0f keypoints/node); repeat pings %ld..%ld -> %zu tiles\n",
              path, n, ta, tb - 1, train.size(), spacing, kp / static_cast<double>(train.size()), ra, rb - 1, rep.size());
  std::printf("  tile  centre ping  true node  estimate  p      entropy  inliers  status       cross-track m  along-track m\n");
  int ok = 0, exact = 0;
  for (std::size_t k = 0; k < rep.size(); ++k) {
    route::LocaliserStep st;
    s = loc->step(rep[k].node, k == 0 ? 0.0 : rep[k].nav_step_m, st);
    if (!s) break;
    int truth = 0;
    for (std::size_t i = 1; i < train_c.size(); ++i)
      if (std::abs(train_c[i] - rep_c[k]) < std::abs(train_c[static_cast<std::size_t>(truth)] - rep_c[k])) truth = static_cast<int>(i);
    const bool near = std::abs(train_c[static_cast<std::size_t>(truth)] - rep_c[k]) <= tc.tiles.scanline_stride;
    ok += near && std::abs(static_cast<int>(st.estimate) - truth) <= 1;
    exact += near && static_cast<int>(st.estimate) == truth;
    std::printf("  %4zu  %11.0f  %9s  %8u  %.3f  %7.3f  %7u  %-11s  %13.2f  %13.2f\n", k, rep_c[k], near ? std::to_string(truth).c_str() : "beyond",
                st.estimate, static_cast<double>(st.probability), st.entropy, st.best_inliers, route::to_string(st.guidance.status),
                st.guidance.cross_track_m, st.guidance.along_track_m);
    if (f)
      std::fprintf(f, "%zu,%.0f,%d,%u,%.4f,%.4f,%u,%s,%.2f,%.2f\n", k, rep_c[k], near ? truth : -1, st.estimate, static_cast<double>(st.probability),
                   st.entropy, st.best_inliers, route::to_string(st.guidance.status), st.guidance.cross_track_m, st.guidance.along_track_m);
  }
  if (f) std::fclose(f);
  std::printf("  estimate within +/-1 node on %d tiles, exact on %d (tiles whose centre is within the taught pings)\n", ok, exact);
  return s ? 0 : 1;
}

// qnav route train --sonar FILE: teach a route on pings [A, B) of a recorded pass. The nodes are
// written durably one by one (fdatasync each) once the pass's node spacing is known.
int cmd_train_file(const char* path) {
  const char* out = g_opt.out.c_str();
  long a = 0, b = std::numeric_limits<long>::max();  // all pings (32-bit long on armhf)
  if (!parse_range(opt_or_null(g_opt.pings), a, b)) return usage("train", "--pings: give A:B, pings A to B-1 with 0 <= A < B");
  FilePass fp;
  if (const int rc = open_file_pass(path, fp); rc != 0) return rc;
  b = std::min<long>(b, static_cast<long>(fp.fd.pings.size()));
  pipeline::RouteTilePipeline pipe;
  std::vector<pipeline::RouteTile> tiles;
  Status s = pipe.init(fp.tiles);
  if (s) s = file_tiles(pipe, fp, a, b, tiles, nullptr);
  if (s && tiles.size() < 2) s = Status(StatusCode::kInvalidArgument, "fewer than 2 tiles in the ping range: a route needs 2 nodes");
  // A node with fewer keypoints than a registration's minimum consensus can never be recognised:
  // a route made only of such nodes (a featureless pass, or pings whose navigation was unusable) is
  // refused rather than written; some of them are reported.
  std::size_t blind = 0;
  const std::size_t min_kp = static_cast<std::size_t>(pipeline::default_localiser_config(route::RouteDirection::kForward, 2).registration.robust.min_inliers);
  for (const pipeline::RouteTile& t : tiles) blind += t.node.keypoints.size() < min_kp ? 1u : 0u;
  if (s && blind == tiles.size())
    s = Status(StatusCode::kInvalidArgument, "no tile holds enough keypoints to be recognised: this pass cannot be a route");
  if (!s) {
    std::fprintf(stderr, "qnav route train: %s: %s\n", path, s.message());
    return 1;
  }
  if (blind > 0)
    std::fprintf(stderr, "qnav route train: %s: WARNING: %zu of %zu nodes hold fewer than %zu keypoints (never recognised)\n", path, blind,
                 tiles.size(), min_kp);
  const double spacing = (tiles.back().node.meta.along_m - tiles.front().node.meta.along_m) / static_cast<double>(tiles.size() - 1);
  tools::RouteFileWriter writer;
  if (!begin_route(writer, "train", out, pipeline::side_scan_route_params(fp.tiles, spacing, fp.swath_m), g_opt.force)) return 1;
  std::size_t kps = 0;
  for (const pipeline::RouteTile& t : tiles) {
    if (!s) break;
    s = writer.append(t.node);
    kps += t.node.keypoints.size();
  }
  if (!finish_route(writer, "train", out, s)) return 1;  // nodes appended before an error stay durable in OUT.new
  std::printf("route %s: %u nodes from %s pings %ld..%ld, spacing %.1f m, swath %.1f m, %.1f keypoints/node (%s)\n", out, writer.node_count(), path,
              a, b - 1, spacing, fp.swath_m, static_cast<double>(kps) / static_cast<double>(tiles.size()), fp.fd.counters.c_str());
  return 0;
}

// qnav route repeat --sonar FILE: localise the tiles of pings [C, D) of a recorded pass on a route.
// No ground truth: the CSV's true_node is -1.
int cmd_repeat_file(const char* path) {
  const char* route_path = g_opt.route.c_str();
  long a = 0, b = std::numeric_limits<long>::max();  // all pings (32-bit long on armhf)
  if (!parse_range(opt_or_null(g_opt.pings), a, b)) return usage("repeat", "--pings: give A:B, pings A to B-1 with 0 <= A < B");
  tools::RouteFileReader reader;
  std::vector<route::NodeMeta> meta;
  if (!open_route_for_repeat(route_path, reader, meta)) return 1;
  FilePass fp;
  if (const int rc = open_file_pass(path, fp); rc != 0) return rc;
  b = std::min<long>(b, static_cast<long>(fp.fd.pings.size()));
  const bool reverse = g_opt.reverse;
  route::LocaliserConfig lc = pipeline::file_localiser_config(reverse ? route::RouteDirection::kReverse : route::RouteDirection::kForward, meta.size() + 8,
                                                    meta.size(), static_cast<double>(reader.params().node_spacing_m));
  auto loc = std::make_unique<pipeline::RouteRepeater>();
  pipeline::RouteTilePipeline pipe;
  std::vector<pipeline::RouteTile> tiles;
  std::vector<double> centre;
  Status s = loc->init(lc);
  if (s) s = loc->start(reader.params(), Span<const route::NodeMeta>(meta.data(), meta.size()), reader);
  if (s) s = pipe.init(fp.tiles);
  if (s) s = file_tiles(pipe, fp, a, b, tiles, &centre);
  if (s && tiles.empty()) s = Status(StatusCode::kInvalidArgument, "no complete tile in the ping range");
  if (!s) {
    std::fprintf(stderr, "qnav route repeat: %s\n", s.message());
    return 1;
  }
  FILE* f = open_repeat_csv();
  if (f == nullptr) return 1;
  const bool csv = f != stdout;
  int tracking = 0;
  for (std::size_t k = 0; k < tiles.size() && s; ++k) {
    route::LocaliserStep st;
    s = loc->step(tiles[k].node, k == 0 ? 0.0 : tiles[k].nav_step_m, st);
    if (!s) break;
    tracking += st.guidance.status == route::GuidanceStatus::kTracking;
    write_repeat_row(f, static_cast<long>(k), -1, st, "unknown");
  }
  const bool written = close_csv(f);
  if (s && !written) return 1;
  if (!s) {
    std::fprintf(stderr, "qnav route repeat: %s\n", s.message());
    return 1;
  }
  std::fprintf(csv ? stdout : stderr, "repeat %s on %s pings %ld..%ld%s: %zu tiles, %d tracking (registered and confident)\n", route_path, path, a,
               b - 1, reverse ? " reverse" : "", tiles.size(), tracking);
  return 0;
}

}  // namespace

// ---------------------------------------------------------------------------------------------------
// qnav route camera: the same route teach and repeat on a downward camera (SensorKind::kCamera).
namespace {

// A downward camera 0.8 m above the synthetic Mars yard (the VO bench's 320x256 camera, f 333 px,
// turned straight down: footprint 0.77 m across x 0.62 m along track), with rover-like attitude wobble.
struct CameraWorld {
  sim::MarsYardTerrain terrain;
  sim::StereoBench bench;
  route::CameraIntrinsics k;
  double altitude_m = 0.8;
  explicit CameraWorld(std::uint64_t seed) : terrain([seed] {
      sim::MarsYardConfig c;
      c.seed = seed;
      return c;
    }()) {
    k.fx_px = k.fy_px = bench.focal_px();
    k.cu_px = bench.cu_px();
    k.cv_px = bench.cv_px();
  }
  double footprint_across_m() const { return bench.width() * altitude_m / bench.focal_px(); }
  double footprint_along_m() const { return bench.height() * altitude_m / bench.focal_px(); }
  // Camera pose in NED for a vehicle at (north, east) with compass heading and small roll / pitch:
  // camera x = starboard, y = aft (image top = forward), z = down.
  Pose3 ned_T_cam(double north, double east, double heading, double roll, double pitch) const {
    Mat3d body_R_cam;
    body_R_cam << 0, -1, 0, 1, 0, 0, 0, 0, 1;
    const Mat3d ned_R_body = rotation_from_rpy(roll, pitch, heading);
    return Pose3{ned_R_body * body_R_cam, Vec3d(north, east, -altitude_m)};
  }
  // The simulator's world is x, y, z up: north = x, east = -y, down = -z.
  Pose3 sim_T_cam(const Pose3& ned) const {
    const Mat3d F = Vec3d(1.0, -1.0, -1.0).asDiagonal();
    return Pose3{F * ned.R, F * ned.t};
  }
};

struct CameraPassFrame {
  route::RouteNode node;
  double nav_step_m = 0.0;
  double truth_north_m = 0.0;
};

// Renders one pass: frames every spacing_m from start_north towards end_north at east = lateral_m,
// heading north (or south when reverse); nav pose = truth in the pass's own dead-reckoned frame (origin
// shifted, 1 deg heading bias, 2 % odometry scale error, 0.3 deg compass noise).
Status camera_pass(const CameraWorld& w, route::CameraTileProjector& proj, route::TileFeatureExtractor& fx, double start_north,
                   double end_north, double spacing_m, double lateral_m, bool taught, std::uint64_t seed, std::vector<CameraPassFrame>& out) {
  out.clear();
  const bool reverse = end_north < start_north;
  const double dir = reverse ? -1.0 : 1.0;
  const double heading0 = reverse ? kPi : 0.0;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  const double bias = taught ? 0.0 : deg_to_rad(1.0), scale = taught ? 1.0 : 1.02;
  const Vec2d origin = taught ? Vec2d(0.0, 0.0) : Vec2d(3.0, -2.0);
  Image<std::uint8_t> left = std::move(Image<std::uint8_t>::allocate(w.bench.width(), w.bench.height()).value());
  Image<std::uint8_t> right = std::move(Image<std::uint8_t>::allocate(w.bench.width(), w.bench.height()).value());
  const route::CameraTileConfig& pc = proj.config();
  Image<float> raster = std::move(Image<float>::allocate(pc.width_px, pc.height_px).value());
  Image<std::uint8_t> cover = std::move(Image<std::uint8_t>::allocate(pc.width_px, pc.height_px).value());
  double prev_n = start_north;
  for (int i = 0;; ++i) {
    const double n = start_north + dir * spacing_m * i;
    if (dir * (n - end_north) > 1e-9) break;
    const double yaw = heading0 + deg_to_rad(2.0) * std::sin(0.7 * n + static_cast<double>(seed % 7));
    const Pose3 cam = w.ned_T_cam(n, lateral_m, yaw, deg_to_rad(2.0) * n01(rng), deg_to_rad(2.0) * n01(rng));
    QNAV_RETURN_IF_ERROR(sim::render_stereo(w.terrain, w.bench, w.sim_T_cam(cam), seed * 1000003 + static_cast<std::uint64_t>(i), left.view(),
                                            right.view()));
    route::TileGeometry g;
    const double compass = yaw + bias + (taught ? 0.0 : deg_to_rad(0.3) * n01(rng));
    const Result<double> cov = proj.project(left.view(), w.k, cam, 0.0, compass, raster.view(), cover.view(), g);
    if (!cov) return cov.status();
    // The nav frame: the truth rotated by the heading bias about the pass's start and shifted.
    const Mat2d Rb = Pose2{0.0, 0.0, bias}.rotation();
    const Vec2d nav = origin + Rb * Vec2d(g.pose.x_m, g.pose.y_m);
    const double nav_n = nav.x(), nav_e = nav.y(), true_centre_n = g.pose.x_m;
    g.origin_north_m += nav_n - g.pose.x_m;
    g.origin_east_m += nav_e - g.pose.y_m;
    g.pose.x_m = nav_n;
    g.pose.y_m = nav_e;
    CameraPassFrame f;
    QNAV_RETURN_IF_ERROR(fx.extract(raster.view(), cover.view(), g, f.node));
    f.node.meta.along_m = scale * spacing_m * i;
    f.nav_step_m = i == 0 ? 0.0 : scale * std::abs(n - prev_n);
    f.truth_north_m = true_centre_n;  // the tile centre (optical axis on the ground), true north
    prev_n = n;
    out.push_back(std::move(f));
  }
  return Status::ok();
}

int cmd_camera() {
  const double length_m = g_opt.camera_length_m, spacing_m = 0.3;
  const long seed = g_opt.camera_seed;
  const bool json = g_opt.json;
  CameraWorld w(static_cast<std::uint64_t>(seed));
  route::CameraTileConfig pc;  // 4 mm raster, 192 x 192 (0.77 m square)
  route::TileFeatureConfig fc;
  fc.max_width = pc.width_px;
  fc.max_height = pc.height_px;
  fc.max_keypoints = 128;
  fc.downsample = 1;  // 4 mm pixels: grains (8 mm) and rock rims give the corners
  fc.blur_radius_px = 1;
  fc.harris_nms_radius = 4;
  fc.harris_norm_cell_px = 32;
  route::CameraTileProjector proj;
  route::TileFeatureExtractor fx;
  ArenaStorage fx_arena(route::TileFeatureExtractor::arena_bytes(fc));
  Status s = proj.init(pc);
  if (s) s = fx.init(fc, fx_arena);
  std::vector<CameraPassFrame> taught;
  const auto t0 = Clock::now();
  if (s) s = camera_pass(w, proj, fx, 0.0, length_m, spacing_m, 0.0, true, static_cast<std::uint64_t>(seed) * 31 + 1, taught);
  if (!s || taught.size() < 2) {
    std::fprintf(stderr, "qnav route camera: teach: %s\n", s ? "fewer than 2 frames" : s.message());
    return 1;
  }
  std::vector<route::NodeMeta> meta;
  double kp = 0.0;
  for (std::size_t i = 0; i < taught.size(); ++i) {
    route::NodeMeta m = taught[i].node.meta;
    m.index = static_cast<std::uint32_t>(i);
    meta.push_back(m);
    kp += static_cast<double>(taught[i].node.keypoints.size());
  }
  route::RouteParams params;
  params.sensor = route::SensorKind::kCamera;
  params.node_spacing_m = static_cast<float>(spacing_m);
  params.tile_length_m = static_cast<float>(pc.height_px * pc.resolution_m);
  params.tile_width_m = static_cast<float>(w.footprint_across_m());
  params.pixel_m = static_cast<float>(pc.resolution_m);
  params.max_keypoints = static_cast<std::uint16_t>(fc.max_keypoints);
  params.harris_window_px = static_cast<std::uint16_t>(2 * fc.harris_block_radius + 1);
  params.keypoint_min_distance_px = static_cast<std::uint16_t>(fc.harris_nms_radius);
  const double swath = w.footprint_across_m();
  if (!json)
    std::printf("camera route: %zu nodes over %.1f m (spacing %.2f m, footprint %.2f x %.2f m, %.0f keypoints/node), %.1f s to teach\n",
                taught.size(), length_m, spacing_m, swath, w.footprint_along_m(), kp / static_cast<double>(taught.size()), ms_since(t0) / 1000.0);
  const int pcts[] = {0, 10, 20, 30, 40};
  int scored = 0, within1 = 0, side_n = 0, side_ok = 0, off_route = 0;
  std::string rows;
  for (int rev = 0; rev < 2; ++rev) {
    for (const int pct : pcts) {
      const double lateral = pct / 100.0 * swath;
      std::vector<CameraPassFrame> rep;
      const double half = 0.5 * spacing_m;
      s = rev ? camera_pass(w, proj, fx, length_m - half, 0.0, spacing_m, lateral, false, static_cast<std::uint64_t>(seed) * 131 + pct * 2 + 1, rep)
              : camera_pass(w, proj, fx, half, length_m, spacing_m, lateral, false, static_cast<std::uint64_t>(seed) * 131 + pct * 2, rep);
      // The recorded-file configuration with its metric settings scaled from 0.3 m feature pixels to 4 mm.
      route::LocaliserConfig lc = pipeline::file_localiser_config(rev ? route::RouteDirection::kReverse : route::RouteDirection::kForward,
                                                        taught.size() + 8, taught.size(), spacing_m);
      lc.sensor = route::SensorKind::kCamera;
      lc.registration.robust.inlier_threshold_m = 0.02;
      lc.registration.fc.sigma_dist_m = 0.013;
      lc.guidance.side_deadband_m = 0.02;
      auto loc = std::make_unique<pipeline::RouteRepeater>();
      VectorNodeSource<CameraPassFrame> src(&taught);
      if (s) s = loc->init(lc);
      if (s) s = loc->start(params, Span<const route::NodeMeta>(meta.data(), meta.size()), src);
      if (!s) {
        std::fprintf(stderr, "qnav route camera: %s\n", s.message());
        return 1;
      }
      int p_scored = 0, p_within = 0, p_side_n = 0, p_side_ok = 0, p_off = 0, p_track = 0;
      for (std::size_t k = 0; k < rep.size(); ++k) {
        route::LocaliserStep st;
        s = loc->step(rep[k].node, rep[k].nav_step_m, st);
        if (!s) {
          std::fprintf(stderr, "qnav route camera: %s\n", s.message());
          return 1;
        }
        const int truth = static_cast<int>(std::lround(std::clamp(rep[k].truth_north_m / spacing_m, 0.0, static_cast<double>(taught.size() - 1))));
        const route::RouteSide want = expected_side(lateral, rev == 1, lc.guidance.side_deadband_m);
        p_track += st.guidance.status == route::GuidanceStatus::kTracking;
        if (k < static_cast<std::size_t>(kWarmupTiles)) continue;
        ++p_scored;
        p_within += std::abs(static_cast<int>(st.estimate) - truth) <= 1;
        if (want != route::RouteSide::kOnRoute) {
          ++p_off;
          const bool decided = st.guidance.side != route::RouteSide::kUnknown;
          p_side_n += decided;
          p_side_ok += decided && st.guidance.side == want;
        }
      }
      scored += p_scored;
      within1 += p_within;
      side_n += p_side_n;
      side_ok += p_side_ok;
      off_route += p_off;
      char line[256];
      std::snprintf(line, sizeof line, "  %-7s %3d%% (%.2f m)  %2zu frames  node +/-1 %5.1f%%  side correct %2d/%2d of %2d off-route  tracking %2d\n",
                    rev ? "reverse" : "forward", pct, lateral, rep.size(), p_scored ? 100.0 * p_within / p_scored : 0.0, p_side_ok, p_side_n, p_off,
                    p_track);
      rows += line;
    }
  }
  const double w1 = scored ? 100.0 * within1 / scored : 0.0, sc = side_n ? 100.0 * side_ok / side_n : 0.0,
               sall = off_route ? 100.0 * side_ok / off_route : 0.0;
  if (json) {
    std::printf("{\"sensor\":\"camera\",\"nodes\":%zu,\"spacing_m\":%.2f,\"footprint_m\":[%.3f,%.3f],\"keypoints_per_node\":%.1f,"
                "\"scored_tiles\":%d,\"node_within_1_pct\":%.2f,\"side_correct_pct\":%.2f,\"side_decided\":%d,"
                "\"side_correct_pct_of_offset_tiles\":%.2f,\"offset_tiles\":%d}\n",
                taught.size(), spacing_m, swath, w.footprint_along_m(), kp / static_cast<double>(taught.size()), scored, w1, sc, side_n, sall,
                off_route);
  } else {
    std::fputs(rows.c_str(), stdout);
    std::printf("all passes: node within +/-1 on %d of %d scored tiles (%.1f%%); side correct on %d of %d decided (%.1f%%), %.1f%% of %d off-route tiles\n",
                within1, scored, w1, side_ok, side_n, sc, sall, off_route);
  }
  return 0;
}

}  // namespace

namespace {
// The options a recorded pass (--sonar / --xtf FILE) is cut into tiles with (open_file_pass).
void add_file_pass_options(CLI::App& c) {
  qnav::cli::add_text(c, "--nav", g_opt.nav, "navigation of a recorded pass: the position fixes, or dead reckoning", {"fix", "dr"});
  qnav::cli::add_number(c, "--lines", g_opt.lines, "pings per tile of a recorded pass", "pings", 10, 2000);
  qnav::cli::add_number(c, "--stride", g_opt.stride, "a tile every N pings of a recorded pass (<= --lines)", "pings", 1, 2000);
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
  add_file_pass_options(*r);
  run.on(r, cmd_repeat);

  CLI::App* e = cmd.add_subcommand("eval", "the route-following paper's evaluation on the simulator (Table I, Fig. 5/7/9/10 data)");
  add_flag(*e, "--json", g_opt.json, "one JSON summary on stdout (the log on stderr)");
  add_text(*e, "--out", g_opt.eval_out, "folder for the CSV data (created as needed)")->type_name("DIR");
  add_number(*e, "--length-m", g_opt.length_m, "length of each simulated route", "m", 400, 20000);
  add_number(*e, "--seabeds", g_opt.seabeds, "simulated seabeds", "", 1, 20)
      ->description("simulated seabeds (default 3, 1 with --quick; 1..20)");
  add_flag(*e, "--quick", g_opt.quick, "fewer passes and one seabed (a smoke run)");
  run.on(e, cmd_eval);

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
}
}  // namespace

QNAV_CLI_COMMAND("route", "route teach and repeat: train, info, repeat, eval, xtf, camera (route-following paper)", setup_route);
