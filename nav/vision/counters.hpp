// Named counters of the vision front end (nav/core/counters.hpp). Every stage object (HarrisDetector,
// StereoMatcher, RemapTable, ...) owns one CounterSet<VisionCounter> and increments the counter that
// names each input it rejects; health telemetry publishes them. O(1), no heap.
#pragma once

#include <cstdint>

#include "nav/core/counters.hpp"

namespace qnav::vision {

enum class VisionCounter : std::uint8_t {
  kBadImage,            // null / zero-size / wrong-size / larger-than-configured image
  kBadConfig,           // init() refused a configuration (or a call before init())
  kBadRoi,              // region of interest outside the image
  kCornerCapReached,    // more NMS survivors than the corner cap (weakest dropped, by design)
  kStereoOutOfBounds,   // corner too close to the border for the patch / disparity range
  kStereoFlatPatch,     // left or right patch without texture (ZNCC undefined)
  kStereoWeak,          // best ZNCC below min_zncc
  kStereoAmbiguous,     // second peak too close to the best (uniqueness test)
  kStereoLeftRight,     // left-right consistency check failed
  kStereoEdgeOfRange,   // best disparity on the edge of the search range (true peak may be outside)
  kStereoCapReached,    // output point container full
  kDescriptorOutOfBounds,  // descriptor support leaves the image
  kDescriptorFlat,      // descriptor patch without texture
  kCount
};

inline constexpr const char* kVisionCounterNames[] = {
    "bad_image",          "bad_config",           "bad_roi",           "corner_cap_reached",
    "stereo_out_of_bounds", "stereo_flat_patch",  "stereo_weak",       "stereo_ambiguous",
    "stereo_left_right",  "stereo_edge_of_range", "stereo_cap_reached", "descriptor_out_of_bounds",
    "descriptor_flat"};
static_assert(sizeof(kVisionCounterNames) / sizeof(kVisionCounterNames[0]) ==
                  static_cast<unsigned>(VisionCounter::kCount),
              "one name per counter");

using VisionCounters = CounterSet<VisionCounter>;

}  // namespace qnav::vision
