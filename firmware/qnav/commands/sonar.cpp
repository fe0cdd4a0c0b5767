// qnav sonar: side-scan tools over XTF and EdgeTech JSF files (told apart by their first bytes).
//   qnav sonar waterfall FILE --out PNG [--corrected] [--raster PNG]
//       port (far..near) | starboard (near..far), one row per ping, first ping at the top, drawn with
//       its axes (across-track m, ping) and a colour bar (firmware/tools/raster_plot.hpp); --raster
//       also writes the bare image, one pixel per sample. --corrected shows ScanlineCorrector output
//       (ground range from the detected first return, TVG + EGN) instead of raw samples.
//   qnav sonar tiles FILE --out DIR [--res 0.1] [--lines 500] [--stride N] [--size 1024]
//       [--nav fix|dr] [--heading-offset-deg 0] [--altitude detect|file] [--nadir-gap-m 1]
//       north-up tiles (tile_NNN.png, tile_NNN_coverage.png: the bare rasters) and tiles.csv with each
//       tile's pose; tile_NNN_plot.png: the tile with east/north axes in metres, a scale bar, a north
//       arrow and an intensity colour bar.
//       Altitude: the first return detected in the ping by default; `file` uses the altimeter field
//       (on the Iver2 file it reads 15-20 % short of the first return, leaving water column in the tile).
//   qnav sonar simulate --out FILE.xtf|FILE.jsf [--length-m 200] [--offset-m 0] [--reverse] [--seed 1] [--pass-seed N]
//       [--samples 1024] [--range-m 40] [--truth PNG] [--candump FILE] [--dvl-log FILE] [--start-s 1700000000]
//       flies the simulator along a straight route (metric nav) and writes an XTF or JSF file; --truth
//       draws the ground-truth reflectivity under the swath at 0.1 m (metric axes, scale bar, north
//       arrow, colour bar). --candump / --dvl-log also record the dive's navigation sensors at each
//       ping, as a vehicle logs them: the AHRS heading as QNAV_ATTITUDE_IN in a `candump -l` log, the
//       DVL's body velocities as Water Linked wrz sentences (qnavd replays them: sim.pass.candump,
//       sim.pass.dvl_log). --start-s: the first ping's time (s since the epoch), so that passes
//       recorded one after the other have their own times.
#include <algorithm>
#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "firmware/tools/stats.hpp"
#include "drivers/dvl/wl_parser.hpp"
#include "drivers/qnavcan/messages.hpp"
#include "drivers/sidescan/jsf_framer.hpp"
#include "drivers/sidescan/sim_seabed.hpp"
#include "drivers/sidescan/sim_sidescan.hpp"
#include "drivers/sidescan/sim_trajectory.hpp"
#include "drivers/sidescan/xtf_reader.hpp"
#include "drivers/sidescan/xtf_writer.hpp"
#include "firmware/cli/cli_app.hpp"
#include "firmware/pipeline/dead_reckoner.hpp"
#include "firmware/pipeline/route_tile_pipeline.hpp"
#include "firmware/qnav/command.hpp"
#include "firmware/tools/png_writer.hpp"
#include "firmware/tools/raster_plot.hpp"
#include "firmware/tools/sim_dive.hpp"
#include "firmware/tools/sonar_file.hpp"
#include "hal/core/candump.hpp"
#include "nav/sonar/scanline_corrector.hpp"
#include "nav/sonar/tile_builder.hpp"

