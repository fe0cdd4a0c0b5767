// qnav map: downward-camera mapping (underwater SLAM paper): the homography chain of nav/topo over a
// directory of frames, with the navigation poses when given. The per-frame wiring (undistortion,
// chain, topological map) and its tuned defaults are firmware/pipeline/topo_mapper, shared with qnavd;
// this file reads the frames, times the parts, saves the map file and writes the outputs.
//
//   qnav map --images DIR [--poses CSV] [--camera YAML] [--altitude M] [--out DIR] [--json]
//            [--no-undistort] [--fundamental] [--keyframe-gap N] [--frames N] [--no-plot]
//       Frames: every .png/.jpg/.jpeg/.pgm in DIR, in name order, read as 8-bit grey. --camera: OpenCV
//       style YAML (image_width/height, camera_matrix data, distortion_coefficients k1 k2 p1 p2 [k3]);
//       frames are undistorted with nav/vision's RemapTable unless --no-undistort, and fx gives metric
//       scale with --altitude (metres above the seabed, constant). --poses: a CSV with columns file,
//       x, y, yaw_deg (optional t_video_s, pose_note; the sparus_snippet frames.csv layout), matched to
//       frames by file name. --fundamental: the paper's F both-accept outlier rule before H.
//       --keyframe-gap N: a new keyframe at least every N frames (default 30; 1 = frame-to-frame chain).
//       Writes DIR_OUT/map_trajectory.csv (per frame: status, keyframe, keypoints, matches, inliers,
//       pose in mosaic pixels, heading, metres, the chain aligned to the navigation, nav pose, time) and
//       DIR_OUT/map_trajectory.png (scripts/map_plot.py through /usr/bin/python3; skipped with a note
//       when either is missing) and DIR_OUT/map_mosaic.png (the frames warped into frame 0's grid
//       through the chained homographies, the trajectory and the map over it; write_map_mosaic). Prints pairs registered / total, inliers per pair, chained image
//       rotation vs the navigation's yaw change, path vs the navigation path, frame time; --json: one
//       object. Exit 1 when no frame could be read or a pair did not register.
//       --map-out FILE [--node-spacing D] [--max-nodes N]: the topological map (nav/topo TopoMap) beside
//       the chain, in metres with --altitude (default spacing 0.2 m) else mosaic pixels (30 px); the map
//       file (firmware/tools/map_file) rewritten durably after every new node and at the end;
//       DIR_OUT/map_nodes.csv and map_edges.csv; per frame the node, kind and revisit in the CSV.
//   qnav map route --map FILE --from A --to B [--astar] [--json]: shortest path over the map's edges.
//   qnav map eval [--json] [--fig3-csv FILE] ...: the synthetic loop under the Table-1 filters (see run_eval);
//       --fig3-csv: the paper's Fig. 3 (keypoints and true matches per frame and run).
#include <time.h>
#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "firmware/cli/cli_app.hpp"
#include "firmware/pipeline/topo_mapper.hpp"
#include "firmware/qnav/command.hpp"
#include "firmware/tools/image_reader.hpp"
#include "firmware/tools/map_file.hpp"
#include "firmware/tools/mosaic.hpp"
#include "firmware/tools/raster_plot.hpp"
#include "firmware/tools/sequence_reader.hpp"
#include "firmware/tools/text_file.hpp"
#include "nav/vision/degrade.hpp"
// The synthetic seabed and its downward camera (header-only, deterministic on every target): the same
// sequence the nav/topo tests use, for `qnav map eval`.
#include "drivers/downward_sim/seabed_scene.hpp"

namespace {

using namespace qnav;
using Clock = std::chrono::steady_clock;

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string basename_of(const std::string& p) {
  const std::size_t s = p.find_last_of('/');
  return s == std::string::npos ? p : p.substr(s + 1);
}

// Numbers of the first `[...]` after key (OpenCV-style YAML "data: [a, b, ...]").
struct NavPose {
  bool valid = false;
  double x = 0.0, y = 0.0, yaw_deg = 0.0, t = std::nan("");
  bool interpolated = true;  // pose_note == interpolated (or no note column)
};

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> f;
  std::string cur;
  for (char c : line) {
    if (c == ',') {
      f.push_back(cur);
      cur.clear();
    } else if (c != '\r') {
      cur += c;
    }
  }
  f.push_back(cur);
  return f;
}

bool read_poses(const char* path, std::vector<std::pair<std::string, NavPose>>& out, std::string& err) {
  std::string text;
  const Status s = tools::read_text_file(path, 16 << 20, text);
  if (!s) {
    err = s.message();
    return false;
  }
  std::size_t pos = 0;
  std::vector<std::string> header;
  int c_file = -1, c_x = -1, c_y = -1, c_yaw = -1, c_t = -1, c_note = -1;
  int line_no = 0;
  while (pos < text.size()) {
    std::size_t nl = text.find('\n', pos);
    if (nl == std::string::npos) nl = text.size();
    const std::string line = text.substr(pos, nl - pos);
    pos = nl + 1;
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> f = split_csv(line);
    if (header.empty()) {
      header = f;
      for (int i = 0; i < static_cast<int>(f.size()); ++i) {
        if (f[i] == "file") c_file = i;
        if (f[i] == "x") c_x = i;
        if (f[i] == "y") c_y = i;
        if (f[i] == "yaw_deg") c_yaw = i;
        if (f[i] == "t_video_s") c_t = i;
        if (f[i] == "pose_note") c_note = i;
      }
      if (c_file < 0 || c_x < 0 || c_y < 0 || c_yaw < 0) {
        err = std::string(path) + ": header needs the columns file, x, y, yaw_deg";
        return false;
      }
      continue;
    }
    if (f.size() != header.size()) {
      err = std::string(path) + ": line " + std::to_string(line_no) + " has " + std::to_string(f.size()) + " fields, header " +
            std::to_string(header.size());
      return false;
    }
    NavPose p;
    char* e1 = nullptr;
    char* e2 = nullptr;
    char* e3 = nullptr;
    p.x = std::strtod(f[c_x].c_str(), &e1);
    p.y = std::strtod(f[c_y].c_str(), &e2);
    p.yaw_deg = std::strtod(f[c_yaw].c_str(), &e3);
    if (*e1 != '\0' || *e2 != '\0' || *e3 != '\0' || f[c_x].empty() || !std::isfinite(p.x) || !std::isfinite(p.y) ||
        !std::isfinite(p.yaw_deg)) {
      err = std::string(path) + ": line " + std::to_string(line_no) + ": x, y or yaw_deg is not a finite number";
      return false;
    }
    if (c_t >= 0) p.t = std::strtod(f[c_t].c_str(), nullptr);
    if (c_note >= 0) p.interpolated = f[c_note] == "interpolated";
    p.valid = true;
    out.emplace_back(basename_of(f[c_file]), p);
  }
  if (out.empty()) err = std::string(path) + ": no poses";
  return !out.empty();
}

double cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

double wrap_deg(double d) {
  while (d > 180.0) d -= 360.0;
  while (d <= -180.0) d += 360.0;
  return d;
}

struct FrameRecord {
  std::string file;
  topo::ChainStep step;
  double ms = 0.0;        // undistortion + chain
  double chain_ms = 0.0;  // HomographyChain::process alone
  double chain_cpu_ms = 0.0;  // the same in process CPU time (less sensitive to a loaded machine)
  NavPose nav;
  Vec2d aligned = Vec2d::Zero();  // chain position in the navigation frame (metres), when aligned
  topo::ObserveResult place;      // the topological map's answer (kBadInput when not observed)
  bool observed = false;
  double map_ms = 0.0;            // signature + map update (in ms)
  void take(const pipeline::MapperStep& m) {
    step = m.chain;
    place = m.place;
    observed = m.observed;
  }
};

// The tool's side of the topological map that the shared mapper (pipeline::TopoMapper) builds beside
// the chain: the map file (rewritten durably after each new node), its save count and times, the
// nodes and edges CSVs.
struct MapBuilder {
  const pipeline::TopoMapper* mapper = nullptr;
  const char* path = nullptr;  // --map-out
  int saves = 0;
  std::vector<double> save_ms;
  Status status;  // the first save failure

