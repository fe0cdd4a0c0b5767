// Side-scan files for the host tools: every ping of an XTF or EdgeTech JSF file (told apart by the
// first bytes) with its samples and navigation, and the local north/east track of the pings. Used by
// `qnav sonar` and `qnav route train|repeat|xtf`. Not flight code: tool-side memory (std::vector);
// the drivers' parsers underneath are the bounded, counted ones. Header-only: qnav_tools is linked
// before drivers/sidescan.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "firmware/tools/stats.hpp"
#include "drivers/sidescan/jsf_framer.hpp"
#include "drivers/sidescan/xtf_reader.hpp"
#include "firmware/tools/file_source.hpp"
#include "nav/core/geometry.hpp"
#include "nav/sonar/scanline_corrector.hpp"
#include "nav/sonar/tile_builder.hpp"

namespace qnav::tools {

using sidescan::JsfFramer;
using sidescan::JsfMessageView;
using sidescan::JsfPingAssembler;
using sidescan::JsfSonarData;
using sidescan::XtfFileHeader;
using sidescan::XtfPing;
using sidescan::XtfReader;
using sidescan::XtfReaderConfig;
using sidescan::XtfRecord;
using sidescan::XtfRecordKind;

constexpr std::size_t kMaxSonarSamples = 16384;

// Every ping of a file, with its samples (tool-side memory; the nav stages below stay fixed-size).
struct PingRec {
  XtfPing ping;
  std::vector<float> port, stbd;
};

struct FileData {
  XtfFileHeader header;
  std::vector<PingRec> pings;
  std::string counters;
};

// Opens a side-scan file for the loaders below; false (said on stderr) when it cannot be opened.
inline bool open_sonar_file(FileSource& src, const char* path) {
  if (src.open(path)) return true;
  std::fprintf(stderr, "qnav: cannot open %s\n", path);
  return false;
}

inline int load_xtf(const char* path, FileData& out) {
  FileSource src;
  if (!open_sonar_file(src, path)) return 1;
  XtfReader reader;
  if (!reader.init(XtfReaderConfig{})) return 1;
  const Status o = reader.open(src);
  if (!o) {
    std::fprintf(stderr, "qnav: %s: %s\n", path, o.message());
    return 1;
  }
  out.header = reader.header();
  std::vector<float> port(kMaxSonarSamples), stbd(kMaxSonarSamples);
  XtfRecord rec;
  for (;;) {
    const Result<bool> r = reader.next(rec, Span<float>(port.data(), port.size()), Span<float>(stbd.data(), stbd.size()));
    if (!r) {
      std::fprintf(stderr, "qnav: %s: %s (continuing with the pings read so far)\n", path, r.status().message());
      continue;
    }
    if (!r.value()) break;
    if (rec.kind != XtfRecordKind::kPing) continue;
    PingRec p;
    p.ping = rec.ping;
    p.port.assign(port.begin(), port.begin() + rec.ping.samples_per_side);
    p.stbd.assign(stbd.begin(), stbd.begin() + rec.ping.samples_per_side);
    out.pings.push_back(std::move(p));
  }
  char buf[512];
  int n = 0;
  for (std::size_t i = 0; i < reader.counters().size(); ++i)
    if (reader.counters().count_at(i) != 0 && n < 400)
      n += std::snprintf(buf + n, sizeof buf - static_cast<std::size_t>(n), " %s=%u", reader.counters().name_at(i),
                         reader.counters().count_at(i));
  buf[n] = '\0';
  out.counters = n > 0 ? buf : " none";
  if (out.pings.empty()) {
    std::fprintf(stderr, "qnav: %s: no side-scan pings\n", path);
    return 1;
  }
  return 0;
}

// JSF file (EdgeTech): framed in 64 KiB reads, port + starboard paired into pings; positions in
// lat/lon (units 2) or metres (units 1/3) become the same XtfPing fields the XTF path fills.
inline int load_jsf(const char* path, FileData& out) {
  FileSource src;
  if (!open_sonar_file(src, path)) return 1;
  JsfFramer framer;
  JsfPingAssembler pings;
  if (!framer.init(4u << 20) || !pings.init(kMaxSonarSamples)) return 1;
  std::vector<std::uint8_t> chunk(65536);
  bool latlon = true;
  for (;;) {
    const std::size_t got = src.read(chunk.data(), chunk.size());
    if (got == 0) break;
    Span<const std::uint8_t> c(chunk.data(), got);
    while (!c.empty()) {
      const std::size_t used = framer.feed(c);
      c = c.subspan(used, c.size() - used);
      JsfMessageView m;
      while (framer.next(m)) {
        if (!pings.add(m)) continue;
        const sonar::SonarPing& sp = pings.ping();
        const JsfSonarData& d = pings.port_data();
        PingRec p;
        p.ping.ping_number = sp.ping_number;
        p.ping.stamp_ns = sp.stamp_ns;
        p.ping.sensor_y = d.y;
        p.ping.sensor_x = d.x;
        p.ping.nav_valid = d.position_valid;
        p.ping.heading_deg = d.heading_deg;
        p.ping.sensor_speed_knots = d.speed_knots;
        p.ping.altitude_m = sp.altitude_m;
        p.ping.slant_range_m = sp.slant_range_m;
        p.ping.samples_per_side = static_cast<std::uint32_t>(sp.port.size());
        p.port.assign(sp.port.begin(), sp.port.end());
        p.stbd.assign(sp.stbd.begin(), sp.stbd.end());
        latlon = d.coordinate_units == 2;
        out.pings.push_back(std::move(p));
      }
    }
  }
  out.header.nav_units = latlon ? 3 : 0;
  char buf[512];
  int n = 0;
  for (std::size_t i = 0; i < framer.counters().size(); ++i)
    n += std::snprintf(buf + n, sizeof buf - static_cast<std::size_t>(n), " %s=%u", framer.counters().name_at(i), framer.counters().count_at(i));
  for (std::size_t i = 0; i < pings.counters().size(); ++i)
    n += std::snprintf(buf + n, sizeof buf - static_cast<std::size_t>(n), " %s=%u", pings.counters().name_at(i), pings.counters().count_at(i));
  if (framer.pending_bytes() > 0) n += std::snprintf(buf + n, sizeof buf - static_cast<std::size_t>(n), " truncated_tail_bytes=%zu", framer.pending_bytes());
  out.counters = buf;
  if (out.pings.empty()) {
    std::fprintf(stderr, "qnav: %s: no side-scan pings\n", path);
    return 1;
  }
  return 0;
}

// XTF or JSF, told apart by the first bytes (XTF: 123; JSF: sync 01 16).
inline int load_sonar_file(const char* path, FileData& out) {
  std::FILE* f = std::fopen(path, "rb");
  if (f == nullptr) {
    std::fprintf(stderr, "qnav: cannot open %s\n", path);
    return 1;
  }
  std::uint8_t head[2] = {0, 0};
  const std::size_t k = std::fread(head, 1, 2, f);
  std::fclose(f);
  if (k == 2 && head[0] == 0x01 && head[1] == 0x16) return load_jsf(path, out);
  return load_xtf(path, out);
}

inline sonar::SonarPing as_ping(const PingRec& r, bool use_altimeter) {
  sonar::SonarPing p;
  p.stamp_ns = r.ping.stamp_ns;
  p.ping_number = r.ping.ping_number;
  p.port = Span<const float>(r.port.data(), r.port.size());
  p.stbd = Span<const float>(r.stbd.data(), r.stbd.size());
  p.slant_range_m = r.ping.slant_range_m;
  p.altitude_m = use_altimeter ? r.ping.altitude_m : -1.0f;
  return p;
}

// Median slant range over the pings with a positive finite one (appended to `ranges`, the caller's
// scratch: several files may be pooled); false when none has one. Sets the tile geometry of a file.
inline bool median_slant_range(std::vector<float>& ranges, double& range_m) {
  float m = 0.0f;
  if (!median_of(ranges, m)) return false;
  range_m = static_cast<double>(m);
  return true;
}
inline void collect_slant_ranges(const FileData& fd, std::vector<float>& ranges) {
  for (const PingRec& p : fd.pings)
    if (std::isfinite(p.ping.slant_range_m) && p.ping.slant_range_m > 0.0f) ranges.push_back(p.ping.slant_range_m);
}

// Local north/east of every ping from the file's fixes (interpolated between fix changes) or by
// dead reckoning (speed + heading). Pings before the first valid fix take the first fix.
struct NavTrack {
  std::vector<Pose2> pose;
  std::vector<bool> ok;
  double lat0 = 0.0, lon0 = 0.0;
  std::size_t not_finite = 0;  // pings after the first fix without a finite position / heading (not ok)
  std::size_t nav_outliers = 0;   // fixes rejected: reaching them needs more than kMaxTrackSpeedMps
  std::size_t nav_reanchors = 0;  // kReanchorFixes consistent "outliers" in a row: the track followed them
};

// A fix that would need the vehicle to move faster than this from the last accepted fix (over at
// least 1 s) is a damaged position, not a manoeuvre: towed and AUV side-scan surveys run at 1-6 m/s.
constexpr double kMaxTrackSpeedMps = 15.0;
constexpr std::size_t kReanchorFixes = 5;

inline NavTrack build_track(const FileData& fd, bool dead_reckon, double heading_offset_rad) {
  NavTrack t;
  const std::size_t n = fd.pings.size();
  t.pose.assign(n, Pose2{});
  t.ok.assign(n, false);
  const bool latlon = fd.header.nav_units == 3;
  std::size_t first = n;
  for (std::size_t i = 0; i < n; ++i)
    if (fd.pings[i].ping.nav_valid) {
      first = i;
      break;
    }
  if (first == n) return t;
  t.lat0 = fd.pings[first].ping.sensor_y;
  t.lon0 = fd.pings[first].ping.sensor_x;
  const double m_per_deg_lat = 111320.0, m_per_deg_lon = 111320.0 * std::cos(deg_to_rad(t.lat0));
  auto ne_of = [&](const XtfPing& p) {
    if (latlon) return Vec2d((p.sensor_y - t.lat0) * m_per_deg_lat, (p.sensor_x - t.lon0) * m_per_deg_lon);
    return Vec2d(p.sensor_y - t.lat0, p.sensor_x - t.lon0);
  };
  std::vector<Vec2d> ne(n, Vec2d::Zero());
  if (!dead_reckon) {
    // Fix change points: the fix is valid when it changes; interpolate in time between changes.
    // A fix implausibly far from the last accepted one is rejected and counted; kReanchorFixes such
    // fixes in a row that agree with each other mean the earlier fixes were wrong (or the navigation
    // was reset): the track follows them, counted, and a lone first fix they contradict is dropped.
    std::vector<std::size_t> knots;
    Vec2d last(1e300, 1e300);
    auto plausible = [&](std::size_t a, std::size_t b) {
      const double dt = std::fabs(static_cast<double>(fd.pings[b].ping.stamp_ns) - static_cast<double>(fd.pings[a].ping.stamp_ns)) * 1e-9;
      return (ne_of(fd.pings[b].ping) - ne_of(fd.pings[a].ping)).norm() <= kMaxTrackSpeedMps * (dt > 1.0 ? dt : 1.0);
    };
    std::size_t streak = 0, streak_first = n, streak_last = n;
    for (std::size_t i = first; i < n; ++i) {
      if (!fd.pings[i].ping.nav_valid) continue;
      const Vec2d p = ne_of(fd.pings[i].ping);
      if ((p - last).norm() <= 1e-6) continue;
      if (knots.empty() || plausible(knots.back(), i)) {
        knots.push_back(i);
        last = p;
        streak = 0;
        continue;
      }
      ++t.nav_outliers;
      if (streak > 0 && plausible(streak_last, i)) {
        ++streak;
      } else {
        streak = 1;
        streak_first = i;
      }
      streak_last = i;
      if (streak >= kReanchorFixes) {
        if (knots.size() == 1) knots.clear();
        knots.push_back(streak_first);
        knots.push_back(i);
        last = p;
        t.nav_outliers -= streak;
        ++t.nav_reanchors;
        streak = 0;
      }
    }
    std::size_t k = 0;
    for (std::size_t i = 0; i < n; ++i) {
      while (k + 1 < knots.size() && knots[k + 1] <= i) ++k;
      const std::size_t a = knots[k];
      if (i <= a || k + 1 >= knots.size()) {
        ne[i] = ne_of(fd.pings[a].ping);
      } else {
        const std::size_t b = knots[k + 1];
        const double ta = static_cast<double>(fd.pings[a].ping.stamp_ns), tb = static_cast<double>(fd.pings[b].ping.stamp_ns);
        const double ti = static_cast<double>(fd.pings[i].ping.stamp_ns);
        const double f = tb > ta ? (ti - ta) / (tb - ta) : 0.0;
        ne[i] = ne_of(fd.pings[a].ping) + f * (ne_of(fd.pings[b].ping) - ne_of(fd.pings[a].ping));
      }
    }
  } else {
    ne[first] = Vec2d::Zero();
    // A ping with a non-finite speed or heading adds no distance (one NaN heading must not poison
    // every later position of the track); the ping itself is marked not ok below.
    for (std::size_t i = first + 1; i < n; ++i) {
      const XtfPing& p = fd.pings[i].ping;
      const double dt = static_cast<double>(p.stamp_ns - fd.pings[i - 1].ping.stamp_ns) * 1e-9;
      const double v = static_cast<double>(p.sensor_speed_knots) * 0.514444;
      const double h = deg_to_rad(static_cast<double>(p.heading_deg)) + heading_offset_rad;
      const bool valid = std::isfinite(v) && std::isfinite(h) && dt > 0.0 && dt < 10.0;
      ne[i] = valid ? Vec2d(ne[i - 1] + v * dt * sonar::forward_unit(h)) : ne[i - 1];
    }
    for (std::size_t i = 0; i < first; ++i) ne[i] = Vec2d::Zero();
  }
  for (std::size_t i = 0; i < n; ++i) {
    const double h = deg_to_rad(static_cast<double>(fd.pings[i].ping.heading_deg)) + heading_offset_rad;
    t.pose[i] = Pose2{ne[i].x(), ne[i].y(), wrap_angle_rad(h)};
    t.ok[i] = t.pose[i].is_finite() && i >= first;
    if (i >= first && !t.ok[i]) ++t.not_finite;
  }
  return t;
}

// One line on stderr for what build_track() could not use (nothing when every fix was good).
inline void report_track(const char* who, const char* path, const NavTrack& t) {
  if (t.not_finite > 0)
    std::fprintf(stderr, "%s: %s: %zu pings without a finite position or heading are skipped\n", who, path, t.not_finite);
  if (t.nav_outliers > 0 || t.nav_reanchors > 0)
    std::fprintf(stderr, "%s: %s: %zu position fixes rejected (would need > %.0f m/s); track re-anchored %zu times\n", who, path,
                 t.nav_outliers, kMaxTrackSpeedMps, t.nav_reanchors);
}

}  // namespace qnav::tools
