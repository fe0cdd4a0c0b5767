#include "drivers/sidescan/sim_sidescan.hpp"

#include <cmath>
#include <new>

namespace qnav::sidescan {

namespace {
std::uint64_t mix64(std::uint64_t z) noexcept {
  z += 0x9E3779B97F4A7C15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}
struct Xorshift {
  std::uint64_t s;
  std::uint64_t next() noexcept {
    s ^= s << 13;
    s ^= s >> 7;
    s ^= s << 17;
    return s;
  }
};
}  // namespace

Status SideScanSimulator::init(const SideScanSimConfig& c, const Seabed* seabed) noexcept {
  if (seabed == nullptr) return Status(StatusCode::kInvalidArgument, "simulator needs a seabed");
  if (c.samples_per_side < 16 || c.samples_per_side > 65536) return Status(StatusCode::kInvalidArgument, "samples_per_side outside [16, 65536]");
  if (!(c.slant_range_m > 1.0f && c.slant_range_m < 10000.0f)) return Status(StatusCode::kInvalidArgument, "slant_range_m outside (1, 10000)");
  if (!(c.beam_width_rad > 0.0f) || !std::isfinite(c.depression_rad)) return Status(StatusCode::kInvalidArgument, "bad beam pattern");
  if (!(c.gain > 0.0f) || !(c.noise_floor >= 0.0f) || !std::isfinite(c.spreading_db) || !(c.absorption_db_per_m >= 0.0f))
    return Status(StatusCode::kInvalidArgument, "bad gain, noise or loss");
  if (!(c.speckle_coherence_m >= 0.0f && c.speckle_coherence_m < 1000.0f))
    return Status(StatusCode::kInvalidArgument, "speckle_coherence_m outside [0, 1000)");
  const std::size_t n = static_cast<std::size_t>(c.samples_per_side);
  if (!mem_ || mem_samples_ != n) {  // a second init() of the same size (a new pass) reuses the buffers
    mem_.reset(new (std::nothrow) float[8 * n]);
    if (!mem_) return Status(StatusCode::kCapacityExceeded, "out of memory for the simulator");
    mem_samples_ = n;
  }
  energy_ = mem_.get();
  own_port_ = energy_ + n;
  own_stbd_ = own_port_ + n;
  loss_ = own_stbd_ + n;
  coh_ = loss_ + n;
  have_prev_ = false;
  coh_rho_ = 0.0f;
  cfg_ = c;
  seabed_ = seabed;
  const double dr = static_cast<double>(c.slant_range_m) / static_cast<double>(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double r = (static_cast<double>(i) + 0.5) * dr;
    const double rel = r / static_cast<double>(c.slant_range_m);
    loss_[i] = static_cast<float>(std::pow(rel, -static_cast<double>(c.spreading_db) / 10.0) *
                                  std::pow(10.0, -2.0 * static_cast<double>(c.absorption_db_per_m) * r / 10.0));
  }
  // Rayleigh quantiles with unit mean: R = sqrt(-ln(1-u)) * 2/sqrt(pi).
  for (int k = 0; k < 4096; ++k) {
    const double u = (k + 0.5) / 4096.0;
    rayleigh_[k] = static_cast<float>(std::sqrt(-std::log(1.0 - u)) * 2.0 / std::sqrt(kPi));
  }
  return Status::ok();
}

Vec2d SideScanSimulator::sample_position_ne(const Pose2& pose, float altitude_m, int side, int sample) const noexcept {
  const double dr = static_cast<double>(cfg_.slant_range_m) / cfg_.samples_per_side;
  const double r = (sample + 0.5) * dr, a = static_cast<double>(altitude_m);
  const double g = r > a ? std::sqrt(r * r - a * a) : 0.0;
  return pose.translation() + (side == 0 ? -g : g) * sonar::starboard_unit(pose.heading_rad);
}

void SideScanSimulator::render_side(const Pose2& pose, float altitude_m, int side, std::uint64_t rng_seed, float* out) noexcept {
  const int n = cfg_.samples_per_side;
  const double R = static_cast<double>(cfg_.slant_range_m);
  const double dr = R / n;
  const double a = static_cast<double>(altitude_m);
  for (int i = 0; i < n; ++i) energy_[i] = 0.0f;
  const double g_max = R > a ? std::sqrt(R * R - a * a) : 0.0;
  const double dg = 0.7 * dr;
  const int m = static_cast<int>(g_max / dg);
  const Vec2d dir = (side == 0 ? -1.0 : 1.0) * sonar::starboard_unit(pose.heading_rad);
  const double dep0 = static_cast<double>(cfg_.depression_rad);
  const double inv_bw = 1.0 / static_cast<double>(cfg_.beam_width_rad);
  SeabedCache cache;  // consecutive ground points share lattice cells: same values, fewer hashes
  double min_tan = 1e300;
  double h_prev = 0.0;
  for (int k = 0; k < m; ++k) {
    const double g = (k + 0.5) * dg;
    const SeabedSample s = seabed_->sample(pose.x_m + g * dir.x(), pose.y_m + g * dir.y(), cache);
    const double h = static_cast<double>(s.height_m);
    const double up = a - h;
    const double tan_dep = up / g;
    const bool lit = tan_dep <= min_tan + 1e-12 && up > 0.0;
    if (tan_dep < min_tan) min_tan = tan_dep;
    const double dh = k == 0 ? 0.0 : h - h_prev;
    const double slope = dh / dg;
    h_prev = h;
    if (!lit) continue;
    const double r = std::sqrt(g * g + up * up);
    const double cos_inc = (g * slope + up) / (r * std::sqrt(1.0 + slope * slope));
    if (cos_inc <= 0.0) continue;
    const double dep = std::atan2(up, g);
    const double t = (dep - dep0) * inv_bw;
    const double e = static_cast<double>(s.reflectivity) * cos_inc * cos_inc * std::exp(-t * t) *
                     std::sqrt(dg * dg + dh * dh);  // surface length: a vertical face returns energy by its height
    const double x = r / dr - 0.5;
    if (x < 0.0 || x >= n - 1) {
      if (x >= n - 1 && x < n) energy_[n - 1] += static_cast<float>(e);
      continue;
    }
    const int i = static_cast<int>(x);
    const double f = x - i;
    energy_[i] += static_cast<float>((1.0 - f) * e);
    energy_[i + 1] += static_cast<float>(f * e);
  }
  Xorshift rng{mix64(rng_seed) | 1u};
  const float inv_dr = static_cast<float>(1.0 / dr);
  const float noise = cfg_.noise_floor * cfg_.gain;
  const bool coherent = cfg_.speckle && cfg_.speckle_coherence_m > 0.0f;
  // Phases from a stream of their own: the amplitude stream, and so a ping with rho = 0, is the same
  // as without coherence.
  Xorshift phase_rng{mix64(rng_seed ^ 0x2545F4914F6CDD1DULL) | 1u};
  float* zre = coh_ + static_cast<std::ptrdiff_t>(2 * side) * n;
  float* zim = zre + n;
  const float rho = coh_rho_, keep = std::sqrt(1.0f - rho * rho);
  constexpr float kTwoPiOver2p24 = static_cast<float>(2.0 * kPi / 16777216.0);
  for (int i = 0; i < n; ++i) {
    float sp = cfg_.speckle ? rayleigh_[rng.next() >> 52] : 1.0f;
    const float nz = cfg_.speckle ? rayleigh_[rng.next() >> 52] : 1.0f;
    if (coherent) {
      const float phi = static_cast<float>(phase_rng.next() >> 40) * kTwoPiOver2p24;
      float re = sp * std::cos(phi), im = sp * std::sin(phi);
      if (rho > 0.0f) {
        re = rho * zre[i] + keep * re;
        im = rho * zim[i] + keep * im;
        sp = std::sqrt(re * re + im * im);
      }
      zre[i] = re;
      zim[i] = im;
    }
    out[i] = cfg_.gain * std::sqrt(energy_[i] * inv_dr) * sp * loss_[i] + noise * nz;
  }
}

Status SideScanSimulator::ping(const Pose2& pose, float altitude_m, std::uint32_t ping_index, Span<float> port,
                               Span<float> stbd) noexcept {
  if (seabed_ == nullptr) return Status(StatusCode::kNotReady, "simulator not initialised");
  if (port.size() != static_cast<std::size_t>(cfg_.samples_per_side) || stbd.size() != port.size())
    return Status(StatusCode::kInvalidArgument, "output buffers must hold samples_per_side");
  if (!pose.is_finite() || !std::isfinite(altitude_m) || altitude_m <= 0.0f)
    return Status(StatusCode::kInvalidArgument, "pose or altitude not finite / altitude <= 0");
  const std::uint64_t base = mix64(cfg_.seed ^ (static_cast<std::uint64_t>(ping_index) << 1));
  coh_rho_ = 0.0f;
  if (have_prev_ && cfg_.speckle_coherence_m > 0.0f) {
    const double d = (pose.translation() - prev_pose_.translation()).norm();
    const double rho = 1.0 - d / static_cast<double>(cfg_.speckle_coherence_m);
    coh_rho_ = rho > 0.0 ? static_cast<float>(rho) : 0.0f;
  }
  render_side(pose, altitude_m, 0, base, port.data());
  render_side(pose, altitude_m, 1, base ^ 0x5555555555555555ULL, stbd.data());
  prev_pose_ = pose;
  have_prev_ = true;
  return Status::ok();
}

Result<sonar::SonarPing> SideScanSimulator::ping(const Pose2& pose, float altitude_m, std::uint32_t ping_index,
                                                 std::uint64_t stamp_ns) noexcept {
  const std::size_t n = static_cast<std::size_t>(cfg_.samples_per_side);
  const Status s = ping(pose, altitude_m, ping_index, Span<float>(own_port_, n), Span<float>(own_stbd_, n));
  if (!s) return s;
  sonar::SonarPing p;
  p.stamp_ns = stamp_ns;
  p.ping_number = ping_index;
  p.port = Span<const float>(own_port_, n);
  p.stbd = Span<const float>(own_stbd_, n);
  p.slant_range_m = cfg_.slant_range_m;
  p.altitude_m = altitude_m;
  return p;
}

}  // namespace qnav::sidescan