  const topo::TopoMap& map() const { return mapper->map(); }
  bool metric() const { return mapper->metric(); }
  void save() {
    const auto t0 = Clock::now();
    const Status s = tools::save_map(path, map(), metric());
    save_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    ++saves;
    if (!s && status) status = s;
  }
  int revisit_frames(const std::vector<FrameRecord>& rec) const {
    int n = 0;
    for (const FrameRecord& r : rec) n += r.observed && r.place.revisit ? 1 : 0;
    return n;
  }
  bool write_csv(const std::string& dir, double mpp) const {
    const std::string np = dir + "/map_nodes.csv", ep = dir + "/map_edges.csv";
    FILE* f = std::fopen(np.c_str(), "w");
    if (f == nullptr) return false;
    std::fprintf(f, "id,x,y,units,x_px,y_px,heading_deg,created,last_seen,visits,revisits,edges\n");
    for (std::uint16_t i = 0; i < map().capacity(); ++i) {
      if (!map().active(i)) continue;
      const topo::TopoNode& n = map().node(i);
      const double to_px = metric() && mpp > 0.0 ? 1.0 / mpp : 1.0;
      std::fprintf(f, "%u,%.4f,%.4f,%s,%.3f,%.3f,%.3f,%u,%u,%u,%u,%u\n", i, n.position.x(), n.position.y(), metric() ? "m" : "px",
                   n.position.x() * to_px, n.position.y() * to_px, rad_to_deg(n.heading_rad), n.created, n.last_seen, n.visits,
                   n.revisits, n.edge_count);
    }
    bool ok = std::fflush(f) == 0;
    std::fclose(f);
    f = std::fopen(ep.c_str(), "w");
    if (f == nullptr) return false;
    std::fprintf(f, "a,b,age,length\n");
    for (std::uint16_t i = 0; i < map().capacity(); ++i) {
      if (!map().active(i)) continue;
      for (const topo::TopoEdge& e : map().edges(i))
        if (e.to > i) std::fprintf(f, "%u,%u,%u,%.4f\n", i, e.to, e.age, (map().node(e.to).position - map().node(i).position).norm());
    }
    ok = std::fflush(f) == 0 && ok;
    std::fclose(f);
    return ok;
  }
};

// DIR/map_mosaic.png: every registered frame warped into frame 0's pixel grid through its chained
// homography (ChainPose::H_0_cur; the newest frame on top), the trajectory (the frames' principal
// points; keyframes ringed), and the topological map's edges and nodes (revisited ones red) over it,
// axes through tools/raster_plot: metres with a scale bar when the chain is metric, else mosaic
// pixels. The canvas is at most kMosaicMaxSide a side: a larger mosaic is downscaled (said in the
// title). frame(i, buf) gives frame i as the chain saw it (undistorted), false when it cannot.
constexpr int kMosaicMaxSide = 1600;
struct MosaicFrameSource {
  std::function<bool(std::size_t, ImageU8&)> frame;
  int width = 0, height = 0;
};
bool write_map_mosaic(const std::string& path, const MosaicFrameSource& src, const std::vector<FrameRecord>& rec,
                      const topo::TopoMap* map, bool metric, double mpp, const char* what) {
  std::vector<Mat3d> H;
  std::vector<std::size_t> used;
  for (std::size_t i = 0; i < rec.size(); ++i)
    if (rec[i].step.status == topo::StepStatus::kOk) {
      H.push_back(rec[i].step.pose.H_0_cur);
      used.push_back(i);
    }
  Result<tools::MosaicGeometry> g = tools::mosaic_geometry(H, src.width, src.height, kMosaicMaxSide);
  if (!g || used.empty()) {
    std::fprintf(stderr, "map: no mosaic: %s\n", g ? "no registered frame" : g.status().message());
    return false;
  }
  tools::MosaicCanvas canvas(g.value());
  Result<ImageU8> buf = ImageU8::allocate(src.width, src.height);
  if (!buf) return false;
  int pasted = 0;
  for (std::size_t j = 0; j < used.size(); ++j)
    if (src.frame(used[j], buf.value()) && canvas.paste(ConstImageViewU8(buf->view()), H[j])) ++pasted;
  std::vector<std::uint8_t> rgb = canvas.to_rgb();
  const int w = g->width, h = g->height;
  const Vec2d pp = rec[used[0]].step.pose.position_px;  // frame 0's principal point: the origin of position_m
  auto node_px = [&](const Vec2d& p) { return g->to_canvas(metric && mpp > 0.0 ? Vec2d(pp + p / mpp) : p); };
  int nodes = 0;
  if (map != nullptr) {
    for (std::uint16_t i = 0; i < map->capacity(); ++i) {
      if (!map->active(i)) continue;
      for (const topo::TopoEdge& e : map->edges(i))
        if (e.to > i) tools::draw_line(rgb, w, h, node_px(map->node(i).position), node_px(map->node(e.to).position), {0, 170, 255}, 2.0);
    }
  }
  for (std::size_t j = 1; j < used.size(); ++j)
    tools::draw_line(rgb, w, h, g->to_canvas(rec[used[j - 1]].step.pose.position_px), g->to_canvas(rec[used[j]].step.pose.position_px),
                     {255, 200, 0}, 1.5);
  for (std::size_t i : used)
    if (rec[i].step.new_keyframe) tools::draw_ring(rgb, w, h, g->to_canvas(rec[i].step.pose.position_px), 4.0, {255, 200, 0}, 1.5);
  if (map != nullptr) {
    for (std::uint16_t i = 0; i < map->capacity(); ++i) {
      if (!map->active(i)) continue;
      const topo::TopoNode& n = map->node(i);
      const Vec2d c = node_px(n.position);
      tools::draw_disc(rgb, w, h, c, 4.5, {0, 0, 0});
      tools::draw_disc(rgb, w, h, c, 3.5, n.revisits > 0 ? tools::RgbColour{230, 30, 30} : tools::RgbColour{0, 170, 255});
      ++nodes;
    }
  }
  tools::RasterPlot plot;
  char title[256];
  std::snprintf(title, sizeof title, "%s: mosaic of %d frames, trajectory (yellow, keyframes ringed)%s%s", what, pasted,
                map != nullptr ? (", map " + std::to_string(nodes) + " nodes (revisited red), edges").c_str() : "",
                g->downscaled() ? (", downscaled 1:" + std::to_string(1.0 / g->scale).substr(0, 4)).c_str() : "");
  plot.title = title;
  if (metric && mpp > 0.0) {
    plot.x = {(g->x0 - pp.x()) * mpp, mpp / g->scale, "x m (frame 0 camera axes)"};
    plot.y = {(g->y0 - pp.y()) * mpp, mpp / g->scale, "y m"};
    plot.scale_bar = true;
  } else {
    plot.x = {g->x0, 1.0 / g->scale, "mosaic x px (frame 0)"};
    plot.y = {g->y0, 1.0 / g->scale, "mosaic y px"};
  }
  const Status s = tools::write_raster_plot_png_rgb(path.c_str(), rgb.data(), w, h, w * 3, plot);
  if (!s) std::fprintf(stderr, "map: writing %s: %s\n", path.c_str(), s.message());
  return s.is_ok();
}

// Least-squares 2D rotation + scale (+ optional reflection) about the start, mapping chain positions
// a (pixels from frame 0's principal point) onto nav positions b (metres from the first nav pose):
// b ~ s R F a; both start at the origin, so the aligned chain starts where the navigation does.
// fixed_scale > 0 fixes s (metres per pixel from the altitude). The mirror (F = diag(1, -1)) is chosen
// by the residual: image axes (x right, y down, camera z down) seen in a z-up world are mirrored.
struct Alignment {
  bool valid = false;
  bool mirrored = false;
  double scale = 0.0, rotation_rad = 0.0, rms_m = 0.0;
  Vec2d apply(const Vec2d& a) const {
    const Vec2d m(a.x(), mirrored ? -a.y() : a.y());
    const double c = std::cos(rotation_rad), s = std::sin(rotation_rad);
    return scale * Vec2d(c * m.x() - s * m.y(), s * m.x() + c * m.y());
  }
};
Alignment align(const std::vector<Vec2d>& a, const std::vector<Vec2d>& b, double fixed_scale) {
  Alignment best;
  if (a.size() < 3) return best;
  for (int mirror = 0; mirror < 2; ++mirror) {
    double sxx = 0.0, sxy = 0.0, va = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const Vec2d p(a[i].x(), mirror ? -a[i].y() : a[i].y());
      const Vec2d& q = b[i];
      sxx += p.dot(q);
      sxy += p.x() * q.y() - p.y() * q.x();
      va += p.squaredNorm();
    }
    if (!(va > 0.0)) return best;
    Alignment al;
    al.valid = true;
    al.mirrored = mirror == 1;
    al.rotation_rad = std::atan2(sxy, sxx);
    al.scale = fixed_scale > 0.0 ? fixed_scale : std::hypot(sxx, sxy) / va;
    double ss = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) ss += (al.apply(a[i]) - b[i]).squaredNorm();
    al.rms_m = std::sqrt(ss / static_cast<double>(a.size()));
    if (!best.valid || al.rms_m < best.rms_m) best = al;
  }
  return best;
}

std::string source_root() {
  std::string f = __FILE__;  // .../firmware/qnav/commands/map.cpp
  for (int i = 0; i < 4; ++i) {
    const std::size_t s = f.find_last_of('/');
    if (s == std::string::npos) return ".";
    f = f.substr(0, s);
  }
  return f.empty() ? "." : f;
}

