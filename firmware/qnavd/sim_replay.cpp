#include "firmware/qnavd/sim_replay.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "drivers/qnavcan/messages.hpp"
#include "hal/core/candump.hpp"

namespace qnav::daemon {

namespace {

// The whole file, refused beyond RecordedSensors::kMaxLogBytes; the error names the file.
Status read_whole(const std::string& path, const char* key, std::string& out) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) {
    std::fprintf(stderr, "qnavd sim: %s %s: %s\n", key, path.c_str(), std::strerror(errno));
    return Status(StatusCode::kNotFound, "sim: a recorded sensor log cannot be read (see the line above)");
  }
  out.clear();
  char buf[65536];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) {
    if (out.size() + n > RecordedSensors::kMaxLogBytes) {
      std::fclose(f);
      std::fprintf(stderr, "qnavd sim: %s %s: larger than %zu MB\n", key, path.c_str(), RecordedSensors::kMaxLogBytes >> 20);
      return Status(StatusCode::kOutOfRange, "sim: a recorded sensor log is too large (see the line above)");
    }
    out.append(buf, n);
  }
  const bool err = std::ferror(f) != 0;
  std::fclose(f);
  if (err) {
    std::fprintf(stderr, "qnavd sim: %s %s: read error (a folder?)\n", key, path.c_str());
    return Status(StatusCode::kIoError, "sim: a recorded sensor log cannot be read (see the line above)");
  }
  return Status::ok();
}

bool starts_with(const char* p, std::size_t n, const char* prefix) {
  const std::size_t k = std::strlen(prefix);
  return n >= k && std::memcmp(p, prefix, k) == 0;
}

// Water Linked wrz: the time_of_transmission field (us since the epoch), read whatever the rest of the
// sentence holds (a damaged one is replayed as recorded; the daemon's driver judges it).
bool wrz_time(const char* p, std::size_t n, std::int64_t& t_ns) {
  if (!starts_with(p, n, "wrz,")) return false;
  std::size_t field = 0, i = 0;
  while (i < n && field < 9) field += p[i++] == ',' ? 1 : 0;
  if (field < 9) return false;
  std::int64_t us = 0;
  std::size_t digits = 0;
  for (; i < n && p[i] >= '0' && p[i] <= '9' && digits < 16; ++i, ++digits) us = us * 10 + (p[i] - '0');  // < 1e16 us: no overflow in ns
  if (digits == 0 || (i < n && p[i] != ',')) return false;
  t_ns = us * 1000;
  return true;
}

// PD6 :TS,YYMMDDHHmmsshh -> ns since the epoch (UTC; years 2000-2099).
bool pd6_time(const char* p, std::size_t n, std::int64_t& t_ns) {
  if (n < 18 || !starts_with(p, n, ":TS,")) return false;
  int v[7];
  for (int i = 0; i < 7; ++i) {
    const char a = p[4 + 2 * i], b = p[5 + 2 * i];
    if (a < '0' || a > '9' || b < '0' || b > '9') return false;
    v[i] = (a - '0') * 10 + (b - '0');
  }
  if (v[1] < 1 || v[1] > 12 || v[2] < 1 || v[2] > 31 || v[3] > 23 || v[4] > 59 || v[5] > 60) return false;
  t_ns = utc_seconds(2000 + v[0], v[1], v[2], v[3], v[4], v[5]) * 1000000000LL + static_cast<std::int64_t>(v[6]) * 10000000LL;
  return true;
}

}  // namespace

std::int64_t utc_seconds(int year, int month, int day, int hour, int minute, int second) noexcept {
  // Days from 1970-01-01 of a civil date (H. Hinnant's days_from_civil).
  const int y = year - (month <= 2 ? 1 : 0);
  const int era = (y >= 0 ? y : y - 399) / 400;
  const int yoe = y - era * 400;
  const int doy = (153 * (month + (month > 2 ? -3 : 9)) + 2) / 5 + day - 1;
  const int doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  const std::int64_t days = static_cast<std::int64_t>(era) * 146097 + doe - 719468;
  return days * 86400 + hour * 3600 + minute * 60 + second;
}

