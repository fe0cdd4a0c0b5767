// The synthetic route of the power-cut test: node i of a route taught with a seed, every field a
// function of (seed, i), so the test checks what it reads back bit for bit.
#pragma once

#include <cstdint>

#include "nav/route/route_types.hpp"

namespace qnav::test {

inline route::RouteParams power_cut_params() {
  route::RouteParams p;
  p.sensor = route::SensorKind::kSideScan;
  p.depth_m = 30.0f;
  p.node_spacing_m = 25.0f;
  p.tile_length_m = 25.0f;
  p.tile_width_m = 120.0f;
  p.pixel_m = 0.25f;
  p.max_keypoints = 48;  // 3,700-byte records: a record spans a page boundary now and then
  p.harris_window_px = 5;
  p.keypoint_min_distance_px = 6;
  return p;
}

inline std::uint32_t power_cut_mix(std::uint64_t x) {
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdull;
  x ^= x >> 33;
  x *= 0xc4ceb9fe1a85ec53ull;
  x ^= x >> 33;
  return static_cast<std::uint32_t>(x);
}

inline route::RouteNode power_cut_node(std::uint64_t seed, std::uint32_t i) {
  route::RouteNode n;
  const std::uint32_t h = power_cut_mix(seed * 1000003ull + i);
  n.meta.index = i;
  n.meta.pose = Pose2{25.0 * i + 0.001 * (h % 1000), -3.0 + 0.01 * (h % 97), 0.001 * static_cast<double>(h % 3141)};
  n.meta.along_m = 25.0 * i;
  n.meta.stamp_ns = 1000000000ull * i + h;
  const int kps = 1 + static_cast<int>(h % 48);
  for (int k = 0; k < kps; ++k) {
    route::RouteKeypoint* kp = n.keypoints.emplace_back();
    const std::uint32_t g = power_cut_mix(static_cast<std::uint64_t>(h) * 131ull + static_cast<std::uint64_t>(k));
    kp->x_m = static_cast<float>(g % 2500) * 0.01f - 12.5f;
    kp->y_m = static_cast<float>((g >> 12) % 12000) * 0.01f - 60.0f;
    kp->score = 1.0f + static_cast<float>(g % 100);
    for (std::size_t b = 0; b < route::kDescriptorBytes; ++b)
      kp->descriptor[b] = static_cast<std::int8_t>(static_cast<int>((g >> (b % 24)) & 0xFF) - 128);
  }
  n.meta.keypoint_count = static_cast<std::uint16_t>(kps);
  return n;
}

}  // namespace qnav::test
