// The freestanding workload: one VO step, one route-filter update and the XTF decoding of the canned
// sonar pings (the byte-order-sensitive parser, big-endian on the LEON3) from the canned stages
// (test/timing/canned.hpp, the same code the hosted timing program counts), each reduced to the
// stage's 64-bit result hash. Pure code, shared by the LEON3 image (main_leon3.cpp) and its host
// reference (main_host.cpp), which must print the same numbers.
#pragma once

#include <cstdint>

#include "nav/core/status.hpp"

namespace qnav::timing {

struct FreestandingResult {
  std::uint64_t vo_step = 0;       // CannedVo: reference frame 0, then the VO step 0 -> 1 (pose, matches, ...)
  std::uint64_t route_update = 0;  // CannedRoute: restart, then update 0 (argmax node, registrations, belief)
  std::uint64_t xtf_decode = 0;    // CannedSonar: the 8 XTF packets decoded (ping number, samples)
  std::uint64_t all = 0;           // hash of the three
  // Diagnostics (printed, not compared): the VO front-end stages on the same canned frames, to
  // locate a divergence between the image and the host.
  static constexpr int kStages = 7;
  const char* stage_name[kStages] = {"harris0", "harris1", "remap0", "stereo0", "match_fc", "motion_6d", "motion_3d"};
  std::uint64_t stage[kStages] = {};
};

// Runs the three stages; a stage that fails on its canned input leaves its hash 0 and returns an error.
Status run_freestanding_workload(FreestandingResult& out);

}  // namespace qnav::timing