Status RecordedSensors::load_candump(const std::string& path) {
  std::string text;
  QNAV_RETURN_IF_ERROR(read_whole(path, "sim.pass.candump", text));
  can.clear();
  std::size_t pos = 0;
  std::int64_t last = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::size_t n = end - pos;
    if (n > 0 && text[pos + n - 1] == '\r') --n;
    hal::CanLogRecord rec;
    if (n > 0) {
      // (a time beyond 2^63 ns, year 2262, is not a time: counted with the bad lines)
      if (!hal::parse_can_log_line(text.data() + pos, n, rec) || !rec.has_time || rec.time_us < 0 || rec.time_us > INT64_MAX / 1000) {
        ++can_bad_lines;
      } else {
        const std::uint32_t id = rec.frame.id;
        const bool own = !rec.frame.extended && id >= 0x200 && id <= 0x2FF;
        if (!rec.frame.error && (own || (!rec.frame.extended && id == drivers::qnavcan::kIdModeCmd))) {
          ++can_skipped;
        } else {
          // A log whose clock steps back is played in file order at the last time (never backwards).
          const std::int64_t t = std::max(rec.time_us * 1000, last);
          can.push_back({t, rec.frame});
          last = t;
        }
      }
    }
    pos = end + 1;
  }
  if (can.empty()) {
    std::fprintf(stderr, "qnavd sim: sim.pass.candump %s: no frame to replay (%u lines are not `candump -l` records, %u skipped)\n", path.c_str(),
                 can_bad_lines, can_skipped);
    return Status(StatusCode::kInvalidArgument, "sim: the candump log has nothing to replay (see the line above)");
  }
  char line[512];
  std::snprintf(line, sizeof line, "candump %s: %zu frames over %.1f s (%u skipped: mode commands and qnavd's own; %u bad lines); ", path.c_str(),
                can.size(), static_cast<double>(can.back().t_ns - can.front().t_ns) * 1e-9, can_skipped, can_bad_lines);
  what += line;
  return Status::ok();
}

Status RecordedSensors::load_dvl(const std::string& path, bool pd6) {
  QNAV_RETURN_IF_ERROR(read_whole(path, "sim.pass.dvl_log", dvl_text));
  dvl.clear();
  std::size_t pos = 0;
  std::int64_t last = -1;
  bool open_has_time = false;
  while (pos < dvl_text.size()) {
    std::size_t end = dvl_text.find('\n', pos);
    end = end == std::string::npos ? dvl_text.size() : end + 1;
    const char* p = dvl_text.data() + pos;
    std::size_t n = end - pos;
    while (n > 0 && (p[n - 1] == '\n' || p[n - 1] == '\r')) --n;
    std::int64_t t = -1;
    bool starts = false;
    if (pd6) {
      const bool ts = pd6_time(p, n, t);
      starts = starts_with(p, n, ":SA") || (ts && open_has_time);
      if (!ts) t = -1;
    } else {
      starts = starts_with(p, n, "wrz") || starts_with(p, n, "wrx");
      if (!wrz_time(p, n, t)) t = -1;
    }
    if (starts || dvl.empty()) {
      dvl.push_back({-1, static_cast<std::uint32_t>(pos), 0});
      open_has_time = false;
    }
    ReplayDvlReport& r = dvl.back();
    r.length = static_cast<std::uint32_t>(end - r.offset);
    if (t >= 0 && !open_has_time) {
      r.t_ns = t;
      open_has_time = true;
    }
    pos = end;
  }
  // Reports without a time of their own follow the one before (the first timed one for the lines
  // before it); the replay never runs backwards.
  std::int64_t first = -1;
  for (const ReplayDvlReport& r : dvl)
    if (r.t_ns >= 0) {
      first = r.t_ns;
      break;
    }
  if (first < 0) {
    std::fprintf(stderr, "qnavd sim: sim.pass.dvl_log %s: no %s in it carries a time\n", path.c_str(),
                 pd6 ? "PD6 :TS line" : "Water Linked velocity report (wrz/wrx)");
    return Status(StatusCode::kInvalidArgument, "sim: the DVL capture has no timed sentence (see the line above; dvl.protocol?)");
  }
  last = first;
  for (ReplayDvlReport& r : dvl) {
    r.t_ns = std::max(r.t_ns, last);
    last = r.t_ns;
  }
  char line[512];
  std::snprintf(line, sizeof line, "DVL %s: %zu reports over %.1f s; ", path.c_str(), dvl.size(),
                static_cast<double>(dvl.back().t_ns - dvl.front().t_ns) * 1e-9);
  what += line;
  return Status::ok();
}

Status RecordedSensors::load_images(const std::string& dir, std::size_t max_frames) {
  pairs.clear();
  Status s = tools::read_kitti_sequence(dir, pairs);
  if (!s) s = tools::read_euroc_sequence(dir, pairs);
  if (!s || pairs.size() < 2) {
    std::fprintf(stderr, "qnavd sim: sim.pass.images %s: not a stereo sequence of at least two pairs (KITTI left/ right/, or EuRoC cam0/ cam1/): %s\n",
                 dir.c_str(), s ? "fewer than two pairs" : s.message());
    return Status(StatusCode::kInvalidArgument, "sim: the stereo sequence cannot be read (see the line above)");
  }
  if (max_frames > 0 && pairs.size() > max_frames) pairs.resize(max_frames);
  char line[512];
  std::snprintf(line, sizeof line, "images %s: %zu pairs over %.1f s; ", dir.c_str(), pairs.size(),
                static_cast<double>(pairs.back().stamp_ns - pairs.front().stamp_ns) * 1e-9);
  what += line;
  return Status::ok();
}

}  // namespace qnav::daemon