// Every map option (one invocation per process), declared in setup_map at the end of this file.
// NaN / -1: not given (the default depends on other options).
struct MapOptions {
  std::string images, poses, camera, out, map_out, map, fig3_csv;
  bool json = false, no_undistort = false, fundamental = false, no_plot = false, astar = false;
  double altitude = -1.0, node_spacing = std::nan(""), laps = 1.35;
  long frames = 100000, keyframe_gap = -1, max_nodes = 1024, from = -1, to = -1, per_lap = 90, filters = 5;
};
MapOptions g_opt;
const char* opt_or_null(const std::string& s) { return s.empty() ? nullptr : s.c_str(); }

// qnav map route --map FILE --from A --to B [--astar] [--json]: the shortest path over the map's
// edges (Dijkstra, or A* with the Euclidean heuristic), node ids and cost.
int run_route() {
  const char* path = g_opt.map.c_str();
  const long from = g_opt.from, to = g_opt.to;
  const bool astar = g_opt.astar;
  const bool json = g_opt.json;
  if (const std::string e = qnav::cli::input_file_problem(path); !e.empty()) {
    std::fprintf(stderr, "map route: %s\n", e.c_str());
    return 1;
  }
  topo::MapHeader h;
  Status s = tools::read_map_header(path, h);
  if (!s) {
    std::fprintf(stderr, "map route: %s: refused: %s (%s)\n", path, s.message(), to_string(s.code()));
    return 1;
  }
  topo::TopoMapConfig c = pipeline::topo_map_config(h.node_spacing, std::max<std::size_t>(h.capacity, 2));
  c.max_edges_per_node = h.max_edges_per_node;
  ArenaStorage arena(topo::TopoMap::arena_bytes(c));
  topo::TopoMap map;
  s = map.init(c, arena);
  if (s) s = tools::load_map(path, map, nullptr);
  if (!s) {
    std::fprintf(stderr, "map route: %s: refused: %s (%s)\n", path, s.message(), to_string(s.code()));
    return 1;
  }
  if (from < 0 || to < 0 || from >= static_cast<long>(map.capacity()) || to >= static_cast<long>(map.capacity()) ||
      !map.active(static_cast<std::uint16_t>(from)) || !map.active(static_cast<std::uint16_t>(to))) {
    std::fprintf(stderr, "map route: node %ld or %ld is not in the map (%zu nodes, ids < %zu)\n", from, to, map.node_count(),
                 map.capacity());
    return 1;
  }
  std::vector<std::uint16_t> nodes(map.capacity());
  const Span<std::uint16_t> out(nodes.data(), nodes.size());
  const auto a = static_cast<std::uint16_t>(from), b = static_cast<std::uint16_t>(to);
  const auto t0 = Clock::now();
  const topo::PathResult r = astar ? map.astar(a, b, out) : map.dijkstra(a, b, out);
  const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  const char* units = h.metric ? "m" : "px";
  if (json) {
    std::printf("{\"algorithm\": \"%s\", \"status\": \"%s\", \"from\": %ld, \"to\": %ld, \"cost\": %.6f, \"units\": \"%s\", "
                "\"expansions\": %zu, \"ms\": %.4f, \"path\": [",
                astar ? "astar" : "dijkstra", topo::to_string(r.status), from, to, r.cost, units, r.expansions, ms);
    for (std::size_t i = 0; r.status == topo::PathStatus::kFound && i < r.length; ++i) std::printf(i ? ", %u" : "%u", nodes[i]);
    std::printf("]}\n");
  } else {
    std::printf("map %s: %zu nodes, %zu edges (%s)\n", path, map.node_count(), map.edge_count(), units);
    if (r.status == topo::PathStatus::kFound) {
      std::printf("path %ld -> %ld (%s): ", from, to, astar ? "A*" : "Dijkstra");
      for (std::size_t i = 0; i < r.length; ++i) std::printf(i ? " %u" : "%u", nodes[i]);
      std::printf("\ncost %.4f %s, %zu nodes, %zu expansions, %.3f ms\n", r.cost, units, r.length, r.expansions, ms);
    } else {
      std::printf("no path %ld -> %ld (%s): %s after %zu expansions\n", from, to, astar ? "A*" : "Dijkstra", topo::to_string(r.status),
                  r.expansions);
    }
  }
  return r.status == topo::PathStatus::kFound ? 0 : 1;
}

// The paper's Fig. 3 on the synthetic loop: per frame and per run (none, filter1..5) the keypoints
// and the TRUE matches: ratio-test matches whose keyframe position is within kTrueMatchPx of where the
// seabed point seen at the frame position really is in the keyframe (seabed_scene's exact projection).
constexpr double kTrueMatchPx = 3.0;
// A percentage for JSON: one decimal, or null when undefined (no second-pass frame: laps too short).
std::string json_pct(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", v);
  return std::isfinite(v) ? std::string(b) : std::string("null");
}
struct Fig3 {
  std::vector<std::vector<double>> keypoints, matches, true_matches, inliers;  // [run][frame]; NaN: none
  // Frame k of run: its keypoints; unless the chain refused it before matching (0 matches), its
  // matches, inliers and true matches (counted only then: true_matches() reprojects every match).
  template <typename TrueMatches>
  void record(std::size_t run, std::size_t k, const topo::ChainStep& st, TrueMatches true_matches_of) {
    keypoints[run][k] = st.keypoints;
    if (st.reference) return;
    matches[run][k] = st.matches;
    true_matches[run][k] = true_matches_of();
    inliers[run][k] = st.inliers;
  }
};

// Pixel (u, v) of the camera at pose a, seen by the camera at pose b (same intrinsics, flat seabed).
Vec2d transfer(const sim::downward::Camera& cam, const sim::downward::CameraPose& a, const sim::downward::CameraPose& b, const Vec2d& px) {
  const double ma = a.altitude_m / cam.f, mb = b.altitude_m / cam.f;
  const double ca = std::cos(a.yaw_rad), sa = std::sin(a.yaw_rad), cb = std::cos(b.yaw_rad), sb = std::sin(b.yaw_rad);
  const double du = px.x() - cam.cx, dv = px.y() - cam.cy;
  const double gx = a.x_m + ma * (ca * du - sa * dv) - b.x_m, gy = a.y_m + ma * (sa * du + ca * dv) - b.y_m;
  return Vec2d(cam.cx + (cb * gx + sb * gy) / mb, cam.cy + (-sb * gx + cb * gy) / mb);
}

int count_true_matches(const topo::HomographyChain& chain, const sim::downward::Camera& cam, const sim::downward::CameraPose& cur,
                       const sim::downward::CameraPose& key) {
  const Span<const Vec2d> c = chain.matched_current(), k = chain.matched_keyframe();
  int n = 0;
  for (std::size_t i = 0; i < c.size(); ++i) n += (transfer(cam, cur, key, c[i]) - k[i]).norm() <= kTrueMatchPx ? 1 : 0;
  return n;
}

bool write_fig3_csv(const char* path, const Fig3& f, int runs) {
  FILE* out = std::fopen(path, "w");
  if (out == nullptr) return false;
  const char* name[] = {"none", "filter1", "filter2", "filter3", "filter4", "filter5"};
  std::fprintf(out, "# qnav map eval --fig3-csv: per frame of the synthetic loop, keypoints, ratio-test matches, true matches (within %.1f px "
                    "of the true transfer to the keyframe) and homography inliers, per run; empty: no matching (the reference frame)\n",
               kTrueMatchPx);
  std::fprintf(out, "frame");
  for (int r = 0; r < runs; ++r) std::fprintf(out, ",keypoints_%s,matches_%s,true_matches_%s,inliers_%s", name[r], name[r], name[r], name[r]);
  std::fprintf(out, "\n");
  const std::size_t frames = f.keypoints.empty() ? 0 : f.keypoints[0].size();
  for (std::size_t k = 0; k < frames; ++k) {
    std::fprintf(out, "%zu", k);
    for (int r = 0; r < runs; ++r)
      for (const auto* col : {&f.keypoints, &f.matches, &f.true_matches, &f.inliers}) {
        const double v = (*col)[static_cast<std::size_t>(r)][k];
        if (std::isfinite(v)) std::fprintf(out, ",%.0f", v);
        else std::fprintf(out, ",");
      }
    std::fprintf(out, "\n");
  }
  const bool ok = std::fflush(out) == 0;
  return std::fclose(out) == 0 && ok;
}

