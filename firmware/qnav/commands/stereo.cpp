// qnav stereo: the vision front end on image files.
//   qnav stereo disparity LEFT RIGHT [--max-disparity N] [--corners N] [--out PNG]
//       Harris corners on LEFT, ZNCC stereo at the corners; prints counts and counters; --out writes
//       the left image with each matched corner coloured by disparity (red = near, blue = far), with
//       pixel axes and a disparity colour bar (firmware/tools/raster_plot.hpp).
//   qnav stereo aloe [--dir DIR]
//       Disparity at Harris corners of the Middlebury Aloe pair against its ground truth.
//   qnav stereo euroc-rectify [DIR] [--out PNG]
//       Rectifies the first EuRoC pair from the two sensor.yaml; prints the row offset of matched
//       corners before and after; --out writes the rectified pair side by side with guide rows.
//   qnav stereo degrade IMAGE [--filter 1..5] [--out PNG]
//       Applies an underwater degradation of Table 1 and prints Harris repeatability against the
//       clean image.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "firmware/tools/stats.hpp"
#include "firmware/cli/cli_app.hpp"
#include "firmware/qnav/command.hpp"
#include "firmware/tools/image_reader.hpp"
#include "firmware/tools/png_writer.hpp"
#include "firmware/tools/raster_plot.hpp"
#include "firmware/tools/sequence_reader.hpp"
#include "firmware/tools/shared_dir.hpp"
#include "firmware/tools/stereo_eval.hpp"
#include "nav/vision/degrade.hpp"
#include "nav/vision/harris.hpp"
#include "nav/vision/rectify.hpp"
#include "nav/vision/stereo.hpp"