namespace {

using namespace qnav;
using namespace qnav::sidescan;
using namespace qnav::tools;

constexpr std::size_t kMaxSamples = 16384;
constexpr double kFalseNorth_m = 5000000.0;  // simulated files: metric nav around a false origin
constexpr double kFalseEast_m = 500000.0;

// Every sonar subcommand's options (one invocation per process), declared in setup_sonar below.
struct SonarOptions {
  std::string file, out, raster, nav = "fix", altitude = "detect", truth, candump, dvl_log, truth_csv;
  bool corrected = false, reverse = false;
  double res = 0.1, heading_off_deg = 0.0, nadir_gap = 1.0;
  long lines = 500, stride = -1, size = 1024;
  double length = 200.0, offset = 0.0, range = 40.0, speed = 1.5;
  long seed = 1, samples = 1024, pass_seed = -1, start_s = 1700000000;
};
SonarOptions g_opt;

// Percentile of the finite values (copy; tool side).
float percentile(std::vector<float> v, double q) {
  float p = 1.0f;
  qnav::tools::percentile_of(v, q, p);
  return p;
}

// Creates the folder the output file goes in; false (reported) when it cannot.
bool make_out_parent(const char* cmd, const std::string& out) {
  const std::string e = qnav::cli::make_parent_dirs(out);
  if (e.empty()) return true;
  std::fprintf(stderr, "qnav sonar %s: %s\n", cmd, e.c_str());
  return false;
}

int waterfall() {
  const char* file = g_opt.file.c_str();
  const char* out = g_opt.out.c_str();
  if (!make_out_parent("waterfall", out)) return 1;
  FileData fd;
  if (const std::string e = qnav::cli::input_file_problem(file); !e.empty()) {
    std::fprintf(stderr, "qnav sonar: %s\n", e.c_str());
    return 1;
  }
  if (load_sonar_file(file, fd) != 0) return 1;
  const bool corrected = g_opt.corrected;
  const int rows = static_cast<int>(fd.pings.size());
  int side = static_cast<int>(fd.pings[0].port.size());
  std::vector<float> img;
  int failed = 0;
  if (!corrected) {
    img.assign(static_cast<std::size_t>(rows) * 2 * static_cast<std::size_t>(side), 0.0f);
    for (int r = 0; r < rows; ++r) {
      const PingRec& p = fd.pings[static_cast<std::size_t>(r)];
      const int n = static_cast<int>(p.port.size()) < side ? static_cast<int>(p.port.size()) : side;
      float* row = img.data() + static_cast<std::size_t>(r) * 2 * static_cast<std::size_t>(side);
      for (int i = 0; i < n; ++i) {
        row[side - 1 - i] = p.port[static_cast<std::size_t>(i)];
        row[side + i] = p.stbd[static_cast<std::size_t>(i)];
      }
    }
  } else {
    sonar::ScanlineCorrectorConfig cc;
    cc.max_samples_per_side = static_cast<int>(kMaxSamples);
    const float range = fd.pings[0].ping.slant_range_m;
    cc.ground_bin_m = range / static_cast<float>(side);
    cc.ground_bins_per_side = side;
    ArenaStorage arena(sonar::ScanlineCorrector::arena_bytes(cc));
    sonar::ScanlineCorrector corr;
    const Status s = corr.init(cc, arena);
    if (!s) {
      std::fprintf(stderr, "qnav sonar: corrector: %s\n", s.message());
      return 1;
    }
    img.assign(static_cast<std::size_t>(rows) * 2 * static_cast<std::size_t>(side), 0.0f);
    for (int r = 0; r < rows; ++r) {
      sonar::CorrectedScanline line;
      if (!corr.correct(as_ping(fd.pings[static_cast<std::size_t>(r)], false), line)) {
        ++failed;
        continue;
      }
      float* row = img.data() + static_cast<std::size_t>(r) * 2 * static_cast<std::size_t>(side);
      for (int i = 0; i < side; ++i) {
        row[side - 1 - i] = line.port[static_cast<std::size_t>(i)];
        row[side + i] = line.stbd[static_cast<std::size_t>(i)];
      }
    }
  }
  const float hi = corrected ? 2.5f : percentile(img, 0.95);
  const Result<ConstImageViewF32> v = ConstImageViewF32::make(img.data(), 2 * side, rows);
  if (!v) return 1;
  if (!g_opt.raster.empty()) {
    if (!make_out_parent("waterfall", g_opt.raster)) return 1;
    const Status w = tools::write_png_float(g_opt.raster.c_str(), v.value(), 0.0f, hi);
    if (!w) {
      std::fprintf(stderr, "qnav sonar: %s: %s\n", g_opt.raster.c_str(), w.message());
      return 1;
    }
  }
  // Column c's centre: (c - side + 0.5) bins across track, port negative; the bin is the slant
  // range per sample (raw) or the corrector's ground bin (the same range over as many bins).
  const double bin_m = static_cast<double>(fd.pings[0].ping.slant_range_m) / side;
  tools::RasterPlot plot;
  plot.title = std::string("qnav sonar waterfall ") + file + (corrected ? " (corrected)" : " (raw)");
  plot.x = {(0.5 - side) * bin_m, bin_m,
            corrected ? "across-track ground range m (port -, starboard +)" : "across-track slant range m (port -, starboard +)"};
  plot.y = {0.0, 1.0, "ping (first at the top)"};
  plot.colour_bar = true;
  plot.colour_lo = 0.0;
  plot.colour_hi = static_cast<double>(hi);
  plot.colour_label = corrected ? "intensity (TVG + EGN)" : "raw sample value";
  const std::vector<std::uint8_t> grey = tools::gray8_from_float(v.value(), 0.0f, hi);
  const Status w = grey.empty() ? Status(StatusCode::kInvalidArgument, "bad intensity range")
                                : tools::write_raster_plot_png(out, ConstImageViewU8::unchecked(grey.data(), 2 * side, rows, 2 * side), plot);
  if (!w) {
    std::fprintf(stderr, "qnav sonar: %s: %s\n", out, w.message());
    return 1;
  }
  std::printf("waterfall %s: %d pings x (%d port | %d starboard) samples, %s, white = %.1f%s; reader counters:%s\n", out,
              rows, side, side, corrected ? "corrected ground range (TVG + EGN)" : "raw slant range",
              static_cast<double>(hi), failed ? " (some pings failed correction)" : "", fd.counters.c_str());
  if (failed) std::printf("pings not corrected: %d\n", failed);
  return 0;
}

int tiles() {
  const char* file = g_opt.file.c_str();
  const char* out = g_opt.out.c_str();
  const double res = g_opt.res, heading_off_deg = g_opt.heading_off_deg, nadir_gap = g_opt.nadir_gap;
  const long lines = g_opt.lines, stride = g_opt.stride, size = g_opt.size;
  const std::string nav = g_opt.nav;
  const std::string alt = g_opt.altitude;
  if (const std::string e = qnav::cli::make_dirs(out); !e.empty()) {
    std::fprintf(stderr, "qnav sonar tiles: %s\n", e.c_str());
    return 1;
  }
  FileData fd;
  if (const std::string e = qnav::cli::input_file_problem(file); !e.empty()) {
    std::fprintf(stderr, "qnav sonar: %s\n", e.c_str());
    return 1;
  }
  if (load_sonar_file(file, fd) != 0) return 1;
  const NavTrack track = build_track(fd, nav == "dr", deg_to_rad(heading_off_deg));
  report_track("qnav sonar", file, track);
  const float range = fd.pings[0].ping.slant_range_m;

  sonar::ScanlineCorrectorConfig cc;
  cc.max_samples_per_side = static_cast<int>(kMaxSamples);
  cc.ground_bin_m = static_cast<float>(res) * 0.5f;
  cc.nadir_gap_m = static_cast<float>(nadir_gap);
  cc.ground_bins_per_side = static_cast<int>(std::ceil(static_cast<double>(range) / static_cast<double>(cc.ground_bin_m)));
  sonar::TileBuilderConfig tc;
  tc.resolution_m = res;
  tc.tile_width_px = static_cast<int>(size);
  tc.tile_height_px = static_cast<int>(size);
  tc.scanlines_per_tile = static_cast<int>(lines);
  tc.scanline_stride = static_cast<int>(stride > 0 ? stride : lines);
  tc.max_bins_per_side = cc.ground_bins_per_side;
  // The tile stage qnavd's SonarTiles runs (corrector -> tile builder), without the keypoints.
  pipeline::RouteTileConfig pc;
  pc.corrector = cc;
  pc.tiles = tc;
  pc.extract_features = false;
  pipeline::RouteTilePipeline tiles;
  const Status s = tiles.init(pc);
  if (!s) {
    std::fprintf(stderr, "qnav sonar tiles: configuration: %s\n", s.message());
    return 2;
  }
  const std::string dir = out;
  const std::string csv_path = dir + "/tiles.csv";
  std::FILE* csv = std::fopen(csv_path.c_str(), "w");
  if (csv == nullptr) {
    std::fprintf(stderr, "qnav sonar tiles: cannot write %s: %s\n", csv_path.c_str(), std::strerror(errno));
    return 1;
  }
  std::fprintf(csv,
               "tile,first_ping,last_ping,scanlines,pose_north_m,pose_east_m,heading_deg,origin_north_m,origin_east_m,"
               "resolution_m,width_px,height_px,coverage,origin_file_y,origin_file_x\n");  // file_y/x: lat/lon deg or northing/easting m (file nav units)
  int written = 0, skipped_nav = 0;
  const double m_per_deg_lon = 111320.0 * std::cos(deg_to_rad(track.lat0));
  const pipeline::RouteTileSink emit = [&](const pipeline::RouteTile&) {
    const sonar::SonarTile& t = tiles.last_tile();
    char name[64];
    std::snprintf(name, sizeof name, "/tile_%03u.png", t.index);
    const Status w1 = tools::write_png_gray8((dir + name).c_str(), t.intensity_u8);
    std::vector<std::uint8_t> cov(t.coverage.pixel_count());
    for (int r = 0; r < t.coverage.height(); ++r)
      for (int c = 0; c < t.coverage.width(); ++c)
        cov[static_cast<std::size_t>(r * t.coverage.width() + c)] = static_cast<std::uint8_t>(t.coverage(c, r) * 127);
    std::snprintf(name, sizeof name, "/tile_%03u_coverage.png", t.index);
    const Status w2 = tools::write_png_gray8((dir + name).c_str(),
                                             ConstImageViewU8::unchecked(cov.data(), t.coverage.width(), t.coverage.height(), t.coverage.width()));
    tools::RasterPlot plot;
    char title[96];
    std::snprintf(title, sizeof title, "tile %u: pings %u..%u, %.2f m per px, north up", t.index, t.first_ping, t.last_ping, t.resolution_m);
    plot.title = title;
    plot.x = {t.origin_east_m + 0.5 * t.resolution_m, t.resolution_m, "east m (from the track's origin)"};
    plot.y = {t.origin_north_m - 0.5 * t.resolution_m, -t.resolution_m, "north m (from the track's origin)"};
    plot.scale_bar = plot.north_arrow = plot.colour_bar = true;
    plot.colour_hi = static_cast<double>(tc.display_max);
    plot.colour_label = "intensity (TVG + EGN)";
    std::snprintf(name, sizeof name, "/tile_%03u_plot.png", t.index);
    const Status w3 = tools::write_raster_plot_png((dir + name).c_str(), t.intensity_u8, plot);
    if (!w1 || !w2 || !w3) std::fprintf(stderr, "qnav sonar tiles: cannot write tile %u\n", t.index);
    const bool latlon = fd.header.nav_units == 3;
    std::fprintf(csv, "%u,%u,%u,%u,%.3f,%.3f,%.2f,%.3f,%.3f,%.3f,%d,%d,%.4f,%.8f,%.8f\n", t.index, t.first_ping, t.last_ping,
                 t.scanlines, t.pose.x_m, t.pose.y_m, rad_to_deg(t.pose.heading_rad), t.origin_north_m, t.origin_east_m,
                 t.resolution_m, t.intensity.width(), t.intensity.height(), static_cast<double>(t.coverage_fraction),
                 latlon ? track.lat0 + t.origin_north_m / 111320.0 : t.origin_north_m + track.lat0,
                 latlon ? track.lon0 + t.origin_east_m / m_per_deg_lon : t.origin_east_m + track.lon0);
    std::printf("tile %u: pings %u..%u (%u scanlines), pose N %.2f E %.2f hdg %.1f deg, coverage %.1f %%, clipped %u\n",
                t.index, t.first_ping, t.last_ping, t.scanlines, t.pose.x_m, t.pose.y_m, rad_to_deg(t.pose.heading_rad),
                100.0 * static_cast<double>(t.coverage_fraction), t.clipped_splats);
    ++written;
    return true;
  };
  for (std::size_t i = 0; i < fd.pings.size(); ++i) {
    if (!track.ok[i]) {
      ++skipped_nav;
      continue;
    }
    (void)tiles.push_ping(as_ping(fd.pings[i], alt != "detect"), track.pose[i], emit, nullptr);
  }
  (void)tiles.flush(emit, 2);
  const int failed = static_cast<int>(tiles.rejected_pings());
  std::fclose(csv);
  std::printf("%d tiles of %ldx%ld px at %.3f m in %s (tiles.csv); %zu pings, %d without nav, %d rejected; nav=%s, "
              "altitude=%s; reader counters:%s\n",
              written, size, size, res, out, fd.pings.size(), skipped_nav, failed, nav.c_str(), alt.c_str(), fd.counters.c_str());
  std::printf("corrector counters:");
  const auto& cc_counters = tiles.corrector().counters();
  for (std::size_t i = 0; i < cc_counters.size(); ++i) std::printf(" %s=%u", cc_counters.name_at(i), cc_counters.count_at(i));
  std::printf("\n");
  return written > 0 ? 0 : 1;
}

// The simulated dive's navigation sensors, logged at each ping (qnav sonar simulate --candump/--dvl-log).
class SensorLogs {
 public:
  ~SensorLogs() {
    if (can_) std::fclose(can_);
    if (dvl_) std::fclose(dvl_);
  }
  bool open(const char* can_path, const char* dvl_path) {
    if (can_path != nullptr && (can_ = std::fopen(can_path, "w")) == nullptr) return report(can_path);
    if (dvl_path != nullptr && (dvl_ = std::fopen(dvl_path, "w")) == nullptr) return report(dvl_path);
    return true;
  }
  // t_ns: ns since the epoch; nav: the vehicle's navigation (NED metres, heading) at that time.
  void write(std::uint64_t t_ns, const Pose2& nav) {
    if (can_ != nullptr) {
      const drivers::qnavcan::AttitudeIn a = drivers::qnavcan::attitude_from_heading(nav.heading_rad, 0.0, 0.0, counter_++);
      hal::CanLogRecord r;
      r.has_time = true;
      r.time_us = static_cast<std::int64_t>(t_ns / 1000);
      std::memcpy(r.interface, "can0", 5);
      char line[hal::kMaxCanLogLine];
      if (drivers::qnavcan::encode(a, r.frame) && hal::format_can_log_line(r, line, sizeof line) > 0) std::fprintf(can_, "%s\n", line);
    }
    if (dvl_ != nullptr) {
      double fwd = 0.0, stbd = 0.0;
      if (have_prev_ && t_ns > prev_t_ns_) {
        pipeline::body_velocity_between(prev_, nav, static_cast<double>(t_ns - prev_t_ns_) * 1e-9, fwd, stbd);
      }
      const long long t_us = static_cast<long long>(t_ns / 1000);
      char line[240];
      if (drivers::dvl::wl_velocity_report(fwd, stbd, 0.0, 10.0, t_us, t_us, line, sizeof line) > 0) std::fputs(line, dvl_);
    }
    prev_ = nav, prev_t_ns_ = t_ns, have_prev_ = true;
  }

