#include "nav/sonar/scanline_corrector.hpp"

#include <cmath>
#include <cstring>

namespace qnav::sonar {

namespace {
constexpr std::size_t kAlign = 16;
std::size_t padded(std::size_t bytes) noexcept { return bytes + kAlign; }
bool finite_positive(float v) noexcept { return std::isfinite(v) && v > 0.0f; }
constexpr std::uint8_t kOutside = 0, kAverage = 1, kInterpolate = 2;  // BinGeometry::kind
}  // namespace

std::size_t ScanlineCorrector::arena_bytes(const ScanlineCorrectorConfig& c) noexcept {
  const std::size_t n = c.max_samples_per_side > 0 ? static_cast<std::size_t>(c.max_samples_per_side) : 0;
  const std::size_t b = c.ground_bins_per_side > 0 ? static_cast<std::size_t>(c.ground_bins_per_side) : 0;
  return padded(n * sizeof(float)) + 2 * padded((n + 1) * sizeof(double)) + padded(n * sizeof(float)) +
         4 * padded(b * sizeof(float)) + 2 * padded(b) + 2 * padded(b * sizeof(std::uint16_t)) + padded(b * sizeof(BinGeometry));
}

Status ScanlineCorrector::init(const ScanlineCorrectorConfig& c, Arena& arena) noexcept {
  ready_ = false;
  if (c.max_samples_per_side < 8 || c.max_samples_per_side > 65536)
    return Status(StatusCode::kInvalidArgument, "max_samples_per_side outside [8, 65536]");
  if (c.ground_bins_per_side < 1 || c.ground_bins_per_side > 65536)
    return Status(StatusCode::kInvalidArgument, "ground_bins_per_side outside [1, 65536]");
  if (!finite_positive(c.ground_bin_m)) return Status(StatusCode::kInvalidArgument, "ground_bin_m must be > 0");
  if (!std::isfinite(c.nadir_gap_m) || c.nadir_gap_m < 0.0f) return Status(StatusCode::kInvalidArgument, "nadir_gap_m < 0");
  if (!std::isfinite(c.spreading_db) || !std::isfinite(c.absorption_db_per_m) || c.absorption_db_per_m < 0.0f)
    return Status(StatusCode::kInvalidArgument, "bad TVG parameters");
  if (!(c.egn_alpha > 0.0f && c.egn_alpha <= 1.0f)) return Status(StatusCode::kInvalidArgument, "egn_alpha outside (0, 1]");
  if (!(c.bottom_threshold_fraction > 0.0f && c.bottom_threshold_fraction < 1.0f))
    return Status(StatusCode::kInvalidArgument, "bottom_threshold_fraction outside (0, 1)");
  if (c.bottom_smooth_samples < 1 || c.bottom_smooth_samples > 256 || c.bottom_noise_samples < 1 ||
      c.bottom_noise_samples > c.max_samples_per_side / 2)
    return Status(StatusCode::kInvalidArgument, "bad bottom detection window");
  if (!(c.bottom_search_fraction > 0.0f && c.bottom_search_fraction <= 1.0f))
    return Status(StatusCode::kInvalidArgument, "bottom_search_fraction outside (0, 1]");
  if (!std::isfinite(c.min_altitude_m) || c.min_altitude_m < 0.0f) return Status(StatusCode::kInvalidArgument, "min_altitude_m < 0");
  const std::size_t n = static_cast<std::size_t>(c.max_samples_per_side);
  const std::size_t b = static_cast<std::size_t>(c.ground_bins_per_side);
  tvg_ = arena.allocate<float>(n);
  prefix_ = arena.allocate<double>(n + 1);
  prefix_stbd_ = arena.allocate<double>(n + 1);
  smooth_ = arena.allocate<float>(n);
  geometry_ = arena.allocate<BinGeometry>(b);
  egn_port_ = arena.allocate<float>(b);
  egn_stbd_ = arena.allocate<float>(b);
  egn_n_port_ = arena.allocate<std::uint16_t>(b);
  egn_n_stbd_ = arena.allocate<std::uint16_t>(b);
  out_port_ = arena.allocate<float>(b);
  out_stbd_ = arena.allocate<float>(b);
  valid_port_ = arena.allocate<std::uint8_t>(b);
  valid_stbd_ = arena.allocate<std::uint8_t>(b);
  if (tvg_.empty() || prefix_.empty() || prefix_stbd_.empty() || smooth_.empty() || geometry_.empty() || egn_port_.empty() || egn_stbd_.empty() || egn_n_port_.empty() || egn_n_stbd_.empty() || out_port_.empty() ||
      out_stbd_.empty() || valid_port_.empty() || valid_stbd_.empty())
    return Status(StatusCode::kCapacityExceeded, "arena too small for ScanlineCorrector");
  cfg_ = c;
  tvg_range_m_ = -1.0f;
  tvg_n_ = -1;
  geom_n_ = -1;
  reset_normalisation();
  ready_ = true;
  return Status::ok();
}

void ScanlineCorrector::reset_normalisation() noexcept {
  for (float& v : egn_port_) v = 0.0f;
  for (float& v : egn_stbd_) v = 0.0f;
  for (std::uint16_t& n : egn_n_port_) n = 0;
  for (std::uint16_t& n : egn_n_stbd_) n = 0;
}

Status ScanlineCorrector::check_ping(const SonarPing& ping) noexcept {
  if (!ready_) return Status(StatusCode::kNotReady, "ScanlineCorrector not initialised");
  const std::size_t n = ping.port.size();
  if (n < 8 || n != ping.stbd.size() || n > static_cast<std::size_t>(cfg_.max_samples_per_side) ||
      ping.port.data() == nullptr || ping.stbd.data() == nullptr) {
    counters_.increment(CorrectorCounter::kBadSampleCount);
    return Status(StatusCode::kInvalidArgument, "ping sample count: sides differ, < 8 or above max_samples_per_side");
  }
  // A range no longer than the blanking distance cannot hold a seabed return: it is a damaged
  // field (one flipped bit turns 30 m into 8.8e-38), and every index computed from it would be absurd.
  if (!finite_positive(ping.slant_range_m) || ping.slant_range_m <= cfg_.min_altitude_m || ping.slant_range_m > 100000.0f) {
    counters_.increment(CorrectorCounter::kBadRange);
    return Status(StatusCode::kInvalidArgument, "ping slant range not finite, not above min_altitude_m or above 100 km");
  }
  // Finite and >= 0 (-0 included), on the bits: u < 0x7f800000 (sign clear, exponent not all ones) or
  // u == 0x80000000 (-0). One branch-free integer pass the compiler vectorises; no float compares.
  const float* pp = ping.port.data();
  const float* ps = ping.stbd.data();
  std::uint32_t bad = 0;
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t a, b;
    std::memcpy(&a, pp + i, sizeof a);
    std::memcpy(&b, ps + i, sizeof b);
    bad |= (static_cast<std::uint32_t>(a >= 0x7f800000u) & static_cast<std::uint32_t>(a != 0x80000000u)) |
           (static_cast<std::uint32_t>(b >= 0x7f800000u) & static_cast<std::uint32_t>(b != 0x80000000u));
  }
  if (bad != 0) {
    counters_.increment(CorrectorCounter::kNonFiniteSample);
    return Status(StatusCode::kInvalidArgument, "ping sample NaN, infinite or negative");
  }
  return Status::ok();
}