namespace {

using namespace qnav;
using namespace qnav::vision;

// Every stereo option (one invocation per process), declared in setup_stereo below.
struct StereoOptions {
  std::string left, right, left_opt, right_opt, out, dir, image;
  long max_d = 64, corners = 500, filter = 4;
};
StereoOptions g_opt;
const char* out_or_null() { return g_opt.out.empty() ? nullptr : g_opt.out.c_str(); }
// --out's folder is created; false (reported) when it cannot be.
bool out_dir_ok() {
  const std::string e = g_opt.out.empty() ? std::string() : qnav::cli::make_parent_dirs(g_opt.out);
  if (!e.empty()) std::fprintf(stderr, "qnav stereo: %s\n", e.c_str());
  return e.empty();
}

struct Detector {
  Detector(int w, int h, int cap) : storage(static_cast<std::size_t>(cap)) {
    HarrisConfig c;
    c.max_width = w;
    c.max_height = h;
    c.max_corners = cap;
    arena = std::make_unique<ArenaStorage>(HarrisDetector::arena_bytes(c));
    status = det.init(c, *arena);
    out = BoundedVector<Corner>(Span<Corner>(storage.data(), storage.size()));
  }
  std::unique_ptr<ArenaStorage> arena;
  std::vector<Corner> storage;
  BoundedVector<Corner> out;
  HarrisDetector det;
  Status status;
};

double median(std::vector<double> v) {
  double m = std::nan("");
  qnav::tools::median_of(v, m);
  return m;
}

void print_counters(const VisionCounters& c) {
  for (std::size_t i = 0; i < c.size(); ++i)
    if (c.count_at(i) > 0) std::printf("  counter %-26s %u\n", c.name_at(i), c.count_at(i));
}

bool load(const char* path, ImageU8& img) {
  if (const std::string e = qnav::cli::input_file_problem(path); !e.empty()) {
    std::fprintf(stderr, "qnav stereo: %s\n", e.c_str());
    return false;
  }
  Result<ImageU8> r = tools::read_image_gray8(path);
  if (!r.is_ok()) {
    std::fprintf(stderr, "qnav stereo: %s: %s\n", path, r.status().message());
    return false;
  }
  img = std::move(r.value());
  return true;
}

// Runs Harris + stereo; fills pts. Returns false on a hard error (printed).
bool run_stereo(const ImageU8& l, const ImageU8& r, int corners, int max_d, Detector& d, std::vector<StereoPoint>& pts,
                StereoMatcher& m) {
  if (!d.status.is_ok()) {
    std::fprintf(stderr, "qnav stereo: harris init: %s\n", d.status.message());
    return false;
  }
  Status s = d.det.detect(l.view(), d.out);
  if (!s.is_ok()) {
    std::fprintf(stderr, "qnav stereo: harris: %s\n", s.message());
    return false;
  }
  StereoConfig sc;
  sc.max_disparity_px = max_d;
  s = m.init(sc, StereoCamera{1.0, l.width() / 2.0, l.height() / 2.0, 1.0});
  if (!s.is_ok()) {
    std::fprintf(stderr, "qnav stereo: stereo init: %s\n", s.message());
    return false;
  }
  pts.assign(static_cast<std::size_t>(corners), StereoPoint{});
  BoundedVector<StereoPoint> out(Span<StereoPoint>(pts.data(), pts.size()));
  s = m.match(l.view(), r.view(), d.out.span(), out);
  if (!s.is_ok()) {
    std::fprintf(stderr, "qnav stereo: match: %s\n", s.message());
    return false;
  }
  pts.resize(out.size());
  return true;
}

int cmd_disparity() {
  const std::string& left = g_opt.left_opt.empty() ? g_opt.left : g_opt.left_opt;
  const std::string& right = g_opt.right_opt.empty() ? g_opt.right : g_opt.right_opt;
  if (left.empty() || right.empty() || (!g_opt.left_opt.empty() && !g_opt.left.empty()) ||
      (!g_opt.right_opt.empty() && !g_opt.right.empty())) {
    std::fprintf(stderr, "qnav stereo disparity: give the pair once: LEFT RIGHT, or --left LEFT --right RIGHT (qnav help stereo disparity)\n");
    return 2;
  }
  const char* lp = left.c_str();
  const char* rp = right.c_str();
  const long max_d = g_opt.max_d, corners = g_opt.corners;
  if (!out_dir_ok()) return 1;
  ImageU8 l, r;
  if (!load(lp, l) || !load(rp, r)) return 1;
  if (l.width() != r.width() || l.height() != r.height()) {
    std::fprintf(stderr, "qnav stereo: left and right sizes differ\n");
    return 1;
  }
  Detector d(l.width(), l.height(), static_cast<int>(corners));
  StereoMatcher m;
  std::vector<StereoPoint> pts;
  if (!run_stereo(l, r, static_cast<int>(corners), static_cast<int>(max_d), d, pts, m)) return 1;
  std::vector<double> ds;
  for (const StereoPoint& p : pts) ds.push_back(static_cast<double>(p.disparity_px));
  std::printf("stereo: %dx%d, %zu corners, %zu matched (%.1f %%), disparity median %.2f px, range %.2f..%.2f px\n", l.width(),
              l.height(), d.out.size(), pts.size(), d.out.size() ? 100.0 * pts.size() / d.out.size() : 0.0, median(ds),
              ds.empty() ? 0.0 : *std::min_element(ds.begin(), ds.end()), ds.empty() ? 0.0 : *std::max_element(ds.begin(), ds.end()));
  print_counters(m.counters());
  if (const char* outp = out_or_null()) {
    std::vector<std::uint8_t> rgb(static_cast<std::size_t>(l.width() * l.height() * 3));
    for (int y = 0; y < l.height(); ++y)
      for (int x = 0; x < l.width(); ++x)
        for (int c = 0; c < 3; ++c) rgb[static_cast<std::size_t>((y * l.width() + x) * 3 + c)] = l(x, y) / 2;
    const double dmax = ds.empty() ? 1.0 : std::max(1.0, *std::max_element(ds.begin(), ds.end()));
    for (const StereoPoint& p : pts) {
      std::uint8_t col[3];  // 1 = near (red), 0 = far (blue)
      tools::plot_colour(tools::PlotColourMap::kBlueGreenRed, static_cast<double>(p.disparity_px) / dmax, col);
      const int cx = static_cast<int>(std::lround(p.x_px)), cy = static_cast<int>(std::lround(p.y_px));
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) {
          const int x = cx + dx, y = cy + dy;
          if (x < 0 || y < 0 || x >= l.width() || y >= l.height()) continue;
          for (int c = 0; c < 3; ++c) rgb[static_cast<std::size_t>((y * l.width() + x) * 3 + c)] = col[c];
        }
    }
    tools::RasterPlot plot;
    char title[96];
    std::snprintf(title, sizeof title, "disparity at %zu matched Harris corners (left image, darkened)", pts.size());
    plot.title = title;
    plot.x = {0.0, 1.0, "column px"};
    plot.y = {0.0, 1.0, "row px"};
    plot.colour_bar = true;
    plot.colour_hi = dmax;
    plot.colour_label = "disparity px (red: near)";
    plot.colour_map = tools::PlotColourMap::kBlueGreenRed;
    const Status s = tools::write_raster_plot_png_rgb(outp, rgb.data(), l.width(), l.height(), l.width() * 3, plot);
    if (!s.is_ok()) {
      std::fprintf(stderr, "qnav stereo: %s: %s\n", outp, s.message());
      return 1;
    }
    std::printf("wrote %s\n", outp);
  }
  return 0;
}

