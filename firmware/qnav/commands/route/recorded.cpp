// qnav route: xtf, and train / repeat on recorded XTF / JSF passes (split from route.cpp; what the files share: route_cmd.hpp).
#include "firmware/qnav/commands/route/route_cmd.hpp"

namespace route_cmd {

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
  double ping_spacing_m = 0.0;  // median along-track distance between consecutive pings with navigation
};

// Loads a file and derives its tile geometry from the median slant range and ping spacing
// (pipeline::file_route_tile_config): 300 ground bins per side (0.1 m for the Iver2's 30 m), tiles
// by along-track distance, 0.9 x the swath long every 0.6 x the swath (--tile-length-m /
// --tile-stride-m override), or --lines pings per tile every --stride pings (default --lines / 2)
// when --lines is given. default_length_m / default_stride_m: the command's own default (xtf), 0 =
// from the swath. Navigation from the fixes (--nav fix) or dead reckoning (--nav dr),
// --heading-offset-deg added to the compass; the bottom is detected in each ping.
int open_file_pass(const char* path, FilePass& out, double default_length_m = 0.0, double default_stride_m = 0.0) {
  const double hoff_deg = g_opt.heading_offset_deg;
  const long lines = g_opt.lines, stride = g_opt.lines > 0 && g_opt.stride == 0 ? std::max(1L, g_opt.lines / 2) : g_opt.stride;
  const char* nav = g_opt.nav.c_str();
  if (lines == 0 && stride > 0) {
    std::fprintf(stderr, "qnav route: --stride %ld needs --lines (tiles by ping count); by distance use --tile-stride-m\n", stride);
    return 2;
  }
  if (lines > 0 && (g_opt.tile_length_m > 0.0 || g_opt.tile_stride_m > 0.0)) {
    std::fprintf(stderr, "qnav route: --lines (tiles by ping count) and --tile-length-m / --tile-stride-m (by distance) exclude each other\n");
    return 2;
  }
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
  std::vector<double> steps;
  for (std::size_t k = 1; k < out.track.pose.size(); ++k)
    if (out.track.ok[k] && out.track.ok[k - 1])
      steps.push_back(std::hypot(out.track.pose[k].x_m - out.track.pose[k - 1].x_m, out.track.pose[k].y_m - out.track.pose[k - 1].y_m));
  if (steps.empty()) {
    std::fprintf(stderr, "qnav route: %s: no two consecutive pings with navigation\n", path);
    return 1;
  }
  double pass_m = 0.0;  // along-track length of the pass (the consecutive pings with navigation)
  for (double d : steps) pass_m += d;
  std::nth_element(steps.begin(), steps.begin() + static_cast<long>(steps.size() / 2), steps.end());
  out.ping_spacing_m = std::max(1e-3, steps[steps.size() / 2]);
  const double len = g_opt.tile_length_m > 0.0 ? g_opt.tile_length_m : default_length_m;
  const double str = g_opt.tile_stride_m > 0.0 ? g_opt.tile_stride_m : default_stride_m;
  out.tiles = pipeline::file_route_tile_config(range, out.ping_spacing_m, len, str, static_cast<int>(lines), static_cast<int>(stride));
  // A pass too short for three tiles of the default length (a short recorded line, a test file): the
  // default tiles shrink to fit three (same length to stride ratio, at least 4 m), so a pass a new user
  // records works without tuning flags. Given lengths (--tile-length-m, --lines) are kept as given.
  const sonar::TileBuilderConfig& dt = out.tiles.tiles;
  if (g_opt.tile_length_m <= 0.0 && g_opt.tile_stride_m <= 0.0 && lines == 0 && dt.tile_length_m > 0.0 && dt.tile_stride_m > 0.0 &&
      pass_m < dt.tile_length_m + 2.0 * dt.tile_stride_m) {
    const double ratio = dt.tile_stride_m / dt.tile_length_m;
    const double fit_len = std::max(4.0, pass_m / (1.0 + 2.0 * ratio) * 0.95);
    std::fprintf(stderr, "qnav route: %s: the pass is %.1f m long: tiles of %.1f m would not give three; %.1f m tiles instead\n", path, pass_m,
                 dt.tile_length_m, fit_len);
    out.tiles = pipeline::file_route_tile_config(range, out.ping_spacing_m, fit_len, fit_len * ratio, 0, 0);
  }
  if (out.tiles.tiles.tile_length_m > 0.0 && out.tiles.tiles.tile_stride_m > out.tiles.tiles.tile_length_m) {
    std::fprintf(stderr, "qnav route: tile stride %.1f m is more than the tile length %.1f m (the seabed between tiles would be skipped)\n",
                 out.tiles.tiles.tile_stride_m, out.tiles.tiles.tile_length_m);
    return 2;
  }
  out.swath_m = 2.0 * range;
  if (out.tiles.tiles.tile_length_m > 0.0)
    std::fprintf(stderr, "qnav route: %s: swath %.1f m, %.2f m between pings: tiles of %.1f m every %.1f m (up to %d pings), %zu keypoints\n", path,
                 out.swath_m, out.ping_spacing_m, out.tiles.tiles.tile_length_m, out.tiles.tiles.tile_stride_m, out.tiles.tiles.scanlines_per_tile,
                 out.tiles.features.max_keypoints);
  return 0;
}