 private:
  static bool report(const char* path) {
    std::fprintf(stderr, "qnav sonar simulate: cannot write %s: %s\n", path, std::strerror(errno));
    return false;
  }
  std::FILE* can_ = nullptr;
  std::FILE* dvl_ = nullptr;
  std::uint8_t counter_ = 0;
  bool have_prev_ = false;
  Pose2 prev_{};
  std::uint64_t prev_t_ns_ = 0;
};

int simulate() {
  const char* out = g_opt.out.c_str();
  const double length = g_opt.length, offset = g_opt.offset, range = g_opt.range;
  const long seed = g_opt.seed, samples = g_opt.samples, start_s = g_opt.start_s;
  long pass_seed = g_opt.pass_seed;
  if (!(length > 1.0)) {
    std::fprintf(stderr, "qnav sonar simulate: --length-m: must be more than 1 m\n");
    return 2;
  }
  if (!make_out_parent("simulate", out)) return 1;
  const SeabedConfig bc = sim_dive_seabed(length, static_cast<std::uint64_t>(seed));
  Seabed bed;
  if (pass_seed < 0) pass_seed = seed;
  const SideScanSimConfig sc = sim_dive_sonar(samples, range, static_cast<std::uint64_t>(pass_seed));
  SideScanSimulator sim;
  TrajectoryConfig trc;
  (void)trc.waypoints_ne.push_back(Vec2d(0.0, 0.0));
  (void)trc.waypoints_ne.push_back(Vec2d(length, 0.0));
  trc.lateral_offset_m = offset;
  trc.speed_mps = g_opt.speed;
  trc.reverse = g_opt.reverse;
  trc.seed = static_cast<std::uint64_t>(pass_seed);
  Trajectory traj;
  Status s = bed.init(bc);
  if (s) s = sim.init(sc, &bed);
  if (s) s = traj.init(trc);
  if (!s) {
    std::fprintf(stderr, "qnav sonar simulate: %s\n", s.message());
    return 2;
  }
  SensorLogs logs;
  if (!logs.open(g_opt.candump.empty() ? nullptr : g_opt.candump.c_str(), g_opt.dvl_log.empty() ? nullptr : g_opt.dvl_log.c_str())) return 1;
  // The simulator's truth at each ping, for verdicts that join the daemon's outputs to the ping they answer.
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> truth_csv(nullptr, &std::fclose);
  if (!g_opt.truth_csv.empty()) {
    if (!make_out_parent("simulate", g_opt.truth_csv.c_str())) return 1;
    truth_csv.reset(std::fopen(g_opt.truth_csv.c_str(), "w"));
    if (!truth_csv) {
      std::fprintf(stderr, "qnav sonar simulate: cannot write %s: %s\n", g_opt.truth_csv.c_str(), std::strerror(errno));
      return 1;
    }
    std::fprintf(truth_csv.get(), "ping,time_s,along_m,north_m,east_m,heading_rad,nav_north_m,nav_east_m,nav_heading_rad\n");
  }
  std::FILE* f = std::fopen(out, "wb");
  if (f == nullptr) {
    std::fprintf(stderr, "qnav sonar simulate: cannot write %s: %s\n", out, std::strerror(errno));
    return 1;
  }
  const std::size_t out_len = std::strlen(out);
  const bool jsf = out_len > 4 && std::strcmp(out + out_len - 4, ".jsf") == 0;
  std::vector<std::uint8_t> buf(xtf_ping_bytes(static_cast<std::size_t>(samples)) + kXtfFileHeaderBytes +
                                jsf_sonar_message_bytes(static_cast<std::size_t>(samples)));
  if (!jsf) {
    (void)encode_xtf_file_header(Span<std::uint8_t>(buf.data(), buf.size()), 0, "QNAV-SIM");
    std::fwrite(buf.data(), 1, kXtfFileHeaderBytes, f);
  }
  const std::uint64_t t0_ns = static_cast<std::uint64_t>(start_s) * 1000000000ull;
  TrajectorySample ts;
  std::uint32_t n = 0;
  float peak = 0.0f;
  std::vector<float> port(static_cast<std::size_t>(samples)), stbd(static_cast<std::size_t>(samples));
  std::vector<std::vector<float>> first_pings;
  std::string jsf_bytes;
  std::vector<std::uint8_t> jsf_buf;
  while (traj.next(ts)) {
    (void)sim.ping(ts.truth, ts.altitude_m, ts.index, Span<float>(port.data(), port.size()), Span<float>(stbd.data(), stbd.size()));
    for (float v : port) peak = v > peak ? v : peak;
    logs.write(t0_ns + ts.stamp_ns, ts.nav);
    if (truth_csv) {
      std::fprintf(truth_csv.get(), "%u,%.3f,%.3f,%.3f,%.3f,%.5f,%.3f,%.3f,%.5f\n", ts.index, static_cast<double>(t0_ns + ts.stamp_ns) * 1e-9,
                   ts.along_route_m, ts.truth.x_m, ts.truth.y_m, ts.truth.heading_rad, ts.nav.x_m, ts.nav.y_m, ts.nav.heading_rad);
    }
    if (jsf) {
      // Two message-80 records per ping (port, starboard), positions in mm (coordinate units 1).
      jsf_bytes.clear();
      const bool ok = append_sim_dive_jsf(jsf_bytes, ts.index, t0_ns + ts.stamp_ns, range, ts.altitude_m, ts.nav, port, stbd, jsf_buf) &&
                      std::fwrite(jsf_bytes.data(), 1, jsf_bytes.size(), f) == jsf_bytes.size();
      if (!ok) {
        std::fclose(f);
        std::fprintf(stderr, "qnav sonar simulate: write failed\n");
        return 1;
      }
      ++n;
      continue;
    }
    XtfWritePing w;
    w.stamp_ns = t0_ns + ts.stamp_ns;
    w.ping_number = ts.index;
    // A UTM-like false origin: (0, 0) is the "no fix" placeholder of XTF files.
    w.sensor_y = kFalseNorth_m + ts.nav.x_m;
    w.sensor_x = kFalseEast_m + ts.nav.y_m;
    w.heading_deg = static_cast<float>(rad_to_deg(ts.nav.heading_rad < 0 ? ts.nav.heading_rad + 2 * kPi : ts.nav.heading_rad));
    w.speed_knots = static_cast<float>(trc.speed_mps / 0.514444);
    w.altitude_m = ts.altitude_m;
    w.slant_range_m = sc.slant_range_m;
    w.port = Span<const float>(port.data(), port.size());
    w.stbd = Span<const float>(stbd.data(), stbd.size());
    w.sample_scale = 4.0f;  // simulator amplitude ~ 0..16000 -> 16-bit
    const Result<std::size_t> b = encode_xtf_ping(Span<std::uint8_t>(buf.data(), buf.size()), w);
    if (!b || std::fwrite(buf.data(), 1, b.value(), f) != b.value()) {
      std::fclose(f);
      std::fprintf(stderr, "qnav sonar simulate: write failed\n");
      return 1;
    }
    ++n;
  }
  std::fclose(f);
  std::printf("simulated %u pings (%.0f m at %.1f m/s, %.0f Hz, %ld samples/side, %.0f m range, offset %.1f m%s) -> %s; "
              "wreck 14 x 4 x 2.5 m at N %.1f E %.1f (%s)\n",
              n, length, trc.speed_mps, trc.ping_rate_hz, samples, range, offset, trc.reverse ? ", reverse" : "", out,
              bc.objects[0].north_m, bc.objects[0].east_m,
              jsf ? "EdgeTech JSF, message 80 per side, positions in mm" : "XTF, metric nav around a false origin N 5000000 E 500000");
  if (const char* truth = g_opt.truth.empty() ? nullptr : g_opt.truth.c_str()) {
    const double res = 0.1;
    const int W = static_cast<int>(2.0 * range / res), H = static_cast<int>(length / res);
    std::vector<float> img(static_cast<std::size_t>(W) * static_cast<std::size_t>(H));
    for (int r = 0; r < H; ++r)
      for (int c = 0; c < W; ++c)
        img[static_cast<std::size_t>(r) * static_cast<std::size_t>(W) + static_cast<std::size_t>(c)] =
            bed.reflectivity(length - (r + 0.5) * res, -range + (c + 0.5) * res);
    const Result<ConstImageViewF32> v = ConstImageViewF32::make(img.data(), W, H);
    tools::RasterPlot plot;
    plot.title = "simulated seabed: ground-truth reflectivity under the swath";
    plot.x = {-range + 0.5 * res, res, "east m (route along north, at east 0)"};
    plot.y = {length - 0.5 * res, -res, "north m"};
    plot.scale_bar = plot.north_arrow = plot.colour_bar = true;
    plot.colour_label = "reflectivity";
    const std::vector<std::uint8_t> grey = v ? tools::gray8_from_float(v.value(), 0.0f, 1.0f) : std::vector<std::uint8_t>();
    if (!grey.empty() && tools::write_raster_plot_png(truth, ConstImageViewU8::unchecked(grey.data(), W, H, W), plot))
      std::printf("ground truth reflectivity %s: %dx%d px at %.1f m, north up, east %.0f..%.0f m, north 0..%.0f m\n", truth, W, H,
                  res, -range, range, length);
  }
  return 0;
}

void setup_sonar(CLI::App& cmd, qnav::cli::Runner& run) {
  using qnav::cli::add_flag;
  using qnav::cli::add_number;
  using qnav::cli::add_text;
  cmd.require_subcommand(1);
  CLI::App* w = cmd.add_subcommand("waterfall", "port (far..near) | starboard (near..far), one row per ping, first ping at the top");
  qnav::cli::add_positional(*w, "FILE", g_opt.file, "the side-scan file (XTF or JSF)");
  add_text(*w, "--out", g_opt.out, "the PNG to write (folders created)")->required()->type_name("PNG");
  add_flag(*w, "--corrected", g_opt.corrected,
           "show the ScanlineCorrector's output (ground range from the first return, TVG + EGN) instead of raw samples");
  add_text(*w, "--raster", g_opt.raster, "also write the bare waterfall, one pixel per sample, no axes (folders created)")->type_name("PNG");
  run.on(w, waterfall);

  CLI::App* t = cmd.add_subcommand("tiles", "north-up tiles (tile_NNN.png, tile_NNN_coverage.png), tile_NNN_plot.png (metric axes, scale bar, north arrow) and tiles.csv with each tile's pose");
  qnav::cli::add_positional(*t, "FILE", g_opt.file, "the side-scan file (XTF or JSF)");
  add_text(*t, "--out", g_opt.out, "the folder to write (created as needed)")->required()->type_name("DIR");
  add_number(*t, "--res", g_opt.res, "tile pixel size", "m", 0.005, 10);
  add_number(*t, "--lines", g_opt.lines, "pings per tile", "pings", 1, 100000);
  add_number(*t, "--stride", g_opt.stride, "a tile every N pings (-1: every --lines pings)", "pings", -1, 100000);
  add_number(*t, "--size", g_opt.size, "tile width and height", "px", 16, 16384);
  add_text(*t, "--nav", g_opt.nav, "navigation: the position fixes, or dead reckoning", {"fix", "dr"});
  add_number(*t, "--heading-offset-deg", g_opt.heading_off_deg, "added to the recorded compass heading", "deg", -360, 360);
  add_text(*t, "--altitude", g_opt.altitude,
           "altitude from the first return detected in each ping, or the file's altimeter field", {"detect", "file"});
  add_number(*t, "--nadir-gap-m", g_opt.nadir_gap, "ground range left blank under the vehicle", "m", 0, 1000);
  run.on(t, tiles);

  CLI::App* m = cmd.add_subcommand("simulate",
                                   "fly the simulator along a straight route (metric nav) and write an XTF or JSF file (by --out's extension)");
  add_text(*m, "--out", g_opt.out, "the file to write: FILE.xtf or FILE.jsf (folders created)")->required()->type_name("FILE");
  add_number(*m, "--length-m", g_opt.length, "route length (more than 1 m)", "m", 1, 1e6);
  add_number(*m, "--offset-m", g_opt.offset, "lateral offset of the pass from the route", "m", -1e4, 1e4);
  add_number(*m, "--speed-mps", g_opt.speed, "the vehicle's speed over ground (10 pings/s)", "m/s", 0.2, 10);
  add_flag(*m, "--reverse", g_opt.reverse, "fly the route backwards");
  add_number(*m, "--seed", g_opt.seed, "seed of the seabed", "", 0, 2147483647);
  add_number(*m, "--pass-seed", g_opt.pass_seed, "seed of the pass's speckle and navigation noise (-1: --seed)", "", -1, 2147483647);
  add_number(*m, "--samples", g_opt.samples, "samples per side", "", 16, 16384);
  add_number(*m, "--range-m", g_opt.range, "slant range", "m", 1, 10000);
  add_text(*m, "--truth", g_opt.truth, "also write the ground-truth reflectivity under the swath at 0.1 m")->type_name("PNG");
  add_text(*m, "--candump", g_opt.candump, "also log the AHRS heading as QNAV_ATTITUDE_IN at each ping (candump -l)")->type_name("FILE");
  add_text(*m, "--dvl-log", g_opt.dvl_log, "also log the DVL's body velocities as Water Linked wrz sentences")->type_name("FILE");
  add_text(*m, "--truth-csv", g_opt.truth_csv,
           "also write the simulator's truth at each ping (ping, time, along-route m, true and dead-reckoned north/east m, heading)")
      ->type_name("FILE");
  add_number(*m, "--start-s", g_opt.start_s, "the first ping's time since the epoch", "s", 0, 4000000000.0);
  run.on(m, simulate);
}

}  // namespace

QNAV_CLI_COMMAND("sonar", "sonar waterfall|tiles|simulate: side-scan waterfall, north-up tiles, simulated XTF", setup_sonar);