// qnav map eval [--json] [--laps L] [--frames-per-lap N] [--filters K] [--map-out FILE] [--out DIR]: the synthetic
// loop of the nav/topo tests (seabed_scene.hpp: radius 0.8 m, 320x240, f 300 px, 2 m altitude) run
// through the chain and the topological map without degradation and under each of the paper's five
// Table-1 filters (vision::table1_filter, seeded per frame; --filters K: only the first K). Per run: trajectory error (max and final,
// % of path), pairs registered, keypoints / inliers, map nodes, revisits recognised (second-pass
// frames matched to a first-lap node within the gate of the true position), frame time (chain +
// signature + map; rendering and degradation not counted).
// Frame k of the synthetic loop: rendered at pose, then (filter > 0) degraded by Table 1's filter with a
// seed of its own; input views the frame the mapper gets.
Status render_eval_frame(const sim::downward::Seabed& seabed, const sim::downward::Camera& cam, const sim::downward::CameraPose& pose,
                         int filter, int k, ImageU8& clean, ImageU8& frame, ConstImageViewU8& input) {
  sim::downward::render(seabed, cam, pose, clean.view());
  input = ConstImageViewU8(clean.view());
  if (filter == 0) return Status::ok();
  vision::UnderwaterDegradation d = vision::table1_filter(filter);
  d.seed = static_cast<std::uint64_t>(filter) * 100003u + static_cast<std::uint64_t>(k);
  input = ConstImageViewU8(frame.view());
  return vision::degrade_underwater(clean.view(), d, frame.view());
}

// The synthetic loop of `map eval`: its geometry and the truth (position of frame k in the frame of
// frame 0, the chain's origin).
struct EvalLoop {
  int frames = 0, lap = 0;
  double radius = 0.8, altitude = 2.0, spacing = 0.2;
  double path_m = 0.0;
  sim::downward::Seabed seabed;
  sim::downward::Camera cam;
  sim::downward::CameraPose p0;
  sim::downward::CameraPose pose(int k) const { return sim::downward::loop_pose(k, lap, radius, altitude); }
  Vec2d truth(int k) const {
    const sim::downward::CameraPose pk = pose(k);
    const double c = std::cos(p0.yaw_rad), sn = std::sin(p0.yaw_rad);
    const Vec2d d(pk.x_m - p0.x_m, pk.y_m - p0.y_m);
    return Vec2d(c * d.x() + sn * d.y(), -sn * d.x() + c * d.y());
  }
};

// What one run of `map eval` (one filter) measured.
struct EvalFilterRun {
  std::vector<FrameRecord> rec;
  std::vector<double> ms, kps, inl, cpu;
  double max_err = 0.0, final_err = std::nan("");
  int ok = 0, second = 0, recognised = 0;
};

// One frame of a run: rendered (and degraded), mapped, scored against the truth into run and fig3.
int eval_frame(const EvalLoop& L, int filter, int k, pipeline::TopoMapper& mapper, MapBuilder& builder, ImageU8& clean, ImageU8& frame,
               std::vector<int>& created_frame, EvalFilterRun& run, Fig3& fig3, std::vector<double>& all_ms, std::vector<double>& all_cpu) {
  ConstImageViewU8 input;
  Status s = render_eval_frame(L.seabed, L.cam, L.pose(k), filter, k, clean, frame, input);
  if (!s) {
    std::fprintf(stderr, "map eval: degrade: %s\n", s.message());
    return 1;
  }
  FrameRecord r;
  const auto t0 = Clock::now();
  const double c0 = cpu_ms();
  pipeline::MapperStep m;
  s = mapper.step(input, L.altitude, m);
  r.take(m);
  r.chain_cpu_ms = cpu_ms() - c0;
  r.ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  if (!s) return 1;
  run.cpu.push_back(r.chain_cpu_ms);
  all_cpu.push_back(r.chain_cpu_ms);
  if (builder.path != nullptr && r.place.kind == topo::ObserveKind::kCreated) builder.save();
  run.ms.push_back(r.ms);
  all_ms.push_back(r.ms);
  run.kps.push_back(r.step.keypoints);
  fig3.record(static_cast<std::size_t>(filter), static_cast<std::size_t>(k), r.step,
              [&] { return count_true_matches(mapper.chain(), L.cam, L.pose(k), L.pose(static_cast<int>(r.step.keyframe_index))); });
  if (r.step.status == topo::StepStatus::kOk) {
    ++run.ok;
    if (k > 0) run.inl.push_back(r.step.inliers);
    const double e = (r.step.pose.position_m - L.truth(k)).norm();
    run.max_err = std::max(run.max_err, e);
    run.final_err = e;
  }
  if (r.observed && r.place.kind == topo::ObserveKind::kCreated && r.place.node < created_frame.size()) created_frame[r.place.node] = k;
  if (k >= L.lap + 3) {
    ++run.second;
    const topo::TopoMap& map = builder.map();
    if (r.observed && r.place.kind == topo::ObserveKind::kMatched && map.active(r.place.node) && created_frame[r.place.node] >= 0 &&
        created_frame[r.place.node] < L.lap && (map.node(r.place.node).position - L.truth(k)).norm() <= map.config().gate)
      ++run.recognised;
  }
  run.rec.push_back(r);
  return 0;
}

// What every run adds to the report: the JSON objects (runs, errs), the text lines, the medians.
struct EvalReport {
  bool json = false;
  std::string out, errs;  // per-run objects; traj_error_pct per filter
  std::vector<double> all_ms, all_cpu;
  double recognised_none = std::nan("");
  int worst_rc = 0;
};

void report_filter_run(const EvalLoop& L, int filter, const EvalFilterRun& run, const MapBuilder& builder, EvalReport& rep) {
  const char* name[] = {"none", "filter1", "filter2", "filter3", "filter4", "filter5"};
  const double err_pct = 100.0 * run.max_err / L.path_m, final_pct = 100.0 * run.final_err / L.path_m;
  const double rec_pct = run.second > 0 ? 100.0 * run.recognised / run.second : std::nan("");
  if (filter == 0) rep.recognised_none = rec_pct;
  if (run.ok < L.frames) rep.worst_rc = 1;
  const topo::TopoCounters& c = builder.map().counters();
  const std::size_t nodes = builder.map().node_count(), edges = builder.map().edge_count();
  const unsigned mismatch = c.get(topo::TopoCounter::kMismatch);
  char buf[768];
  std::snprintf(buf, sizeof buf,
                "%s\"%s\": {\"traj_error_pct\": %.4f, \"final_error_pct\": %.4f, \"frames_ok\": %d, \"frames\": %d, "
                "\"keypoints_median\": %.0f, \"inliers_median\": %.0f, \"nodes\": %zu, \"edges\": %zu, \"mismatch\": %u, "
                "\"revisits_recognised_pct\": %s, \"frame_ms_median\": %.3f, \"frame_cpu_ms_median\": %.3f}",
                filter ? ", " : "", name[filter], err_pct, final_pct, run.ok, L.frames, median(run.kps), median(run.inl), nodes, edges, mismatch,
                json_pct(rec_pct).c_str(), median(run.ms), median(run.cpu));
  rep.out += buf;
  std::snprintf(buf, sizeof buf, "%s\"%s\": %.4f", filter ? ", " : "", name[filter], err_pct);
  rep.errs += buf;
  if (!rep.json)
    std::printf("%-8s traj error max %.3f %% (final %.3f %%) of path; %d/%d frames ok; keypoints %.0f, inliers %.0f; map %zu nodes, "
                "%zu edges, %u mismatches; revisits recognised %.1f %% (%d/%d); frame %.2f ms median (CPU %.2f ms)\n",
                name[filter], err_pct, final_pct, run.ok, L.frames, median(run.kps), median(run.inl), nodes, edges, mismatch, rec_pct, run.recognised,
                run.second, median(run.ms), median(run.cpu));
}

// One run of `map eval`: the loop under one filter (0: clean; the clean run also writes --map-out,
// the mosaic and the map CSVs). 0, or the command's exit code.
int eval_filter(const EvalLoop& L, int filter, ImageU8& clean, ImageU8& frame, const char* map_out, const char* out_dir, Fig3& fig3,
                EvalReport& rep) {
  const vision::PinholeRadTan pinhole = vision::ideal_pinhole(L.cam.f, L.cam.cx, L.cam.cy, L.cam.width, L.cam.height);
  const pipeline::TopoMapperConfig config =
      pipeline::topo_mapper_config(L.cam.width, L.cam.height, true, pinhole, false, true, true, L.spacing, 1024);
  ArenaStorage arena(pipeline::TopoMapper::arena_bytes(config));
  pipeline::TopoMapper mapper;
  MapBuilder builder;
  builder.mapper = &mapper;
  Status s = mapper.init(config, arena);
  if (!s) {
    std::fprintf(stderr, "map eval: init: %s\n", s.message());
    return 1;
  }
  if (filter == 0) builder.path = map_out;
  if (filter == 0 && out_dir != nullptr) mkdir(out_dir, 0755);
  EvalFilterRun run;
  std::vector<int> created_frame(1024, -1);
  const double none = std::nan("");
  for (auto* col : {&fig3.keypoints, &fig3.matches, &fig3.true_matches, &fig3.inliers}) col->emplace_back(L.frames, none);
  for (int k = 0; k < L.frames; ++k)
    if (const int rc = eval_frame(L, filter, k, mapper, builder, clean, frame, created_frame, run, fig3, rep.all_ms, rep.all_cpu); rc != 0) return rc;
  if (builder.path != nullptr) builder.save();
  if (filter == 0 && out_dir != nullptr) {  // the clean run's mosaic: the frames rendered again
    const MosaicFrameSource src{[&](std::size_t i, ImageU8& buf) {
                                  sim::downward::render(L.seabed, L.cam, L.pose(static_cast<int>(i)), buf.view());
                                  return true;
                                },
                                L.cam.width, L.cam.height};
    (void)write_map_mosaic(std::string(out_dir) + "/map_mosaic.png", src, run.rec, &builder.map(), true, mapper.chain().metres_per_px(),
                           "qnav map eval (synthetic loop, no filter)");
  }
  if (filter == 0 && out_dir != nullptr && !builder.write_csv(out_dir, L.altitude / L.cam.f)) {
    std::fprintf(stderr, "map eval: writing the map CSVs in %s failed\n", out_dir);
    return 1;
  }
  if (!builder.status) {
    std::fprintf(stderr, "map eval: writing %s: %s\n", map_out, builder.status.message());
    return 1;
  }
  report_filter_run(L, filter, run, builder, rep);
  return 0;
}