// A default input under the sample data failed to load: say where the data was looked for (1).
int missing_sample_data(bool used_default) {
  const std::string why = used_default ? tools::shared_dir_missing() : std::string();
  if (!why.empty()) std::fprintf(stderr, "qnav stereo: %s\n", why.c_str());
  return 1;
}

int cmd_aloe() {
  const std::string fallback = tools::shared_dir() + "/data/stereo/middlebury_aloe_opencv";
  const std::string dir = g_opt.dir.empty() ? fallback : g_opt.dir;
  ImageU8 l, r, gt;
  if (!load((dir + "/aloeL.jpg").c_str(), l) || !load((dir + "/aloeR.jpg").c_str(), r) || !load((dir + "/aloeGT.png").c_str(), gt))
    return missing_sample_data(dir == fallback);
  Detector d(l.width(), l.height(), 1000);
  StereoMatcher m;
  std::vector<StereoPoint> pts;
  if (!run_stereo(l, r, 1000, 240, d, pts, m)) return 1;
  std::vector<double> err;
  for (const StereoPoint& p : pts) {
    const int g = gt(static_cast<int>(std::lround(p.x_px)), static_cast<int>(std::lround(p.y_px)));
    if (g > 0) err.push_back(std::fabs(static_cast<double>(p.disparity_px) - g));
  }
  const double within1 =
      err.empty() ? 0.0 : static_cast<double>(std::count_if(err.begin(), err.end(), [](double e) { return e <= 1.0; })) / err.size();
  const double within3 =
      err.empty() ? 0.0 : static_cast<double>(std::count_if(err.begin(), err.end(), [](double e) { return e <= 3.0; })) / err.size();
  std::printf("aloe %dx%d: %zu Harris corners, %zu matched, %zu with GT; |d - gt| median %.3f px, within 1 px %.1f %%, within 3 px %.1f %%\n",
              l.width(), l.height(), d.out.size(), pts.size(), err.size(), median(err), 100 * within1, 100 * within3);
  print_counters(m.counters());
  return 0;
}

// Row offsets of strong unique 2D ZNCC matches of left Harris corners in the right image.
std::vector<double> row_offsets(const ImageU8& L, const ImageU8& R) {
  Detector d(L.width(), L.height(), 300);
  if (!d.status.is_ok() || !d.det.detect(L.view(), d.out).is_ok()) return {};
  return tools::epipolar_row_offsets(L.view(), R.view(), Span<const Corner>(d.out.data(), d.out.size()));
}

