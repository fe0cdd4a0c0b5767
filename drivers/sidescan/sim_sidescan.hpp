// Side-scan sonar simulator: renders the raw pings a real side-scan sonar would record over a
// procedural Seabed (sim_seabed.hpp), from a vehicle pose and altitude, with exact ground truth.
// Model, per side and ping (flat mean seabed at z = 0, sonar at altitude a above it):
//  - ground points are marched outward along the across-track line every ground_step (= slant
//    sample size); each point's height comes from the seabed (rocks, objects, ripples);
//  - shadows: a point is lit only if its depression angle is not shallower than that of any nearer
//    point (running horizon), so anything standing up casts an acoustic shadow behind it;
//  - backscatter = reflectivity * cos^2(incidence) (Lambert, with the local slope along the ray) *
//    surface length of the step (a face standing up returns energy in proportion to its height) *
//    vertical beam pattern (Gaussian around depression_rad, width beam_width_rad), which also makes
//    the weak nadir gap;
//  - each lit point adds its energy to the slant-range sample r = sqrt(g^2 + (a-h)^2) (linear split
//    between two samples), so layover and foreshortening come out naturally;
//  - amplitude = sqrt(energy) * Rayleigh speckle (unit mean, from a seeded table) * range loss
//    r^(-spreading_db/10) * 10^(-2*absorption*r/10) * gain, plus a noise floor; the water column
//    (r < a) holds noise only;
//  - speckle between pings: a real sonar's speckle stays partly coherent until it has moved about
//    half its transducer length. With speckle_coherence_m = L > 0 each sample's speckle is complex,
//    z = rho * z_previous_ping + sqrt(1 - rho^2) * w (w: this ping's own Rayleigh draw with a phase
//    from a separate stream), rho = 1 - d / L for a ping d metres from the previous one (0 when
//    d >= L, the first ping, or L = 0): |z| is again unit-mean Rayleigh, and a ping d >= L from the
//    previous one is bit-identical to a simulator without coherence.
// Deterministic: ping(index) depends only on the configs, the pose and the index; with
// speckle_coherence_m > 0 also on the previous ping() call since init() when it was closer than L.
// Memory: buffers sized by init() from samples_per_side (one allocation at init, none per ping).
// Cost: O(samples_per_side) Seabed::sample calls per side; about 0.1-0.3 ms per ping for 2 x 1024
// samples on the host (bench_sonar prints it).
#pragma once

#include <cstdint>
#include <memory>

#include "drivers/sidescan/sim_seabed.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/sonar/sonar_types.hpp"

namespace qnav::sidescan {

struct SideScanSimConfig {
  int samples_per_side = 1024;
  float slant_range_m = 50.0f;       // range of the last sample
  float depression_rad = 0.35f;      // beam axis below horizontal
  float beam_width_rad = 0.55f;      // Gaussian beam-pattern width (1/e)
  float spreading_db = 30.0f;        // must match the corrector's TVG for a flat result
  float absorption_db_per_m = 0.0f;
  float gain = 1000.0f;              // overall scale of the output amplitude
  float noise_floor = 0.02f;         // additive noise amplitude (in output units)
  bool speckle = true;
  // Along-track distance over which a ping's speckle stays partly coherent with the previous ping's
  // (see the model above); 0 = independent per ping. The real Iver2 file (600 kHz) decorrelates over
  // about 0.2 m (docs/route.md, scripts/sonar-speckle-corr).
  float speckle_coherence_m = 0.0f;
  std::uint64_t seed = 42;
};

class SideScanSimulator {
 public:
  SideScanSimulator() noexcept = default;
  // seabed must outlive the simulator.
  Status init(const SideScanSimConfig& config, const Seabed* seabed) noexcept;

  // Renders ping number ping_index from the TRUE pose (north, east, compass heading) at altitude_m
  // above the mean seabed into caller buffers of samples_per_side each (slant range, near first).
  Status ping(const Pose2& true_pose, float altitude_m, std::uint32_t ping_index, Span<float> port,
              Span<float> stbd) noexcept;

  // The same ping as a SonarPing over the simulator's own buffers (valid until the next call).
  Result<sonar::SonarPing> ping(const Pose2& true_pose, float altitude_m, std::uint32_t ping_index,
                                std::uint64_t stamp_ns) noexcept;

  // Ground truth: where slant sample i of a side lands on a flat seabed (north, east).
  Vec2d sample_position_ne(const Pose2& true_pose, float altitude_m, int side, int sample) const noexcept;

  const SideScanSimConfig& config() const noexcept { return cfg_; }
  const Seabed* seabed() const noexcept { return seabed_; }

 private:
  void render_side(const Pose2& pose, float altitude_m, int side, std::uint64_t rng_seed, float* out) noexcept;

  SideScanSimConfig cfg_{};
  const Seabed* seabed_ = nullptr;
  std::unique_ptr<float[]> mem_;  // energy accumulator + two output sides + loss table + the last ping's complex speckle (2 sides x re, im)
  std::size_t mem_samples_ = 0;   // samples per side mem_ was sized for (init() again with the same size allocates nothing)
  float* energy_ = nullptr;
  float* own_port_ = nullptr;
  float* own_stbd_ = nullptr;
  float* loss_ = nullptr;
  float* coh_ = nullptr;          // 4 * samples_per_side: side 0 re, im, side 1 re, im
  float coh_rho_ = 0.0f;          // coherence with the previous ping for the ping being rendered
  bool have_prev_ = false;
  Pose2 prev_pose_{};
  float rayleigh_[4096] = {};
};

}  // namespace qnav::sidescan