int run_eval() {
  EvalReport rep;
  rep.json = g_opt.json;
  const double laps = g_opt.laps;
  const long per_lap = g_opt.per_lap, filters = g_opt.filters;
  const char* map_out = opt_or_null(g_opt.map_out);
  const char* out_dir = opt_or_null(g_opt.out);
  const char* fig3_path = opt_or_null(g_opt.fig3_csv);
  Fig3 fig3;
  if (out_dir != nullptr) {
    if (const std::string e = qnav::cli::make_dirs(out_dir); !e.empty()) {
      std::fprintf(stderr, "map eval: %s\n", e.c_str());
      return 1;
    }
  }
  EvalLoop L;
  L.frames = static_cast<int>(std::lround(laps * static_cast<double>(per_lap)));
  L.lap = static_cast<int>(per_lap);
  L.p0 = L.pose(0);
  L.path_m = 2.0 * 3.14159265358979323846 * L.radius * L.frames / L.lap;
  Result<ImageU8> clean = ImageU8::allocate(L.cam.width, L.cam.height);
  Result<ImageU8> frame = ImageU8::allocate(L.cam.width, L.cam.height);
  if (!clean || !frame) return 1;
  if (!rep.json)
    std::printf("synthetic loop: %d frames (%.2f laps of r = %.1f m), path %.2f m, node spacing %.2f m\n", L.frames, laps, L.radius, L.path_m, L.spacing);
  for (int filter = 0; filter <= static_cast<int>(filters); ++filter)
    if (const int rc = eval_filter(L, filter, *clean, *frame, map_out, out_dir, fig3, rep); rc != 0) return rc;
  if (fig3_path != nullptr && !write_fig3_csv(fig3_path, fig3, static_cast<int>(filters) + 1)) {
    std::fprintf(stderr, "map eval: writing %s failed: %s\n", fig3_path, std::strerror(errno));
    return 1;
  }
  char tail[256];
  std::snprintf(tail, sizeof tail, ", \"path_m\": %.4f, \"node_spacing_m\": %.2f, \"revisits_recognised_pct\": %s, \"frame_ms_median\": %.3f, \"frame_cpu_ms_median\": %.3f}",
                L.path_m, L.spacing, json_pct(rep.recognised_none).c_str(), median(rep.all_ms), median(rep.all_cpu));
  if (rep.json) std::printf("{\"traj_error_pct\": {%s}, \"runs\": {%s}%s\n", rep.errs.c_str(), rep.out.c_str(), tail);
  return rep.worst_rc;
}

// What run_map's parts share: the inputs the options name, the mapper's configuration, the frames.
struct MapRun {
  std::vector<std::string> files;
  vision::PinholeRadTan cam;
  bool have_camera = false;
  bool undistort = true;
  double altitude = 0.0;
  std::vector<std::pair<std::string, NavPose>> poses;
  int W = 0, H = 0;
  const char* map_out = nullptr;
  bool metric = false, mapping = false;
  pipeline::TopoMapperConfig config;
  std::vector<FrameRecord> rec;
};

// Image rotation (content, clockwise on screen positive) = -heading of the chain.
double image_rot_deg(const FrameRecord& r) { return 0.0 - rad_to_deg(r.step.pose.heading_rad) + 0.0; }

// The options checked, the frame list, the camera, the poses and the first frame (which fixes the
// size) read, the mapper configured. 0 when the run can go on, else the exit code.
int load_map_run(MapRun& run, Result<ImageU8>& first) {
  if (g_opt.images.empty()) {
    std::fprintf(stderr, "qnav map: give --images DIR, or `route` / `eval` (qnav help map)\n");
    return 2;
  }
  const char* images = g_opt.images.c_str();
  const char* poses_path = opt_or_null(g_opt.poses);
  const char* camera_path = opt_or_null(g_opt.camera);
  run.undistort = !g_opt.no_undistort;
  run.altitude = g_opt.altitude;
  if (const std::string e = qnav::cli::input_dir_problem(images); !e.empty()) {
    std::fprintf(stderr, "map: --images %s\n", e.c_str());
    return 1;
  }
  std::string err;
  if (!tools::list_image_files(images, run.files, err)) {
    std::fprintf(stderr, "map: %s\n", err.c_str());
    return 1;
  }
  if (static_cast<long>(run.files.size()) > g_opt.frames) run.files.resize(static_cast<std::size_t>(g_opt.frames));
  run.have_camera = camera_path != nullptr;
  if (run.have_camera) {
    Result<vision::PinholeRadTan> c = tools::read_opencv_camera(camera_path);
    if (!c) {
      std::fprintf(stderr, "map: %s: %s\n", camera_path, c.status().message());
      return 1;
    }
    run.cam = c.value();
  }
  if (run.altitude > 0.0 && !run.have_camera) {
    std::fprintf(stderr, "map: --altitude needs --camera (fx for metres per pixel)\n");
    return 2;
  }
  if (poses_path != nullptr && !read_poses(poses_path, run.poses, err)) {
    std::fprintf(stderr, "map: %s\n", err.c_str());
    return 1;
  }
  first = tools::read_image_gray8(run.files[0].c_str());
  if (!first) {
    std::fprintf(stderr, "map: %s: %s\n", run.files[0].c_str(), first.status().message());
    return 1;
  }
  run.W = first->width(), run.H = first->height();
  if (run.have_camera && (run.cam.width != run.W || run.cam.height != run.H)) {
    std::fprintf(stderr, "map: camera is %dx%d, frames are %dx%d\n", run.cam.width, run.cam.height, run.W, run.H);
    return 1;
  }
  // The topological map (when --map-out or --node-spacing is given).
  run.map_out = opt_or_null(g_opt.map_out);
  run.metric = run.altitude > 0.0 && run.have_camera;
  run.mapping = run.map_out != nullptr || !std::isnan(g_opt.node_spacing);
  run.config = pipeline::topo_mapper_config(run.W, run.H, run.have_camera, run.cam, run.undistort, run.mapping, run.metric, g_opt.node_spacing,
                                            static_cast<std::size_t>(g_opt.max_nodes));
  run.config.chain.fundamental_filter = g_opt.fundamental;
  const long gap = g_opt.keyframe_gap > 0 ? g_opt.keyframe_gap : static_cast<long>(run.config.chain.max_keyframe_gap);
  run.config.chain.max_keyframe_gap = static_cast<std::uint32_t>(gap);
  return 0;
}

// Every frame through the mapper, timed, into run.rec; the map file rewritten after each new node.
int map_frames(MapRun& run, pipeline::TopoMapper& mapper, MapBuilder& builder, Result<ImageU8>& first) {
  const std::vector<std::string>& files = run.files;
  Status s;
  for (std::size_t i = 0; i < files.size(); ++i) {
    FrameRecord r;
    r.file = basename_of(files[i]);
    for (const auto& p : run.poses)
      if (p.first == r.file) r.nav = p.second;
    Result<ImageU8> img = i == 0 ? std::move(first) : tools::read_image_gray8(files[i].c_str());
    const auto t0 = Clock::now();
    pipeline::MapperStep m;
    if (!img) {
      std::fprintf(stderr, "map: %s: %s (frame counted as bad input)\n", files[i].c_str(), img.status().message());
      s = mapper.unreadable_frame(m);
    } else {
      ConstImageViewU8 input;
      s = mapper.undistort(img->view(), input);  // a frame of another size passes through, refused as kBadInput (size)
      const auto t1 = Clock::now();
      const double c1 = cpu_ms();
      if (s) s = mapper.register_frame(input, run.altitude, m);
      r.chain_cpu_ms = cpu_ms() - c1;
      if (mapper.undistorts()) r.chain_ms = std::chrono::duration<double, std::milli>(Clock::now() - t1).count();
    }
    if (s && m.chain.status == topo::StepStatus::kOk) {
      const auto t2 = Clock::now();
      mapper.observe(m);
      r.map_ms = std::chrono::duration<double, std::milli>(Clock::now() - t2).count();
    }
    r.take(m);
    r.ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    if (r.chain_ms == 0.0) r.chain_ms = r.ms - r.map_ms;
    if (!s) {
      std::fprintf(stderr, "map: %s: %s\n", files[i].c_str(), s.message());
      return 1;
    }
    if (run.mapping && builder.path != nullptr && r.place.kind == topo::ObserveKind::kCreated) builder.save();  // not timed in ms
    run.rec.push_back(r);
  }
  return 0;
}