Result<float> ScanlineCorrector::detect_bottom_m(const SonarPing& ping) noexcept {
  QNAV_RETURN_IF_ERROR(check_ping(ping));
  return detect_bottom_checked(ping);
}

Result<float> ScanlineCorrector::detect_bottom_checked(const SonarPing& ping) noexcept {
  const int n = static_cast<int>(ping.port.size());
  const int w = cfg_.bottom_smooth_samples;
  int search = static_cast<int>(static_cast<float>(n) * cfg_.bottom_search_fraction);
  if (search > n) search = n;
  // Box-smoothed sum of both sides (running window, O(n)); only the search window is ever read.
  double acc = 0.0;
  for (int i = 0; i < search; ++i) {
    acc += static_cast<double>(ping.port[i]) + static_cast<double>(ping.stbd[i]);
    if (i >= w) acc -= static_cast<double>(ping.port[i - w]) + static_cast<double>(ping.stbd[i - w]);
    const int cnt = i + 1 < w ? i + 1 : w;
    smooth_[static_cast<std::size_t>(i)] = static_cast<float>(acc / cnt);
  }
  // Blanking: samples nearer than min_altitude_m (transmit pulse, ringing) are not looked at.
  const float dr = ping.slant_range_m / static_cast<float>(n);
  // Computed in double and clamped before the conversion: no float-to-int overflow whatever the range.
  const double blank = std::ceil(static_cast<double>(cfg_.min_altitude_m) / static_cast<double>(dr));
  int start = (blank < static_cast<double>(n) ? static_cast<int>(blank) : n) + w;
  const int noise_n = cfg_.bottom_noise_samples;
  if (search <= start + noise_n + w) {
    counters_.increment(CorrectorCounter::kNoBottom);
    return Status(StatusCode::kNotFound, "bottom search window too short");
  }
  double noise = 0.0;
  for (int i = start; i < start + noise_n; ++i) noise += static_cast<double>(smooth_[static_cast<std::size_t>(i)]);
  noise /= noise_n;
  float peak = 0.0f;
  for (int i = start; i < search; ++i) peak = smooth_[static_cast<std::size_t>(i)] > peak ? smooth_[static_cast<std::size_t>(i)] : peak;
  const double thr = noise + static_cast<double>(cfg_.bottom_threshold_fraction) * (static_cast<double>(peak) - noise);
  if (!(static_cast<double>(peak) > 2.0 * noise + 1e-12)) {
    counters_.increment(CorrectorCounter::kNoBottom);
    return Status(StatusCode::kNotFound, "no first return above the water-column level");
  }
  for (int i = start; i < search; ++i) {
    if (static_cast<double>(smooth_[static_cast<std::size_t>(i)]) > thr) {
      // The box-smoothed value crosses a step about (w-1)/2 samples early: compensate half a window.
      const float idx = static_cast<float>(i) - 0.5f * static_cast<float>(w - 1);
      const float h = (idx > 0.0f ? idx : 0.0f) * dr;
      if (h < cfg_.min_altitude_m) break;
      return h;
    }
  }
  counters_.increment(CorrectorCounter::kNoBottom);
  return Status(StatusCode::kNotFound, "no first return found");
}

