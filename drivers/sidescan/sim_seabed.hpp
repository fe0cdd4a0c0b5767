// Procedural seabed for the side-scan simulator, with exact ground truth. Evaluated on demand at any
// (north, east) point: no raster, so routes of many km cost nothing in memory. Deterministic: the
// same seed gives the same seabed on every host (integer hashing, no global state).
// Content: large sediment patches and multi-octave value-noise texture (reflectivity), sand ripples
// (height + reflectivity, present where the patch field says "sand"), rocks scattered one-per-cell
// (hemispheres with height, brighter), and placed objects (boxes such as a wreck, cylinders) that
// stand above the seabed and so cast acoustic shadows in the simulated pings.
// Cost of sample(): about 20 hash evaluations + one sin + a loop over the placed objects (<= 16);
// O(1) memory (the Seabed is a small value type). Reflectivity is in [0.02, 1].
#pragma once

#include <climits>
#include <cstdint>

#include "nav/core/fixed_vector.hpp"
#include "nav/core/status.hpp"

namespace qnav::sidescan {

struct SeabedObject {
  enum class Kind : std::uint8_t { kBox, kCylinder };
  Kind kind = Kind::kBox;
  double north_m = 0.0, east_m = 0.0;  // centre
  float length_m = 10.0f;              // box: along heading_rad; cylinder: unused
  float width_m = 3.0f;                // box: across; cylinder: diameter
  float height_m = 2.0f;
  float heading_rad = 0.0f;
  float reflectivity = 0.95f;
};

struct SeabedConfig {
  std::uint64_t seed = 1;
  float base_reflectivity = 0.45f;
  float patch_scale_m = 40.0f;       // sediment patch size
  float patch_contrast = 0.25f;
  float texture_scale_m = 4.0f;      // largest texture feature (3 octaves below it)
  float texture_contrast = 0.25f;
  float ripple_wavelength_m = 0.9f;  // 0 = no ripples
  float ripple_heading_rad = 0.6f;   // direction of the ripple crest normal (compass)
  float ripple_height_m = 0.06f;
  float ripple_contrast = 0.2f;
  float rock_cell_m = 15.0f;         // one candidate rock per cell; 0 = no rocks
  float rock_probability = 0.35f;
  float rock_radius_min_m = 0.4f;
  float rock_radius_max_m = 1.6f;
  float rock_height_ratio = 0.7f;    // height = ratio * radius
  float rock_reflectivity = 0.85f;
  FixedVector<SeabedObject, 16> objects;
  // A seabed that changed since a route was taught over it (issue 29): all zero = unchanged, and the
  // seabed is then bit for bit the one above. The sand ripples moved by change_ripple_shift_m along
  // their crest normal; a fraction change_fraction of change_scale_m cells holds a patch whose
  // reflectivity moved by +/- change_contrast (a soft disc); and of the rock cells the same fraction
  // flipped: a rock vanished, or one appeared. change_seed says which.
  float change_ripple_shift_m = 0.0f;
  float change_fraction = 0.0f;
  float change_contrast = 0.3f;
  float change_scale_m = 12.0f;
  std::uint64_t change_seed = 7;
  // false: every changed cell's disc is centred in its cell with radius 0.45 cell, so the changed cells
  // form a 12 m lattice of equal discs (which any tile of the changed seabed matches at lattice shifts);
  // true: radius 0.2-0.45 cell and the centre drawn per cell (the disc stays inside it).
  bool change_irregular = false;
};

// What the seabed is at one point.
struct SeabedSample {
  float reflectivity = 0.0f;  // ground truth backscatter strength, [0.02, 1]
  float height_m = 0.0f;      // height above the mean seabed plane (z up)
};

// Memo of the lattice corners and rock cell last used, for callers that sample many nearby points in
// a row (the simulator's ground march). Results are bit-identical with and without it. One per
// thread and per Seabed (the memo does not know which seabed filled it).
struct SeabedCache {
  std::int64_t ix[4] = {INT64_MIN, INT64_MIN, INT64_MIN, INT64_MIN};
  std::int64_t iy[4] = {INT64_MIN, INT64_MIN, INT64_MIN, INT64_MIN};
  float v[4][4] = {};
  std::int64_t rock_fn = INT64_MIN, rock_fe = INT64_MIN;
  bool rock = false;
  float rock_r = 0.0f;
  double rock_cn = 0.0, rock_ce = 0.0;
};

class Seabed {
 public:
  Seabed() noexcept = default;
  Status init(const SeabedConfig& config) noexcept;
  SeabedSample sample(double north_m, double east_m) const noexcept;
  // Same value, reusing the corner hashes of the previous call when the point is in the same cells.
  SeabedSample sample(double north_m, double east_m, SeabedCache& cache) const noexcept;
  float reflectivity(double north_m, double east_m) const noexcept { return sample(north_m, east_m).reflectivity; }
  float height_m(double north_m, double east_m) const noexcept { return sample(north_m, east_m).height_m; }
  const SeabedConfig& config() const noexcept { return cfg_; }

 private:
  float value_noise(double x, double y, std::uint64_t salt, SeabedCache* cache, int slot) const noexcept;
  SeabedConfig cfg_{};
  float ripple_cn_ = 0.0f, ripple_ce_ = 0.0f;
};

}  // namespace qnav::sidescan
