// RouteRepeater: a RouteLocaliser with the arena it runs in. init() sizes and allocates the arena
// from the configuration (RouteLocaliser::arena_bytes) and is the only call that allocates; start()
// binds a route (header params, every node's metadata, the node source) and step() is one
// repeat-mode update per sensed tile (bounded by the localiser's registrations per update). The one
// place the daemon's repeat mode and every `qnav route` command set a localiser up.
#pragma once

#include <cstddef>
#include <memory>

#include "nav/core/arena.hpp"
#include "nav/core/status.hpp"
#include "nav/route/route_localiser.hpp"

namespace qnav::pipeline {

class RouteRepeater {
 public:
  // Allocates its own arena of RouteLocaliser::arena_bytes(config).
  Status init(const route::LocaliserConfig& config) {
    arena_ = std::make_unique<ArenaStorage>(route::RouteLocaliser::arena_bytes(config));
    if (!arena_->valid()) return Status(StatusCode::kCapacityExceeded, "route repeater: cannot allocate the localiser arena");
    return init(config, *arena_);
  }
  // Takes the localiser's buffers from the caller's arena (qnavd: its static block), which outlives this.
  Status init(const route::LocaliserConfig& config, Arena& arena) {
    config_ = config;
    bytes_ = route::RouteLocaliser::arena_bytes(config);
    localiser_ = std::make_unique<route::RouteLocaliser>();
    return localiser_->init(config, arena);
  }
  Status start(const route::RouteParams& params, Span<const route::NodeMeta> meta, route::NodeSource& source) noexcept {
    if (!localiser_) return Status(StatusCode::kNotReady, "route repeater: start() before init()");
    return localiser_->start(params, meta, source);
  }
  Status step(const route::RouteNode& sensed, double distance_m, route::LocaliserStep& out) noexcept {
    if (!localiser_) return Status(StatusCode::kNotReady, "route repeater: step() before init()");
    return localiser_->step(sensed, distance_m, out);
  }
  // See RouteLocaliser::attach_experiences (firmware/pipeline/route_experiences.hpp opens them).
  Status attach_experiences(const route::ExperienceIndex* index, route::NodeSource* records) noexcept {
    if (!localiser_) return Status(StatusCode::kNotReady, "route repeater: attach_experiences() before init()");
    return localiser_->attach_experiences(index, records);
  }
  // See RouteLocaliser::apply_entry_prior.
  Status apply_entry_prior(double mass, double sigma_nodes) noexcept {
    if (!localiser_) return Status(StatusCode::kNotReady, "route repeater: apply_entry_prior() before init()");
    return localiser_->apply_entry_prior(mass, sigma_nodes);
  }
  void set_motion(route::RouteDirection direction, route::MotionModel motion) noexcept {
    if (localiser_) localiser_->set_motion(direction, motion);
    config_.filter.direction = direction;
    config_.filter.motion = motion;
  }
  const route::RouteLocaliser& localiser() const noexcept { return *localiser_; }
  const route::LocaliserConfig& config() const noexcept { return config_; }
  std::size_t arena_bytes() const noexcept { return bytes_; }

 private:
  route::LocaliserConfig config_{};
  std::size_t bytes_ = 0;
  std::unique_ptr<ArenaStorage> arena_;
  std::unique_ptr<route::RouteLocaliser> localiser_;
};

}  // namespace qnav::pipeline