// The run's figures: registrations, rotation against the navigation, paths, the chain aligned to the
// navigation (each record's aligned position set).
struct MapSummary {
  int registered = 0;
  std::vector<double> inliers, keypoints, ms, chain_ms, chain_cpu;
  double rot_chain = 0.0, rot_nav = 0.0;
  bool have_nav = false;
  std::size_t span_a = 0, span_b = 0;
  double span_chain = std::nan(""), span_nav = std::nan(""), span_rms = std::nan(""), span_max = std::nan("");
  double path_px = 0.0, nav_path = 0.0, net_px = 0.0, nav_net = 0.0, mpp = 0.0, implied_alt = std::nan("");
  Alignment al;
};

MapSummary summarise_map(MapRun& run, const topo::HomographyChain& chain) {
  std::vector<FrameRecord>& rec = run.rec;
  MapSummary m;
  const std::size_t n = rec.size();
  for (std::size_t i = 0; i < n; ++i) {
    m.keypoints.push_back(rec[i].step.keypoints);
    m.ms.push_back(rec[i].ms);
    m.chain_ms.push_back(rec[i].chain_ms);
    m.chain_cpu.push_back(rec[i].chain_cpu_ms);
    if (i > 0 && rec[i].step.status == topo::StepStatus::kOk && !rec[i].step.reference) {
      ++m.registered;
      m.inliers.push_back(rec[i].step.inliers);
    }
  }
  m.rot_chain = image_rot_deg(rec[n - 1]) - image_rot_deg(rec[0]);
  m.have_nav = rec[0].nav.valid && rec[n - 1].nav.valid;
  m.rot_nav = m.have_nav ? wrap_deg(rec[n - 1].nav.yaw_deg - rec[0].nav.yaw_deg) : std::nan("");
  // Inside the navigation's own span (pose_note == interpolated): first and last such frame.
  m.span_a = n, m.span_b = n;
  for (std::size_t i = 0; i < n; ++i)
    if (rec[i].nav.valid && rec[i].nav.interpolated) {
      if (m.span_a == n) m.span_a = i;
      m.span_b = i;
    }
  const std::size_t span_a = m.span_a, span_b = m.span_b;
  if (span_a < n && span_b > span_a) {
    m.span_chain = image_rot_deg(rec[span_b]) - image_rot_deg(rec[span_a]);
    m.span_nav = wrap_deg(rec[span_b].nav.yaw_deg - rec[span_a].nav.yaw_deg);
    double ss = 0.0, mx = 0.0;
    int cnt = 0;
    for (std::size_t i = span_a; i <= span_b; ++i) {
      if (!rec[i].nav.valid) continue;
      const double d = (image_rot_deg(rec[i]) - image_rot_deg(rec[span_a])) - wrap_deg(rec[i].nav.yaw_deg - rec[span_a].nav.yaw_deg);
      ss += d * d;
      mx = std::max(mx, std::abs(d));
      ++cnt;
    }
    m.span_rms = std::sqrt(ss / std::max(cnt, 1));
    m.span_max = mx;
  }
  // Paths.
  const topo::ChainPose& p0 = rec[0].step.pose;
  Vec2d last_px = p0.position_px;
  for (std::size_t i = 1; i < n; ++i) {
    if (rec[i].step.status == topo::StepStatus::kOk) {
      m.path_px += (rec[i].step.pose.position_px - last_px).norm();
      last_px = rec[i].step.pose.position_px;
    }
    if (rec[i].nav.valid && rec[i - 1].nav.valid) m.nav_path += std::hypot(rec[i].nav.x - rec[i - 1].nav.x, rec[i].nav.y - rec[i - 1].nav.y);
  }
  m.net_px = (last_px - p0.position_px).norm();
  m.nav_net = m.have_nav ? std::hypot(rec[n - 1].nav.x - rec[0].nav.x, rec[n - 1].nav.y - rec[0].nav.y) : std::nan("");
  m.mpp = chain.metres_per_px();
  // Alignment of the chain to the navigation (rotation [+ scale when no altitude], mirror chosen by fit).
  std::vector<Vec2d> a, b;
  for (std::size_t i = 0; i < n; ++i)
    if (rec[i].step.status == topo::StepStatus::kOk && rec[i].nav.valid) {
      a.push_back(rec[i].step.pose.position_px - p0.position_px);
      b.push_back(Vec2d(rec[i].nav.x - rec[0].nav.x, rec[i].nav.y - rec[0].nav.y));
    }
  m.al = m.have_nav ? align(a, b, m.mpp > 0.0 ? m.mpp : 0.0) : Alignment{};
  for (std::size_t i = 0; i < n; ++i)
    if (m.al.valid) rec[i].aligned = m.al.apply(rec[i].step.pose.position_px - p0.position_px) + Vec2d(rec[0].nav.x, rec[0].nav.y);
  // Only when the scale was fitted (no --altitude): the altitude that scale stands for.
  m.implied_alt = (m.al.valid && run.have_camera && !(m.mpp > 0.0)) ? m.al.scale * run.cam.fx : std::nan("");
  return m;
}

// map_trajectory.csv, one row per frame.
bool write_map_trajectory_csv(const std::string& csv_path, const MapRun& run, const MapSummary& m) {
  const std::vector<FrameRecord>& rec = run.rec;
  FILE* f = std::fopen(csv_path.c_str(), "w");
  if (f == nullptr) {
    std::fprintf(stderr, "map: cannot write %s: %s\n", csv_path.c_str(), std::strerror(errno));
    return false;
  }
  std::fprintf(f, "frame,file,status,new_keyframe,keyframe,keypoints,matches,f_inliers,inliers,rms_px,overlap,x_px,y_px,"
                  "heading_deg,image_rot_deg,x_m,y_m,aligned_x_m,aligned_y_m,nav_x_m,nav_y_m,nav_yaw_deg,nav_interpolated,ms,chain_ms,"
                  "map_node,map_kind,map_revisit,map_similarity\n");
  for (std::size_t i = 0; i < rec.size(); ++i) {
    const topo::ChainStep& st = rec[i].step;
    const bool ok = st.status == topo::StepStatus::kOk;
    std::fprintf(f, "%zu,%s,%s,%d,%u,%u,%u,%u,%u,%.3f,%.3f,%.3f,%.3f,%.4f,%.4f,", i, rec[i].file.c_str(), topo::to_string(st.status),
                 st.new_keyframe ? 1 : 0, st.keyframe_index, st.keypoints, st.matches, st.fundamental_inliers, st.inliers, st.rms_px,
                 st.overlap, st.pose.position_px.x(), st.pose.position_px.y(), rad_to_deg(st.pose.heading_rad), image_rot_deg(rec[i]));
    if (st.pose.metric) std::fprintf(f, "%.4f,%.4f,", st.pose.position_m.x(), st.pose.position_m.y());
    else std::fprintf(f, ",,");
    if (m.al.valid && ok) std::fprintf(f, "%.4f,%.4f,", rec[i].aligned.x(), rec[i].aligned.y());
    else std::fprintf(f, ",,");
    if (rec[i].nav.valid) std::fprintf(f, "%.4f,%.4f,%.4f,%d,", rec[i].nav.x, rec[i].nav.y, rec[i].nav.yaw_deg, rec[i].nav.interpolated ? 1 : 0);
    else std::fprintf(f, ",,,,");
    std::fprintf(f, "%.3f,%.3f,", rec[i].ms, rec[i].chain_ms);
    if (rec[i].observed) {
      std::fprintf(f, "%d,%s,%d,%.4f\n", rec[i].place.node == topo::kNoNode ? -1 : static_cast<int>(rec[i].place.node),
                   topo::to_string(rec[i].place.kind), rec[i].place.revisit ? 1 : 0, rec[i].place.similarity);
    } else {
      std::fprintf(f, ",,,\n");
    }
  }
  const bool write_ok = std::fflush(f) == 0;
  std::fclose(f);
  if (!write_ok) {
    std::fprintf(stderr, "map: writing %s failed\n", csv_path.c_str());
    return false;
  }
  return true;
}

