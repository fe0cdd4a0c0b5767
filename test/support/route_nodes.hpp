// Route nodes and headers for the route store tests (firmware/tools on the host's files,
// drivers/route_store on the memory store): a small header and node i with kps keypoints.
#pragma once

#include <cstdint>

#include "nav/route/route_types.hpp"

namespace qnav::test {

inline route::RouteParams route_params(std::uint16_t max_kp = 8) {
  route::RouteParams p;
  p.sensor = route::SensorKind::kSideScan;
  p.depth_m = 20.0f;
  p.node_spacing_m = 30.0f;
  p.tile_length_m = 30.0f;
  p.tile_width_m = 100.0f;
  p.pixel_m = 0.2f;
  p.max_keypoints = max_kp;
  return p;
}

inline route::RouteNode route_node(std::uint32_t i, int kps) {
  route::RouteNode n;
  n.meta.pose = Pose2{30.0 * i, 1.0, 0.1};
  n.meta.along_m = 30.0 * i;
  for (int k = 0; k < kps; ++k) {
    route::RouteKeypoint* kp = n.keypoints.emplace_back();
    kp->x_m = static_cast<float>(k);
    kp->y_m = static_cast<float>(i);
    kp->descriptor[0] = static_cast<std::int8_t>(k);
  }
  return n;
}

}  // namespace qnav::test