int cmd_euroc_rectify() {
  if (!out_dir_ok()) return 1;
  const char* dp = g_opt.dir.empty() ? nullptr : g_opt.dir.c_str();
  const std::string dir = dp ? dp : tools::shared_dir() + "/data/stereo/euroc_v1_01_hover40";
  Result<tools::EurocCamera> c0 = tools::read_euroc_camera(dir + "/cam0/sensor.yaml");
  Result<tools::EurocCamera> c1 = tools::read_euroc_camera(dir + "/cam1/sensor.yaml");
  std::vector<tools::StereoFrame> frames;
  const Status fs = tools::read_euroc_sequence(dir, frames);
  if (!c0.is_ok() || !c1.is_ok() || !fs.is_ok()) {
    std::fprintf(stderr, "qnav stereo: %s: %s\n", dir.c_str(),
                 !c0.is_ok() ? c0.status().message() : (!c1.is_ok() ? c1.status().message() : fs.message()));
    return missing_sample_data(dp == nullptr);
  }
  ImageU8 rl, rr;
  if (!load(frames[0].left_path.c_str(), rl) || !load(frames[0].right_path.c_str(), rr)) return 1;
  const int W = rl.width(), H = rl.height();
  const Pose3 T = tools::euroc_stereo_extrinsics(*c0, *c1);
  Result<StereoRectification> rect = stereo_rectify(c0->model, c1->model, T, W, H);
  if (!rect.is_ok()) {
    std::fprintf(stderr, "qnav stereo: rectify: %s\n", rect.status().message());
    return 1;
  }
  RemapConfig rc;
  rc.max_width = W;
  rc.max_height = H;
  ArenaStorage arena(2 * RemapTable::arena_bytes(rc));
  RemapTable tl, tr;
  ImageU8 ol = ImageU8::allocate(W, H).value(), orr = ImageU8::allocate(W, H).value();
  Status s = tl.init(rc, arena);
  if (s.is_ok()) s = tr.init(rc, arena);
  if (s.is_ok()) s = tl.build(c0->model, rect->K, rect->R_left, FlatPortRefraction{}, W, H);
  if (s.is_ok()) s = tr.build(c1->model, rect->K, rect->R_right, FlatPortRefraction{}, W, H);
  if (s.is_ok()) s = tl.apply(rl.view(), ol.view());
  if (s.is_ok()) s = tr.apply(rr.view(), orr.view());
  if (!s.is_ok()) {
    std::fprintf(stderr, "qnav stereo: remap: %s\n", s.message());
    return 1;
  }
  const std::vector<double> after = row_offsets(ol, orr), before = row_offsets(rl, rr);
  std::printf("euroc %s: baseline %.4f m, rectified f %.2f px, cu %.2f, cv %.2f, valid pixels L %.1f %% R %.1f %%\n",
              dir.c_str(), rect->baseline_m, rect->K(0, 0), rect->K(0, 2), rect->K(1, 2), 100.0 * tl.valid_pixels() / (W * H),
              100.0 * tr.valid_pixels() / (W * H));
  std::printf("row offset of matched corners: raw %zu matches median %.3f px; rectified %zu matches median %.3f px\n", before.size(),
              median(before), after.size(), median(after));
  if (const char* outp = out_or_null()) {
    ImageU8 both = ImageU8::allocate(2 * W, H).value();
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const bool guide = y % 40 == 0;
        both(x, y) = guide ? 255 : ol(x, y);
        both(W + x, y) = guide ? 255 : orr(x, y);
      }
    s = tools::write_png_gray8(outp, both.view());
    if (!s.is_ok()) {
      std::fprintf(stderr, "qnav stereo: %s: %s\n", outp, s.message());
      return 1;
    }
    std::printf("wrote %s\n", outp);
  }
  return 0;
}

