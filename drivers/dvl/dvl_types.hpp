// Velocity sample every DVL driver produces (what nav/motion consumes).
//  - velocity in the instrument/vehicle frame (m/s): X forward, Y right (starboard), Z down, as the
//    DVL reports it; `bottom_lock` false means the velocity must not be used (DVL says invalid).
//  - altitude_m: range to the bottom (negative = unknown); fom_mps: figure of merit (WL) or error
//    velocity magnitude (PD6), negative = unknown.
#pragma once

#include <cstdint>

#include "hal/core/stamp.hpp"

namespace qnav::drivers::dvl {

// Plausibility bounds every parser applies (a value beyond them is a damaged field, rejected and
// counted as kRange, never passed on): no DVL bottom-tracks beyond 1,000 m (a 75 kHz long-ranger
// reaches ~700 m), and device clocks are bounded so differences of two of them and their conversion
// to nanoseconds cannot overflow 64 bits.
constexpr double kMaxDvlAltitudeM = 1000.0;
constexpr std::int64_t kMaxDvlDeviceTimeUs = 4000000000000000LL;  // ~127 years

enum class DvlSource : std::uint8_t { kWaterLinked, kPd6 };

struct DvlVelocity {
  double vx_mps = 0, vy_mps = 0, vz_mps = 0;
  bool bottom_lock = false;
  double altitude_m = -1;
  double fom_mps = -1;
  std::int64_t device_time_us = 0;  // the DVL's own clock (WL time_of_validity; PD6 TS time of day)
  hal::SampleStamp stamp;
  DvlSource source = DvlSource::kWaterLinked;
};

}  // namespace qnav::drivers::dvl
