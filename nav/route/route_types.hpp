// Value types of a taught route: the keypoints kept for each node (images are not stored), the
// node's pose in the route's own dead-reckoned frame, and the route-wide parameters.
// Frames: a node's tile frame has its origin at the tile centre on the vehicle track, x along the
// direction of travel when the tile was made, y to port (left), metres. Keypoint positions are in
// that frame. Node poses (x_m, y_m, heading_rad of the tile frame) are in the route frame, which is
// the training run's dead-reckoned frame (it drifts; only neighbouring nodes are compared).
// All types are fixed-size (no heap); bounds are compile-time constants below.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/fixed_vector.hpp"
#include "nav/core/geometry.hpp"

namespace qnav::route {

// Descriptor: an 8x8 patch sampled around the keypoint, zero-mean, scaled to unit standard
// deviation x 32 and stored as int8 (ZNCC between two descriptors is their normalised dot product).
constexpr int kDescriptorSide = 8;
constexpr std::size_t kDescriptorBytes = kDescriptorSide * kDescriptorSide;
// Most keypoints kept per node (a route file may use fewer, see RouteParams::max_keypoints).
constexpr std::size_t kMaxKeypointsPerNode = 128;

enum class SensorKind : std::uint8_t { kUnknown = 0, kSideScan = 1, kCamera = 2 };
inline const char* to_string(SensorKind k) noexcept {
  switch (k) {
    case SensorKind::kSideScan: return "sidescan";
    case SensorKind::kCamera: return "camera";
    case SensorKind::kUnknown: break;
  }
  return "unknown";
}

struct RouteKeypoint {
  float x_m = 0.0f;  // tile frame, along-track
  float y_m = 0.0f;  // tile frame, to starboard
  float score = 0.0f;  // detector response (larger is stronger)
  std::int8_t descriptor[kDescriptorBytes] = {};
};

struct NodeMeta {
  std::uint32_t index = 0;
  Pose2 pose;                  // tile frame in the route frame
  double along_m = 0.0;        // dead-reckoned distance travelled from the route start to this node
  std::uint64_t stamp_ns = 0;  // sample time of the tile centre (0 when unknown)
  std::uint16_t keypoint_count = 0;
};

struct RouteNode {
  NodeMeta meta;
  FixedVector<RouteKeypoint, kMaxKeypointsPerNode> keypoints;
};

// Route-wide parameters written in the file header.
struct RouteParams {
  SensorKind sensor = SensorKind::kUnknown;
  float depth_m = 0.0f;           // constant operating depth the route was taught at
  float node_spacing_m = 0.0f;    // nominal distance between consecutive nodes
  float tile_length_m = 0.0f;     // along-track extent of one tile
  float tile_width_m = 0.0f;      // across-track extent of one tile (full swath, both sides)
  float pixel_m = 0.0f;           // tile raster resolution the keypoints were found at
  std::uint16_t max_keypoints = 64;  // keypoint slots per record (<= kMaxKeypointsPerNode)
  std::uint16_t descriptor_bytes = static_cast<std::uint16_t>(kDescriptorBytes);
  std::uint16_t harris_window_px = 0;  // detector parameters, for the record
  std::uint16_t keypoint_min_distance_px = 0;
};

}  // namespace qnav::route