void ScanlineCorrector::update_tvg(float slant_range_m, int n) noexcept {
  if (slant_range_m == tvg_range_m_ && n == tvg_n_) return;
  const double dr = static_cast<double>(slant_range_m) / n;
  const double k = static_cast<double>(cfg_.spreading_db) / 10.0;
  const double a = 2.0 * static_cast<double>(cfg_.absorption_db_per_m) / 10.0;
  for (int i = 0; i < n; ++i) {
    const double r = (i + 0.5) * dr;
    tvg_[static_cast<std::size_t>(i)] = cfg_.tvg_enabled ? static_cast<float>(std::pow(r, k) * std::pow(10.0, a * r)) : 1.0f;
  }
  tvg_range_m_ = slant_range_m;
  tvg_n_ = n;
}

void ScanlineCorrector::bin_geometry(int n, float dr_m, float altitude_m) noexcept {
  if (n == geom_n_ && dr_m == geom_dr_m_ && altitude_m == geom_altitude_m_) return;  // the table is a function of these alone
  geom_n_ = n;
  geom_dr_m_ = dr_m;
  geom_altitude_m_ = altitude_m;
  const double h2 = static_cast<double>(altitude_m) * static_cast<double>(altitude_m);
  const double g_bin = static_cast<double>(cfg_.ground_bin_m);
  const double inv_dr = 1.0 / static_cast<double>(dr_m);
  const double r_max = static_cast<double>(dr_m) * n;
  const int bins = cfg_.ground_bins_per_side;
  for (int b = 0; b < bins; ++b) {
    BinGeometry& q = geometry_[static_cast<std::size_t>(b)];
    const double g0 = b * g_bin, g1 = (b + 1) * g_bin;
    const double r1 = std::sqrt(g1 * g1 + h2);
    if (g0 < static_cast<double>(cfg_.nadir_gap_m) || r1 > r_max) {
      q.kind = kOutside;
      continue;
    }
    const double r0 = std::sqrt(g0 * g0 + h2);
    const double s0 = r0 * inv_dr, s1 = r1 * inv_dr;  // sample coordinates (sample i spans [i, i+1))
    if (s1 - s0 >= 1.0) {
      // Average of the samples covered (fractional ends by linear prefix interpolation).
      q.kind = kAverage;
      q.i0 = static_cast<std::int32_t>(static_cast<int>(s0));
      q.f0 = s0 - q.i0;
      q.i1 = static_cast<std::int32_t>(static_cast<int>(s1));
      q.f1 = s1 - q.i1;
      q.span = s1 - s0;
    } else {
      // Linear interpolation between sample centres at the bin centre.
      const double gc = 0.5 * (g0 + g1);
      const double x = std::sqrt(gc * gc + h2) * inv_dr - 0.5;
      int i = static_cast<int>(x);
      if (x < 0.0) i = 0;
      if (i > n - 2) i = n - 2;
      double f = x - i;
      if (f < 0.0) f = 0.0;
      if (f > 1.0) f = 1.0;
      q.kind = kInterpolate;
      q.i0 = i;
      q.f0 = f;
    }
  }
}