// The pings of one tile stride (for telling a repeat tile "beyond" the taught pings).
double stride_pings(const FilePass& fp) {
  const sonar::TileBuilderConfig& t = fp.tiles.tiles;
  return t.tile_length_m > 0.0 ? t.tile_stride_m / fp.ping_spacing_m : static_cast<double>(t.scanline_stride);
}

// Tiles of pings [a, b) of a file (ping_first / ping_last: file ping indices). centre_ping (optional)
// receives each tile's centre ping index. on_tile (optional) sees each tile as it is built (a repeat
// localises it there and frames the next tile on the route); false stops.
Status file_tiles(pipeline::RouteTilePipeline& pipe, const FilePass& fp, long a, long b, std::vector<pipeline::RouteTile>& out,
                  std::vector<double>* centre_ping, const std::function<bool(const pipeline::RouteTile&)>& on_tile = nullptr) {
  pipe.reset_pass();
  out.clear();
  if (centre_ping) centre_ping->clear();
  bool stop = false;
  for (long i = a; i < b && !stop; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    if (!fp.track.ok[k]) continue;
    sonar::SonarPing ping = tools::as_ping(fp.fd.pings[k], false);
    ping.ping_number = static_cast<std::uint32_t>(i);
    QNAV_RETURN_IF_ERROR(pipe.push_ping(ping, fp.track.pose[k], [&](const pipeline::RouteTile& t) {
      out.push_back(t);
      if (centre_ping) centre_ping->push_back(0.5 * (static_cast<double>(t.ping_first) + static_cast<double>(t.ping_last)));
      return on_tile ? on_tile(t) : true;
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

}  // namespace

int cmd_xtf() {
  const char* path = g_opt.xtf.c_str();
  long ta = 0, tb = 301, ra = 90, rb = 461;  // ping 0 of the Iver2 file has no fix: 300 taught pings
  if (!parse_range(opt_or_null(g_opt.train), ta, tb)) return usage("xtf", "--train: give A:B, pings A to B-1 with 0 <= A < B");
  if (!parse_range(opt_or_null(g_opt.repeat), ra, rb)) return usage("xtf", "--repeat: give C:D, pings C to D-1 with 0 <= C < D");
  FilePass fp;
  // The Iver2 pass is 55 m long, shorter than one swath-sized tile: xtf frames 12 m tiles every 6 m.
  if (const int rc = open_file_pass(path, fp, 12.0, 6.0); rc != 0) return rc;
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
    const bool near = std::abs(train_c[static_cast<std::size_t>(truth)] - rep_c[k]) <= stride_pings(fp);
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
  if (s && tiles.size() < 2)
    s = Status(StatusCode::kInvalidArgument,
               "fewer than 2 tiles in the ping range: a route needs 2 nodes (a longer --pings range, or shorter tiles: --tile-length-m / --tile-stride-m)");
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
  pipeline::RouteRepeatSession session(hal::host_file_store());
  pipeline::RepeatSessionConfig sc;  // recorded passes: no experiences yet (--learn is refused with --sonar)
  sc.localiser = lc;
  sc.max_nodes = meta.size();
  pipeline::RouteTilePipeline pipe;
  std::vector<pipeline::RouteTile> tiles;
  Status s = session.init(sc);
  if (s) s = session.start(reader.params(), Span<const route::NodeMeta>(meta.data(), meta.size()), reader, reverse);
  if (s) s = pipe.init(fp.tiles);
  if (!s) {
    std::fprintf(stderr, "qnav route repeat: %s\n", s.message());
    return 1;
  }
  FILE* f = open_repeat_csv();
  if (f == nullptr) return 1;
  const bool csv = f != stdout;
  int tracking = 0;
  Status step_status;
  // Each tile is localised as it is built and the next one framed on the taught nodes.
  s = file_tiles(pipe, fp, a, b, tiles, nullptr, [&](const pipeline::RouteTile& t) {
    route::LocaliserStep st;
    step_status = session.step(t, false, st).step;
    if (!step_status) return false;
    tracking += st.guidance.status == route::GuidanceStatus::kTracking;
    write_repeat_row(f, static_cast<long>(tiles.size() - 1), -1, st, "unknown", t.ping_first, t.ping_last);
    pipe.set_next_stride_m(session.next_stride_m(st, fp.tiles.tiles.tile_stride_m));
    return true;
  });
  if (s && !step_status) s = step_status;
  if (s && tiles.empty()) s = Status(StatusCode::kInvalidArgument, "no complete tile in the ping range");
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

}  // namespace route_cmd
