// Synthetic keypoint worlds for the route tests: a seabed of point landmarks with random int8
// descriptors; a node (or sensed tile) keeps the landmarks inside its footprint, in its tile frame,
// with position noise, drop-outs and clutter. Deterministic (seeded). Test-only helper.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "nav/match/ransac.hpp"
#include "nav/route/node_window.hpp"
#include "nav/route/route_types.hpp"

namespace qnav::route::testing {

struct Landmark {
  Vec2d ne;
  std::int8_t desc[kDescriptorBytes];
};

struct SyntheticWorld {
  std::vector<Landmark> landmarks;
  // Landmarks uniformly over [0, length] north x [-width/2, width/2] east.
  SyntheticWorld(double length_m, double width_m, double density_per_m2, std::uint64_t seed) {
    match::DeterministicRng rng(seed);
    const std::size_t n = static_cast<std::size_t>(length_m * width_m * density_per_m2);
    landmarks.resize(n);
    for (Landmark& l : landmarks) {
      // East first, in its own statement: argument evaluation order is unspecified (this is the order
      // x86-64 gcc used, so the host's worlds are unchanged; SPARC and ARM gcc used the other).
      const double east = (rng.uniform() - 0.5) * width_m;
      l.ne = Vec2d(rng.uniform() * length_m, east);
      for (auto& d : l.desc) d = static_cast<std::int8_t>(static_cast<int>(rng.below(200)) - 100);
    }
  }
  // Tile centred at pose (north, east, heading), footprint half_length along x, half_width across.
  RouteNode observe(const Pose2& pose, double half_length_m, double half_width_m, double noise_m, double keep,
                    std::size_t max_kp, std::uint64_t seed, int clutter = 0) const {
    match::DeterministicRng rng(seed);
    RouteNode node;
    node.meta.pose = pose;
    const Pose2 inv = pose.inverse();
    auto gauss = [&rng]() {
      const double u1 = rng.uniform() + 1e-12, u2 = rng.uniform();
      return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * 3.141592653589793 * u2);
    };
    for (const Landmark& l : landmarks) {
      const Vec2d t = inv.apply(l.ne);
      if (std::abs(t.x()) > half_length_m || std::abs(t.y()) > half_width_m) continue;
      if (rng.uniform() > keep) continue;
      RouteKeypoint* kp = node.keypoints.emplace_back();
      if (kp == nullptr || node.keypoints.size() > max_kp) {
        if (kp != nullptr) static_cast<void>(node.keypoints.pop_back());
        break;
      }
      kp->x_m = static_cast<float>(t.x() + noise_m * gauss());
      kp->y_m = static_cast<float>(t.y() + noise_m * gauss());
      kp->score = 1.0f;
      for (std::size_t i = 0; i < kDescriptorBytes; ++i) {
        const int v = l.desc[i] + static_cast<int>(std::lround(12.0 * gauss()));
        kp->descriptor[i] = static_cast<std::int8_t>(v > 127 ? 127 : (v < -127 ? -127 : v));
      }
    }
    for (int c = 0; c < clutter && node.keypoints.size() < max_kp; ++c) {
      RouteKeypoint* kp = node.keypoints.emplace_back();
      kp->x_m = static_cast<float>((rng.uniform() * 2 - 1) * half_length_m);
      kp->y_m = static_cast<float>((rng.uniform() * 2 - 1) * half_width_m);
      for (auto& d : kp->descriptor) d = static_cast<std::int8_t>(static_cast<int>(rng.below(200)) - 100);
    }
    node.meta.keypoint_count = static_cast<std::uint16_t>(node.keypoints.size());
    return node;
  }
};

// A long route along north, nodes generated on demand (no storage): node i is the world observed at
// north 30 + spacing * (i % 30) (the world repeats every 30 nodes), numbered and placed as node i. The
// 10,000-node route of bench_route and of the timing tests (test/timing/canned.cpp).
class RepeatingRouteSource final : public NodeSource {
 public:
  RepeatingRouteSource(const SyntheticWorld* w, std::uint32_t n, double spacing_m) : world_(w), n_(n), spacing_m_(spacing_m) {}
  std::uint32_t node_count() const noexcept override { return n_; }
  Status load(std::uint32_t i, RouteNode& out) noexcept override {
    out = world_->observe(Pose2{30.0 + spacing_m_ * (i % 30), 0.0, 0.0}, 45.0, 49.0, 0.3, 0.8, 128, 1000 + i, 20);
    out.meta.index = i;
    out.meta.pose.x_m = 30.0 + spacing_m_ * i;
    out.meta.along_m = spacing_m_ * i;
    return Status::ok();
  }

 private:
  const SyntheticWorld* world_;
  std::uint32_t n_;
  double spacing_m_;
};

}  // namespace qnav::route::testing