// The outputs in --out: the trajectory CSV, the map's CSVs, the plot and the mosaic. False: a write failed.
bool write_map_outputs(const char* out_dir, const MapRun& run, const MapSummary& m, pipeline::TopoMapper& mapper, MapBuilder& builder,
                       std::string& csv_path, std::string& png_path, std::string& mosaic_path) {
  const std::vector<std::string>& files = run.files;
  mkdir(out_dir, 0755);
  csv_path = std::string(out_dir) + "/map_trajectory.csv";
  png_path = std::string(out_dir) + "/map_trajectory.png";
  if (!write_map_trajectory_csv(csv_path, run, m)) return false;
  if (run.mapping && !builder.write_csv(out_dir, m.mpp)) {
    std::fprintf(stderr, "map: writing %s/map_nodes.csv or map_edges.csv failed\n", out_dir);
    return false;
  }
    const std::string script = source_root() + "/scripts/map_plot.py";
    struct stat st {};
    if (g_opt.no_plot) {
      png_path.clear();
    } else if (stat("/usr/bin/python3", &st) != 0 || stat(script.c_str(), &st) != 0) {
      std::fprintf(stderr, "map: no plot (%s or /usr/bin/python3 missing)\n", script.c_str());
      png_path.clear();
    } else {
      const std::string cmd = "/usr/bin/python3 '" + script + "' '" + csv_path + "' '" + png_path + "'";
      if (std::system(cmd.c_str()) != 0) {
        std::fprintf(stderr, "map: plot failed: %s\n", cmd.c_str());
        png_path.clear();
      }
    }
    if (!g_opt.no_plot) {
      const MosaicFrameSource src{[&](std::size_t i, ImageU8& buf) {
                                    Result<ImageU8> img = tools::read_image_gray8(files[i].c_str());
                                    ConstImageViewU8 v;
                                    if (!img || !mapper.undistort(img->view(), v) || v.width() != buf.width() || v.height() != buf.height())
                                      return false;
                                    for (int r = 0; r < v.height(); ++r) std::memcpy(buf.view().row(r), v.row(r), static_cast<std::size_t>(v.width()));
                                    return true;
                                  },
                                  run.W, run.H};
      mosaic_path = std::string(out_dir) + "/map_mosaic.png";
      if (!write_map_mosaic(mosaic_path, src, run.rec, run.mapping ? &builder.map() : nullptr, run.metric, m.mpp, "qnav map")) mosaic_path.clear();
    }
  return true;
}

// The report on stdout: one JSON object (--json) or text.
void print_map_report(const MapRun& run, const MapSummary& m, const MapBuilder& builder, const topo::HomographyChain& chain,
                      const std::string& csv_path, const std::string& png_path, const std::string& mosaic_path) {
  const std::size_t n = run.rec.size();
  const int W = run.W, H = run.H;
  const bool have_camera = run.have_camera, undistort = run.undistort, metric = run.metric, mapping = run.mapping;
  const char* map_out = run.map_out;
  const double spacing = run.config.map.node_spacing;
  const int registered = m.registered;
  const std::vector<double>&inliers = m.inliers, &keypoints = m.keypoints, &ms = m.ms, &chain_ms = m.chain_ms, &chain_cpu = m.chain_cpu;
  const double rot_chain = m.rot_chain, rot_nav = m.rot_nav, span_chain = m.span_chain, span_nav = m.span_nav, span_rms = m.span_rms,
               span_max = m.span_max, path_px = m.path_px, net_px = m.net_px, nav_path = m.nav_path, nav_net = m.nav_net, mpp = m.mpp,
               implied_alt = m.implied_alt;
  const bool have_nav = m.have_nav;
  const std::size_t span_a = m.span_a, span_b = m.span_b;
  const Alignment& al = m.al;
  const int pairs = static_cast<int>(n) - 1;
  auto num = [](double v) { return std::isfinite(v) ? std::to_string(v) : std::string("null"); };
  std::vector<double> map_ms;
  for (const FrameRecord& r : run.rec)
    if (r.observed) map_ms.push_back(r.map_ms);
  std::string map_json = "\"map\": null, ";
  if (mapping) {
    const topo::TopoCounters& c = builder.map().counters();
    char buf[1024];
    std::snprintf(buf, sizeof buf,
                  "\"map\": {\"nodes\": %zu, \"edges\": %zu, \"units\": \"%s\", \"node_spacing\": %g, \"revisits\": %u, "
                  "\"revisit_frames\": %d, \"mismatch\": %u, \"full\": %u, \"pruned\": %u, \"edges_aged\": %u, \"edge_too_long\": %u, "
                  "\"map_ms_median\": %s, \"file\": \"%s\", \"saves\": %d, \"save_ms_median\": %s}, ",
                  builder.map().node_count(), builder.map().edge_count(), metric ? "m" : "px", spacing, builder.map().revisits(),
                  builder.revisit_frames(run.rec), c.get(topo::TopoCounter::kMismatch), c.get(topo::TopoCounter::kNodeCapacity),
                  c.get(topo::TopoCounter::kNodesPruned), c.get(topo::TopoCounter::kEdgesAged), c.get(topo::TopoCounter::kEdgeTooLong),
                  num(median(map_ms)).c_str(), map_out ? map_out : "", builder.saves, num(median(builder.save_ms)).c_str());
    map_json = buf;
  }
  if (g_opt.json) {
    std::printf("{%s\"frames\": %zu, \"pairs_registered\": %d, \"pairs_total\": %d, \"keyframes\": %u, "
                "\"keypoints_median\": %s, \"inliers_median\": %s, \"inliers_min\": %s, "
                "\"yaw_chain_deg\": %s, \"yaw_nav_deg\": %s, \"yaw_error_deg\": %s, "
                "\"span_first\": %d, \"span_last\": %d, \"yaw_span_chain_deg\": %s, \"yaw_span_nav_deg\": %s, "
                "\"yaw_span_error_deg\": %s, \"yaw_span_rms_deg\": %s, \"yaw_span_max_deg\": %s, "
                "\"path_px\": %s, \"net_px\": %s, \"metres_per_px\": %s, \"path_m\": %s, \"nav_path_m\": %s, \"nav_net_m\": %s, "
                "\"align_scale_m_per_px\": %s, \"align_rotation_deg\": %s, \"align_mirrored\": %s, \"align_rms_m\": %s, "
                "\"implied_altitude_m\": %s, \"frame_ms_median\": %s, \"frame_ms_max\": %s, \"chain_ms_median\": %s, \"chain_cpu_ms_median\": %s, \"undistorted\": %s, "
                "\"fundamental_filter\": %s, \"csv\": \"%s\", \"png\": \"%s\", \"mosaic_png\": \"%s\"}\n",
                map_json.c_str(), n, registered, pairs, chain.keyframes(), num(median(keypoints)).c_str(), num(median(inliers)).c_str(),
                num(inliers.empty() ? std::nan("") : *std::min_element(inliers.begin(), inliers.end())).c_str(),
                num(rot_chain).c_str(), num(rot_nav).c_str(), num(rot_chain - rot_nav).c_str(),
                span_a < n ? static_cast<int>(span_a) : -1, span_b < n ? static_cast<int>(span_b) : -1, num(span_chain).c_str(),
                num(span_nav).c_str(), num(span_chain - span_nav).c_str(), num(span_rms).c_str(), num(span_max).c_str(),
                num(path_px).c_str(), num(net_px).c_str(), num(mpp > 0 ? mpp : std::nan("")).c_str(),
                num(mpp > 0 ? path_px * mpp : (al.valid ? path_px * al.scale : std::nan(""))).c_str(), num(have_nav ? nav_path : std::nan("")).c_str(),
                num(nav_net).c_str(), num(al.valid ? al.scale : std::nan("")).c_str(),
                num(al.valid ? rad_to_deg(al.rotation_rad) : std::nan("")).c_str(), al.valid ? (al.mirrored ? "true" : "false") : "null",
                num(al.valid ? al.rms_m : std::nan("")).c_str(), num(implied_alt).c_str(), num(median(ms)).c_str(),
                num(*std::max_element(ms.begin(), ms.end())).c_str(), num(median(chain_ms)).c_str(), num(median(chain_cpu)).c_str(), (have_camera && undistort) ? "true" : "false",
                run.config.chain.fundamental_filter ? "true" : "false", csv_path.c_str(), png_path.c_str(), mosaic_path.c_str());
  } else {
    std::printf("frames %zu (%dx%d)%s%s\n", n, W, H, (have_camera && undistort) ? ", undistorted" : "",
                run.config.chain.fundamental_filter ? ", F both-accept filter" : "");
    std::printf("pairs registered      %d / %d (keyframes %u)\n", registered, pairs, chain.keyframes());
    std::printf("keypoints per frame   median %.0f\n", median(keypoints));
    if (!inliers.empty())
      std::printf("inliers per pair      median %.0f, min %.0f\n", median(inliers), *std::min_element(inliers.begin(), inliers.end()));
    std::printf("image rotation        frame 0 -> %zu: chain %+.2f deg", n - 1, rot_chain);
    if (have_nav) std::printf(", navigation yaw %+.2f deg, error %+.2f deg", rot_nav, rot_chain - rot_nav);
    std::printf("\n");
    if (std::isfinite(span_chain))
      std::printf("  inside the nav span frames %zu -> %zu: chain %+.2f deg, nav %+.2f deg, error %+.2f deg; per frame RMS %.2f, max %.2f deg\n",
                  span_a, span_b, span_chain, span_nav, span_chain - span_nav, span_rms, span_max);
    std::printf("path                  chain %.1f px (net %.1f px)", path_px, net_px);
    if (mpp > 0) std::printf(" = %.3f m at %.5f m/px", path_px * mpp, mpp);
    std::printf("\n");
    if (have_nav) {
      std::printf("navigation path       %.3f m (sum of frame-to-frame steps; net %.3f m)\n", nav_path, nav_net);
      if (al.valid)
        std::printf("chain aligned to nav  %.5f m/px %s, rotation %.1f deg%s, RMS %.3f m; chain path %.3f m\n", al.scale,
                    mpp > 0 ? "(from altitude)" : std::isfinite(implied_alt) ? ("(fitted: implied altitude " + std::to_string(implied_alt).substr(0, 4) + " m)").c_str() : "(fitted)",
                    rad_to_deg(al.rotation_rad),
                    al.mirrored ? ", mirrored" : "", al.rms_m, path_px * al.scale);
    }
    std::printf("frame time            median %.2f ms, max %.2f ms (undistortion + chain); chain alone median %.2f ms (CPU %.2f ms)\n",
                median(ms), *std::max_element(ms.begin(), ms.end()), median(chain_ms), median(chain_cpu));
    if (mapping) {
      const topo::TopoCounters& c = builder.map().counters();
      std::printf("topological map       %zu nodes, %zu edges (node spacing %g %s); revisits %u; refused: appearance mismatch %u, "
                  "map full %u; pruned %u\n",
                  builder.map().node_count(), builder.map().edge_count(), spacing, metric ? "m" : "px", builder.map().revisits(),
                  c.get(topo::TopoCounter::kMismatch), c.get(topo::TopoCounter::kNodeCapacity), c.get(topo::TopoCounter::kNodesPruned));
      std::printf("map update            median %.3f ms per frame (signature + map); file %s rewritten %d times, median %.2f ms\n",
                  median(map_ms), map_out ? map_out : "(none)", builder.saves, median(builder.save_ms));
    }
    if (!csv_path.empty())
      std::printf("wrote %s%s%s%s%s\n", csv_path.c_str(), png_path.empty() ? "" : ", ", png_path.c_str(), mosaic_path.empty() ? "" : ", ",
                  mosaic_path.c_str());
  }
}

