// SimSurvey: the simulated side-scan survey every route consumer shares (qnavd's sim backend, `qnav
// route train|repeat|eval` and the demo): a route of length_m with two gentle bends over a seeded
// procedural seabed, flown at 1.5 m/s with 5 pings/s at 8 m altitude, and dead reckoning with the
// errors a DVL + compass gives (heading bias 0.004 rad, 0.002 rad noise, 0.5 % speed scale).
// pass() gives one pass over it: lateral offset (m, right of the taught direction), reverse, seed.
// Memory: the seabed's tables (sidescan::Seabed) and the configs; no heap after init().
#pragma once

#include <cstdint>

#include "drivers/sidescan/sim_seabed.hpp"
#include "drivers/sidescan/sim_sidescan.hpp"
#include "drivers/sidescan/sim_trajectory.hpp"
#include "nav/core/status.hpp"

namespace qnav::pipeline {

struct SimSurvey {
  sidescan::Seabed seabed;
  sidescan::SideScanSimConfig sonar;
  sidescan::TrajectoryConfig route;
  double swath_m = 0.0;  // full ground swath, both sides

  // length_m in [200, 50000].
  Status init(double length_m, std::uint64_t seed);
  // Each pass gets its own speckle (the simulator's speckle is a function of seed and ping index, so
  // two passes with one seed would share vehicle-fixed speckle "features").
  sidescan::SideScanSimConfig sonar_for(std::uint64_t seed) const;
  sidescan::TrajectoryConfig pass(double lateral_m, bool reverse, std::uint64_t seed) const;
  // Node spacing of a route taught on this survey with tiles every `scanline_stride` pings.
  double node_spacing_m(int scanline_stride) const { return scanline_stride * route.speed_mps / route.ping_rate_hz; }
};

// The pass seeds the tools use: the teach pass and the repeat pass of `qnav route train|repeat`.
inline std::uint64_t teach_pass_seed(std::uint64_t seed) { return seed * 7 + 1; }
inline std::uint64_t repeat_pass_seed(std::uint64_t seed) { return seed * 13 + 5; }

}  // namespace qnav::pipeline