void ScanlineCorrector::prefix_sums(const SonarPing& ping) noexcept {
  // Each side's sum is the same serial chain of double additions as before; the two sides are
  // interleaved so that one's addition latency hides the other's.
  const int n = static_cast<int>(ping.port.size());
  const float* sp = ping.port.data();
  const float* ss = ping.stbd.data();
  const float* g = tvg_.data();
  double* pp = prefix_.data();
  double* ps = prefix_stbd_.data();
  double ap = 0.0, as = 0.0;
  pp[0] = 0.0;
  ps[0] = 0.0;
  for (int i = 0; i < n; ++i) {
    ap += static_cast<double>(sp[i] * g[i]);
    as += static_cast<double>(ss[i] * g[i]);
    pp[i + 1] = ap;
    ps[i + 1] = as;
  }
}

void ScanlineCorrector::correct_side(const double* p, int n, float* egn, std::uint16_t* egn_n, float* out, std::uint8_t* valid) noexcept {
  const float alpha = cfg_.egn_alpha;
  const int bins = cfg_.ground_bins_per_side;
  const auto prefix_at = [p, n](std::int32_t i, double f) { return i >= n ? p[n] : p[i] + f * (p[i + 1] - p[i]); };
  for (int b = 0; b < bins; ++b) {
    const BinGeometry& q = geometry_[static_cast<std::size_t>(b)];
    if (q.kind == kOutside) {
      out[b] = 0.0f;
      valid[b] = 0;
      continue;
    }
    double level;
    if (q.kind == kAverage) {
      level = (prefix_at(q.i1, q.f1) - prefix_at(q.i0, q.f0)) / q.span;
    } else {
      const double v0 = p[q.i0 + 1] - p[q.i0];
      const double v1 = p[q.i0 + 2] - p[q.i0 + 1];
      level = v0 + q.f0 * (v1 - v0);
    }
    float v = static_cast<float>(level);
    if (cfg_.egn_enabled) {
      // Plain mean of the first 1/alpha values seen by the bin, then the exponential running mean.
      // Once (k + 1) alpha > 2, 1 / (k + 1) < alpha for certain: the division is skipped (same a).
      float& m = egn[b];
      std::uint16_t& k = egn_n[b];
      const float kf = static_cast<float>(k + 1);
      const float a = kf * alpha > 2.0f ? alpha : (1.0f / kf > alpha ? 1.0f / kf : alpha);
      m += a * (v - m);
      if (k < 65535) ++k;
      v = m > 1e-20f ? v / m : 0.0f;
    }
    out[b] = v;
    valid[b] = 1;
  }
}

Status ScanlineCorrector::correct(const SonarPing& ping, CorrectedScanline& out) noexcept {
  QNAV_RETURN_IF_ERROR(check_ping(ping));
  float h = ping.altitude_m;
  bool detected = false;
  if (!(std::isfinite(h) && h > 0.0f)) {
    const Result<float> b = detect_bottom_checked(ping);
    if (!b) return b.status();
    h = b.value();
    detected = true;
  } else if (h < cfg_.min_altitude_m || h >= ping.slant_range_m) {
    counters_.increment(CorrectorCounter::kBadAltitude);
    return Status(StatusCode::kInvalidArgument, "altitude below min_altitude_m or beyond the slant range");
  }
  const int n = static_cast<int>(ping.port.size());
  update_tvg(ping.slant_range_m, n);
  const float dr = ping.slant_range_m / static_cast<float>(n);
  bin_geometry(n, dr, h);
  prefix_sums(ping);
  correct_side(prefix_.data(), n, egn_port_.data(), egn_n_port_.data(), out_port_.data(), valid_port_.data());
  correct_side(prefix_stbd_.data(), n, egn_stbd_.data(), egn_n_stbd_.data(), out_stbd_.data(), valid_stbd_.data());
  out.stamp_ns = ping.stamp_ns;
  out.ping_number = ping.ping_number;
  out.bin_m = cfg_.ground_bin_m;
  out.altitude_m = h;
  out.altitude_detected = detected;
  out.port = Span<const float>(out_port_.data(), out_port_.size());
  out.stbd = Span<const float>(out_stbd_.data(), out_stbd_.size());
  out.port_valid = Span<const std::uint8_t>(valid_port_.data(), valid_port_.size());
  out.stbd_valid = Span<const std::uint8_t>(valid_stbd_.data(), valid_stbd_.size());
  return Status::ok();
}

}  // namespace qnav::sonar