int run_map() {
  MapRun run;
  Result<ImageU8> first = Status(StatusCode::kNotReady, "not read");
  if (const int rc = load_map_run(run, first); rc != 0) return rc;
  const char* out_dir = opt_or_null(g_opt.out);
  if (out_dir != nullptr) {  // the map file may live there and is written from the first node
    if (const std::string e = qnav::cli::make_dirs(out_dir); !e.empty()) {
      std::fprintf(stderr, "map: %s\n", e.c_str());
      return 1;
    }
  }
  ArenaStorage arena(pipeline::TopoMapper::arena_bytes(run.config));
  pipeline::TopoMapper mapper;
  const Status s = mapper.init(run.config, arena);
  if (!s) {
    std::fprintf(stderr, "map: mapper init (chain, undistortion table, topological map): %s\n", s.message());
    return 1;
  }
  MapBuilder builder;
  builder.mapper = &mapper;
  builder.path = run.map_out;
  if (const int rc = map_frames(run, mapper, builder, first); rc != 0) return rc;
  const MapSummary m = summarise_map(run, mapper.chain());
  std::string csv_path, png_path, mosaic_path;
  if (out_dir != nullptr && !write_map_outputs(out_dir, run, m, mapper, builder, csv_path, png_path, mosaic_path)) return 1;
  // The map as it ends (adapted since the last new node), and its figures.
  if (run.mapping && builder.path != nullptr) builder.save();
  if (run.mapping && !builder.status) {
    std::fprintf(stderr, "map: writing the map file %s: %s\n", run.map_out, builder.status.message());
    return 1;
  }
  print_map_report(run, m, builder, mapper.chain(), csv_path, png_path, mosaic_path);
  return m.registered == static_cast<int>(run.rec.size()) - 1 ? 0 : 1;
}

}  // namespace

namespace {
void setup_map(CLI::App& cmd, qnav::cli::Runner& run) {
  using qnav::cli::add_flag;
  using qnav::cli::add_number;
  using qnav::cli::add_text;
  cmd.require_subcommand(0, 1);
  cmd.footer("Runs: qnav map --images DIR [...], qnav map route --map FILE --from A --to B, qnav map eval [...].");
  add_text(cmd, "--images", g_opt.images, "the frames: every .png/.jpg/.jpeg/.pgm in DIR, in name order")->type_name("DIR");
  add_text(cmd, "--poses", g_opt.poses, "navigation poses: CSV with file, x, y, yaw_deg (matched by file name)")->type_name("CSV");
  add_text(cmd, "--camera", g_opt.camera, "OpenCV-style camera YAML (frames undistorted unless --no-undistort)")->type_name("YAML");
  add_number(cmd, "--altitude", g_opt.altitude, "altitude above the seabed, constant", "m", 1e-6, 1e6)
      ->description("altitude above the seabed, constant: metric scale with --camera (m; default: none, mosaic pixels; > 0)");
  add_text(cmd, "--out", g_opt.out, "folder for map_trajectory.csv/.png and the map CSVs (created)")->type_name("DIR");
  add_flag(cmd, "--json", g_opt.json, "one JSON object on stdout");
  add_flag(cmd, "--no-undistort", g_opt.no_undistort, "do not undistort the frames");
  add_flag(cmd, "--fundamental", g_opt.fundamental, "the paper's F both-accept outlier rule before H");
  add_number(cmd, "--keyframe-gap", g_opt.keyframe_gap, "a new keyframe at least every N frames", "frames", 1, 100000)
      ->description("a new keyframe at least every N frames; 1 = the frame-to-frame chain (frames; default 30; 1..100000)");
  add_number(cmd, "--frames", g_opt.frames, "frames to use at most", "", 2, 1e9);
  add_flag(cmd, "--no-plot", g_opt.no_plot, "do not draw map_trajectory.png nor map_mosaic.png");
  add_text(cmd, "--map-out", g_opt.map_out, "build the topological map beside the chain, written durably here")->type_name("FILE");
  add_number(cmd, "--node-spacing", g_opt.node_spacing, "topological map node spacing", "", 1e-9, 1e9)
      ->description("topological map node spacing (m with --altitude, else mosaic px; default 0.2 m / 30 px; > 0)");
  add_number(cmd, "--max-nodes", g_opt.max_nodes, "topological map nodes at most", "", 2, 65534);
  run.on(&cmd, run_map);

  CLI::App* r = cmd.add_subcommand("route", "shortest path over a map's edges (Dijkstra, or A* with the Euclidean heuristic)");
  add_text(*r, "--map", g_opt.map, "the topological map file")->required()->type_name("FILE");
  add_number(*r, "--from", g_opt.from, "start node id", "", 0, 65535)->required();
  add_number(*r, "--to", g_opt.to, "goal node id", "", 0, 65535)->required();
  add_flag(*r, "--astar", g_opt.astar, "A* instead of Dijkstra");
  add_flag(*r, "--json", g_opt.json, "one JSON object on stdout");
  run.on(r, run_route);

  CLI::App* e = cmd.add_subcommand("eval", "the nav/topo synthetic loop under the Table-1 filters");
  add_flag(*e, "--json", g_opt.json, "one JSON object on stdout");
  add_number(*e, "--laps", g_opt.laps, "laps of the loop", "laps", 1.05, 5);
  add_number(*e, "--frames-per-lap", g_opt.per_lap, "frames per lap", "frames", 40, 1000);
  add_number(*e, "--filters", g_opt.filters, "Table-1 filters applied (0: clean)", "", 0, 5);
  add_text(*e, "--map-out", g_opt.map_out, "write the map here")->type_name("FILE");
  add_text(*e, "--out", g_opt.out, "folder for the CSVs (created)")->type_name("DIR");
  add_text(*e, "--fig3-csv", g_opt.fig3_csv, "the paper's Fig. 3: keypoints and true matches per frame and run, as CSV")->type_name("FILE");
  run.on(e, run_eval);
}
}  // namespace

QNAV_CLI_COMMAND("map", "downward-camera mapping: homography chain over a frame directory, vs navigation poses", setup_map);