int cmd_degrade() {
  const char* ip = g_opt.image.c_str();
  const long filter = g_opt.filter;
  if (!out_dir_ok()) return 1;
  ImageU8 img;
  if (!load(ip, img)) return 1;
  ImageU8 deg = ImageU8::allocate(img.width(), img.height()).value();
  const UnderwaterDegradation p = table1_filter(static_cast<int>(filter));
  const Status s = degrade_underwater(img.view(), p, deg.view());
  if (!s.is_ok()) {
    std::fprintf(stderr, "qnav stereo: degrade: %s\n", s.message());
    return 1;
  }
  Detector a(img.width(), img.height(), 500), b(img.width(), img.height(), 500);
  if (!a.det.detect(img.view(), a.out).is_ok() || !b.det.detect(deg.view(), b.out).is_ok()) return 1;
  int hit = 0;
  for (const Corner& c : a.out)
    for (const Corner& q : b.out)
      if (std::hypot(c.x - q.x, c.y - q.y) <= 1.5f) {
        ++hit;
        break;
      }
  std::printf("degrade filter %ld (light %.2f m, attenuation %.2f, noise %.0f, min grey %d, %d flakes): Harris repeatability %.3f (%d of %zu corners within 1.5 px)\n",
              filter, p.light_distance_m, p.attenuation, p.noise_sigma, p.min_grey, p.snow_flakes,
              a.out.size() ? static_cast<double>(hit) / a.out.size() : 0.0, hit, a.out.size());
  if (const char* outp = out_or_null()) {
    const Status w = tools::write_png_gray8(outp, deg.view());
    if (!w.is_ok()) {
      std::fprintf(stderr, "qnav stereo: %s: %s\n", outp, w.message());
      return 1;
    }
    std::printf("wrote %s\n", outp);
  }
  return 0;
}

void setup_stereo(CLI::App& cmd, qnav::cli::Runner& run) {
  using qnav::cli::add_number;
  using qnav::cli::add_text;
  cmd.require_subcommand(1);
  CLI::App* d = cmd.add_subcommand("disparity", "Harris corners on LEFT, ZNCC stereo at the corners; prints counts and counters; --out\n"
                                                "writes the left image with each matched corner coloured by disparity (red near, blue far)");
  d->add_option("LEFT", g_opt.left, "the left image (PNG, JPEG, PGM)")->type_name("");
  d->add_option("RIGHT", g_opt.right, "the right image")->type_name("");
  add_text(*d, "--left", g_opt.left_opt, "the left image (instead of LEFT)")->type_name("FILE");
  add_text(*d, "--right", g_opt.right_opt, "the right image (instead of RIGHT)")->type_name("FILE");
  add_number(*d, "--max-disparity", g_opt.max_d, "largest disparity searched", "px", 3, 500);
  add_number(*d, "--corners", g_opt.corners, "Harris corners at most", "", 1, 100000);
  add_text(*d, "--out", g_opt.out, "write the coloured corners here, with axes and a disparity colour bar (folders created)")->type_name("PNG");
  run.on(d, cmd_disparity);

  CLI::App* a = cmd.add_subcommand("aloe", "disparity at Harris corners of the Middlebury Aloe pair against its ground truth");
  add_text(*a, "--dir", g_opt.dir, "the folder with aloeL.jpg, aloeR.jpg, aloeGT.png (default: the sample data)")->type_name("DIR");
  run.on(a, cmd_aloe);

  CLI::App* e = cmd.add_subcommand("euroc-rectify", "rectify the first EuRoC pair from the two sensor.yaml; row offset of matched corners\n"
                                                    "before and after; --out writes the rectified pair side by side with guide rows");
  e->add_option("DIR", g_opt.dir, "the EuRoC sequence folder (default: the sample data)")->type_name("");
  add_text(*e, "--out", g_opt.out, "write the rectified pair here (folders created)")->type_name("PNG");
  run.on(e, cmd_euroc_rectify);

  CLI::App* g = cmd.add_subcommand("degrade", "apply an underwater degradation of Table 1; Harris repeatability against the clean image");
  qnav::cli::add_positional(*g, "IMAGE", g_opt.image, "the clean image");
  add_number(*g, "--filter", g_opt.filter, "the Table 1 filter", "", 1, 5);
  add_text(*g, "--out", g_opt.out, "write the degraded image here (folders created)")->type_name("PNG");
  run.on(g, cmd_degrade);
}

}  // namespace

QNAV_CLI_COMMAND("stereo", "vision front end on files: disparity, aloe, euroc-rectify, degrade", setup_stereo);
