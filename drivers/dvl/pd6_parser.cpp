#include "drivers/dvl/pd6_parser.hpp"

#include <cmath>

#include "drivers/dvl/text_fields.hpp"

namespace qnav::drivers::dvl {

namespace {
constexpr double kBad = -32768.0;
bool digits(Field f, std::size_t n) noexcept {
  if (f.n != n) return false;
  for (std::size_t i = 0; i < n; ++i)
    if (f.p[i] < '0' || f.p[i] > '9') return false;
  return true;
}
long long num(const char* p, int k) noexcept {
  long long v = 0;
  for (int i = 0; i < k; ++i) v = v * 10 + (p[i] - '0');
  return v;
}
}  // namespace

Result<Pd6Result> Pd6Parser::parse_line(const char* line, std::size_t n, std::int64_t arrival_ns, Pd6Ensemble& out) noexcept {
  if (line == nullptr) return Status(StatusCode::kInvalidArgument, "null line");
  while (n > 0 && (line[n - 1] == '\n' || line[n - 1] == '\r' || line[n - 1] == ' ')) --n;
  if (n > kMaxPd6Line) return reject(DvlCounter::kLength, StatusCode::kTruncated, "PD6 line too long");
  if (n < 4 || line[0] != ':') return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "not a PD6 sentence");
  Field f[8];
  const std::size_t nf = split_fields(line, n, ',', f, 8);
  if (nf > 8 || f[0].n != 3) return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "PD6 field count");
  const char a = line[1];
  const char b = line[2];
  auto start_if_needed = [&]() {
    if (!in_ensemble_) {
      cur_ = Pd6Ensemble{};
      have_bi_ = false;
      bi_good_ = false;
      first_arrival_ns_ = arrival_ns;
      in_ensemble_ = true;
    }
  };
  if (a == 'S' && b == 'A') {
    if (nf != 4) return reject(DvlCounter::kFormat, StatusCode::kCorrupt, ":SA needs 3 fields");
    in_ensemble_ = false;  // SA always opens a new ensemble
    stale_ensemble_ = false;
    start_if_needed();
    if (!parse_double(f[1], cur_.pitch_deg) || !parse_double(f[2], cur_.roll_deg) || !parse_double(f[3], cur_.heading_deg))
      return reject(DvlCounter::kFormat, StatusCode::kCorrupt, ":SA number");
    if (std::fabs(cur_.pitch_deg) > 90 || std::fabs(cur_.roll_deg) > 180 || cur_.heading_deg < 0 || cur_.heading_deg > 360)
      return reject(DvlCounter::kRange, StatusCode::kOutOfRange, ":SA angle out of range");
    cur_.has_attitude = true;
    return Pd6Result::kConsumed;
  }
  if (a == 'T' && b == 'S') {
    if (nf != 7) return reject(DvlCounter::kFormat, StatusCode::kCorrupt, ":TS needs 6 fields");
    if (in_ensemble_ && (cur_.has_ts || have_bi_)) in_ensemble_ = false;  // TS after data: a new ensemble
    stale_ensemble_ = false;
    start_if_needed();
    const Field t = trim(f[1]);
    double sal = 0;
    long long bit = 0;
    if (!digits(t, 14) || !parse_double(f[2], sal) || !parse_double(f[3], cur_.temperature_c) ||
        !parse_double(f[4], cur_.depth_m) || !parse_double(f[5], cur_.sound_speed_mps) || !parse_int(f[6], bit))
      return reject(DvlCounter::kFormat, StatusCode::kCorrupt, ":TS field");
    const long long hh = num(t.p + 6, 2), mm = num(t.p + 8, 2), ss = num(t.p + 10, 2), cs = num(t.p + 12, 2);
    const long long mon = num(t.p + 2, 2), day = num(t.p + 4, 2);
    if (mon < 1 || mon > 12 || day < 1 || day > 31 || hh > 23 || mm > 59 || ss > 60 || cur_.sound_speed_mps < 1300 ||
        cur_.sound_speed_mps > 1700)
      return reject(DvlCounter::kRange, StatusCode::kOutOfRange, ":TS value out of range");
    // Centiseconds since the start of the month: enough to order ensembles (stale check).
    const long long time_cs = (((day * 24 + hh) * 60 + mm) * 60 + ss) * 100 + cs;
    if (have_last_time_ && time_cs <= last_time_cs_ && time_cs > last_time_cs_ - 8640000) {  // not a day/month roll-over
      in_ensemble_ = false;
      stale_ensemble_ = true;
      return reject(DvlCounter::kStale, StatusCode::kInvalidArgument, ":TS time not advancing");
    }
    have_last_time_ = true;
    last_time_cs_ = time_cs;
    cur_.has_ts = true;
    cur_.velocity.device_time_us = (((hh * 60 + mm) * 60 + ss) * 100 + cs) * 10000;
    return Pd6Result::kConsumed;
  }
  if (b == 'I' || b == 'S' || b == 'E') {
    if (a != 'W' && a != 'B') return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "unknown PD6 sentence");
    const std::size_t want = b == 'I' ? 6u : 5u;
    if (nf != want) return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "PD6 velocity field count");
    double v[4] = {0, 0, 0, 0};
    for (std::size_t i = 1; i + 1 < want; ++i)
      if (!parse_double(f[i], v[i - 1])) return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "PD6 velocity number");
    const Field st = trim(f[want - 1]);
    if (st.n != 1 || (st.p[0] != 'A' && st.p[0] != 'V')) return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "status must be A or V");
    bool bad_marker = false;
    for (std::size_t i = 0; i + 2 < want; ++i) {
      if (v[i] == kBad) bad_marker = true;
      else if (std::fabs(v[i]) > 20000) return reject(DvlCounter::kRange, StatusCode::kOutOfRange, "PD6 velocity > 20 m/s");
    }
    if (stale_ensemble_) return Pd6Result::kConsumed;
    if (a == 'B' && b == 'I') {
      start_if_needed();
      have_bi_ = true;
      bi_good_ = st.p[0] == 'A' && !bad_marker;
      cur_.velocity.vx_mps = bad_marker ? 0 : v[0] / 1000.0;
      cur_.velocity.vy_mps = bad_marker ? 0 : v[1] / 1000.0;
      cur_.velocity.vz_mps = bad_marker ? 0 : v[2] / 1000.0;
      cur_.error_velocity_mps = v[3] == kBad ? -1 : v[3] / 1000.0;
      cur_.velocity.fom_mps = v[3] == kBad ? -1 : std::fabs(v[3]) / 1000.0;
    }
    return Pd6Result::kConsumed;
  }
  if (b == 'D' && (a == 'W' || a == 'B')) {
    if (nf != 6) return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "PD6 distance field count");
    double d[5];
    for (int i = 0; i < 5; ++i)
      if (!parse_double(f[i + 1], d[i])) return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "PD6 distance number");
    if (a == 'W' || stale_ensemble_) return Pd6Result::kConsumed;
    if (!in_ensemble_ || !have_bi_) {
      in_ensemble_ = false;
      return reject(DvlCounter::kFormat, StatusCode::kCorrupt, ":BD without :BI in the ensemble");
    }
    if (d[3] < 0 || d[4] < 0 || d[3] > kMaxDvlAltitudeM) {
      in_ensemble_ = false;
      return reject(DvlCounter::kRange, StatusCode::kOutOfRange, ":BD range negative or beyond 1,000 m, or negative time");
    }
    cur_.velocity.altitude_m = d[3];
    cur_.time_since_good_s = d[4];
    cur_.velocity.bottom_lock = bi_good_;
    cur_.velocity.source = DvlSource::kPd6;
    cur_.velocity.stamp.sample_ns = first_arrival_ns_;  // no latency field in PD6: first line of the ensemble
    cur_.velocity.stamp.arrival_ns = arrival_ns;
    if (!bi_good_) counters_.increment(DvlCounter::kNoLock);
    out = cur_;
    in_ensemble_ = false;
    return Pd6Result::kEnsemble;
  }
  return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "unknown PD6 sentence");
}

}  // namespace qnav::drivers::dvl
