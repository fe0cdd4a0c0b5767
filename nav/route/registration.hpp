// Registrar: registration of a sensed tile's keypoints against a route node's keypoints (the route
// paper's SIFT + RANSAC step, here Harris keypoints + 2D fc-matching + RANSAC or LMedS).
//   dtheta = sensed heading - node heading (both compass, so known): fc-matching uses it for the
//   "directions preserved" term; RANSAC/LMedS then fits the rigid 2D transform on the putative
//   matches. The result maps the sensed tile frame into the node's tile frame; its inlier count is
//   the paper's similarity S(I_s, I_r) used by the measurement model (eq. 6-9).
// Fails soft: too few matches or inliers give inliers = 0 and ok = false (a measurement of "no
// similarity"), not an error; bad input (NaN, oversize sets) is an error and counted.
// Memory: matcher + match list + RANSAC buffers from the Arena in init(). Cost per call:
// fc-matching (see fc_match_2d.hpp) + max_iterations * O(matches).
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/arena.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/status.hpp"
#include "nav/match/fc_match_2d.hpp"
#include "nav/match/ransac.hpp"
#include "nav/route/route_types.hpp"

namespace qnav::route {

struct RegistrationConfig {
  match::FcMatch2dConfig fc;
  match::RobustConfig robust;
  std::uint32_t min_matches = 4;
  double max_heading_disagreement_rad = 0.25;  // fit rotation vs compass dtheta; beyond -> rejected
};

struct RegistrationResult {
  bool ok = false;
  std::uint32_t inliers = 0;       // similarity S (0 when registration failed)
  std::uint32_t matches = 0;       // putative fc matches
  Pose2 sensed_to_node;            // node_frame_point = sensed_to_node.apply(sensed_frame_point)
  Mat3d covariance = Mat3d::Zero();
  double rms_m = 0.0;
};

enum class RegistrationCounter : std::uint8_t { kBadInput, kTooFewMatches, kNoConsensus, kHeadingDisagrees, kCount };
inline constexpr const char* kRegistrationCounterNames[] = {"bad_input", "too_few_matches", "no_consensus", "heading_disagrees"};

class Registrar {
 public:
  Registrar() noexcept : counters_(kRegistrationCounterNames) {}
  static std::size_t arena_bytes(const RegistrationConfig& c) noexcept;
  Status init(const RegistrationConfig& config, Arena& arena) noexcept;
  Status register_tile(const RouteNode& sensed, const RouteNode& node, RegistrationResult& out) noexcept;
  // Inlier pairs of the last successful registration (sensed frame, node frame), for diagnostics.
  std::size_t last_inlier_count() const noexcept { return last_n_; }
  bool last_inlier(std::size_t i, Vec2d& sensed, Vec2d& node) const noexcept {
    std::size_t seen = 0;
    for (std::size_t k = 0; k < last_n_; ++k) {
      if (!mask_[k]) continue;
      if (seen++ == i) {
        sensed = src_[k];
        node = dst_[k];
        return true;
      }
    }
    return false;
  }
  const CounterSet<RegistrationCounter>& counters() const noexcept { return counters_; }
  const RegistrationConfig& config() const noexcept { return config_; }

 private:
  RegistrationConfig config_{};
  bool ready_ = false;
  match::FcMatcher2d matcher_;
  Span<Vec2d> pos_a_, pos_b_, src_, dst_;
  Span<std::int8_t> desc_a_, desc_b_;
  Span<match::Match2d> matches_;
  Span<std::uint8_t> mask_;
  Span<double> scratch_;
  std::size_t last_n_ = 0;  // pairs given to RANSAC by the last call
  CounterSet<RegistrationCounter> counters_;
};

}  // namespace qnav::route
