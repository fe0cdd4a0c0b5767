// ScanlineCorrector: raw side-scan ping (slant range) -> corrected ground-range scanline.
// Steps, per ping:
//  1. Bottom (first return) detection when the ping has no altimeter value (altitude_m <= 0 or NaN):
//     both sides are summed, box-smoothed (bottom_smooth_samples), and the first sample whose level
//     exceeds noise + bottom_threshold_fraction * (peak - noise) is the seabed; samples nearer than
//     min_altitude_m are blanked (transmit pulse); noise = mean of the first bottom_noise_samples
//     samples after the blanking, peak = max up to bottom_search_fraction of the ping.
//  2. TVG model on slant samples: gain(r) = r^(spreading_db/10) * 10^(2 * absorption_db_per_m * r / 10)
//     (amplitude**2 convention: spreading_db = 20 means two-way 1/r^2 in intensity). The gain table
//     is rebuilt only when slant range or sample count change (O(n) with a log/exp per sample).
//  3. Slant -> ground range for a flat seabed: ground bin centre g -> slant r = sqrt(g^2 + h^2).
//     Speckle-aware resampling: when a ground bin spans one or more slant samples the samples inside
//     it are AVERAGED (prefix sums, O(1) per bin); otherwise linear interpolation at the bin centre.
//  4. Nadir gap: ground bins with g < nadir_gap_m, with slant r below the detected seabed, or beyond the
//     last sample are marked invalid (value 0, valid 0); the tile builder interpolates small holes.
//  5. Empirical gain normalisation (EGN): per side and per ground bin a running mean of the
//     TVG-corrected level (the plain mean of the bin's first 1/egn_alpha values, then exponential with
//     weight egn_alpha); the output is level / running mean, so a flat uniform seabed comes out at 1.0
//     whatever the range, beam pattern or gain.
// Memory: all buffers come from the Arena given to init() (sizes from the config); correct() makes
// no allocation. Cost of correct(): O(samples_per_side + ground_bins) per side, one sqrt per bin;
// bounded by max_samples_per_side and ground_bins_per_side.
// Bad input (NaN/inf/negative samples, wrong sizes, NaN range, no detectable bottom) -> error
// Status + a named counter; the output is then untouched.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/arena.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/sonar/sonar_types.hpp"

namespace qnav::sonar {

struct ScanlineCorrectorConfig {
  int max_samples_per_side = 4096;   // largest raw ping accepted
  int ground_bins_per_side = 512;    // output bins per side
  float ground_bin_m = 0.1f;         // output bin size (ground range per side = bins * bin_m)
  float nadir_gap_m = 0.0f;          // ground bins nearer than this are invalid
  // TVG model
  bool tvg_enabled = true;
  float spreading_db = 30.0f;        // 10*k*log10(r): 20 spherical two-way amplitude, 30-40 common in practice
  float absorption_db_per_m = 0.0f;  // one-way absorption (two-way applied)
  // EGN running normalisation
  bool egn_enabled = true;
  float egn_alpha = 0.02f;           // weight of the newest ping in the per-bin running mean
  // Bottom detection
  float bottom_threshold_fraction = 0.3f;
  int bottom_smooth_samples = 5;
  int bottom_noise_samples = 8;
  float bottom_search_fraction = 0.5f;
  float min_altitude_m = 0.5f;       // detected/altimeter values below are rejected
};

enum class CorrectorCounter : std::uint8_t {
  kBadSampleCount,
  kBadRange,
  kNonFiniteSample,
  kNoBottom,
  kBadAltitude,
  kCount
};
inline constexpr const char* kCorrectorCounterNames[] = {"bad_sample_count", "bad_range", "non_finite_sample",
                                                         "no_bottom", "bad_altitude"};

class ScanlineCorrector {
 public:
  ScanlineCorrector() noexcept = default;
  ScanlineCorrector(const ScanlineCorrector&) = delete;
  ScanlineCorrector& operator=(const ScanlineCorrector&) = delete;

  // Bytes init() takes from the arena for this configuration (for sizing the arena).
  static std::size_t arena_bytes(const ScanlineCorrectorConfig& config) noexcept;
  // Validates the config and carves every buffer from the arena. Call once at start-up.
  Status init(const ScanlineCorrectorConfig& config, Arena& arena) noexcept;

  // Corrects one ping. out's spans point into this object's buffers and stay valid until the next call.
  Status correct(const SonarPing& ping, CorrectedScanline& out) noexcept;

  // Bottom detection alone (exposed for tests): slant range of the first return, metres.
  Result<float> detect_bottom_m(const SonarPing& ping) noexcept;

  // Forget the EGN running means (new survey line).
  void reset_normalisation() noexcept;

  const CounterSet<CorrectorCounter>& counters() const noexcept { return counters_; }
  const ScanlineCorrectorConfig& config() const noexcept { return cfg_; }

 private:
  Status check_ping(const SonarPing& ping) noexcept;
  Result<float> detect_bottom_checked(const SonarPing& ping) noexcept;
  void update_tvg(float slant_range_m, int n) noexcept;
  void bin_geometry(int n, float dr_m, float altitude_m) noexcept;
  void prefix_sums(const SonarPing& ping) noexcept;  // both sides' in one pass (two independent chains)
  void correct_side(const double* prefix, int n, float* egn_mean, std::uint16_t* egn_count, float* out, std::uint8_t* valid) noexcept;

  // One ground bin's slant-range footprint, the same for both sides of a ping (bin_geometry()).
  struct BinGeometry {
    double f0 = 0.0, f1 = 0.0;  // kAverage: fractional sample ends; kInterpolate: f0 = weight of the next sample
    double span = 0.0;          // kAverage: s1 - s0 (samples covered)
    std::int32_t i0 = 0, i1 = 0;  // kAverage: sample indices of the ends; kInterpolate: i0 = first sample
    std::uint8_t kind = 0;        // kOutside, kAverage, kInterpolate
  };

  ScanlineCorrectorConfig cfg_{};
  bool ready_ = false;
  Span<float> tvg_;        // per slant sample gain
  Span<double> prefix_, prefix_stbd_;  // prefix sums of TVG-corrected samples (n + 1), port and starboard
  Span<float> smooth_;     // bottom detection work buffer
  Span<BinGeometry> geometry_;  // per ground bin, this ping's (both sides)
  Span<float> egn_port_, egn_stbd_;
  Span<std::uint16_t> egn_n_port_, egn_n_stbd_;  // values seen per bin (saturating)
  Span<float> out_port_, out_stbd_;
  Span<std::uint8_t> valid_port_, valid_stbd_;
  float tvg_range_m_ = -1.0f;
  int tvg_n_ = -1;
  // The inputs bin_geometry() last computed geometry_ for (a detected altitude is a whole number of
  // samples, so consecutive pings often repeat it): the same inputs reuse the table.
  int geom_n_ = -1;
  float geom_dr_m_ = -1.0f, geom_altitude_m_ = -1.0f;
  CounterSet<CorrectorCounter> counters_{kCorrectorCounterNames};
};

}  // namespace qnav::sonar
