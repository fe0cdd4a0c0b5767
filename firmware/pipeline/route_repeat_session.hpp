// RouteRepeatSession: the repeat component, one pass over a taught route, as qnavd's Mode = Repeat
// (firmware/qnavd/components/route_repeat.hpp) and `qnav route repeat` (--sim and --sonar) run it.
// It owns the localiser (RouteRepeater: the paper's eqs. 1-5) and the route's experiences
// (RouteExperiences: ROUTE.exp read, learnt into with learn), and does the per-tile sequence both
// executables used to write out themselves: the motion model (odometry, or the paper's eq. 5 while
// the DVL is lost), the filter step (the pass's first tile with no travel), the learner after it,
// and the stride that frames the next tile on the taught nodes.
// Ports in:  start(route params, node metadata, node source, direction) once per pass;
//            open_experiences(route path, learn) after start (optional);
//            step(tile, DVL lost) per finished tile; end() when the pass ends.
// Ports out: the filter step (route::LocaliserStep: estimate, guidance) per tile; next_stride_m() for
//            the tile pipeline; learnt() per tile and the experiences' counters.
// Logging and what to do with an error stay with the caller (qnavd logs JSON events, the tool
// prints to stderr): every call returns what happened.
// Memory: the localiser's arena (the caller's, or its own), the experiences' index and learner
// (max_nodes x per node), all in init(); start() and the rest allocate nothing. Time: one filter
// update per tile (the route_update budget; with experiences at most 16 more registrations), plus a
// ~10 KB durable append when a tile is learnt.
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivers/route_store/experience_file.hpp"
#include "firmware/pipeline/route_defaults.hpp"
#include "firmware/pipeline/route_experiences.hpp"
#include "firmware/pipeline/route_repeater.hpp"
#include "firmware/pipeline/route_tile_pipeline.hpp"
#include "hal/core/file_store.hpp"
#include "nav/core/arena.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/route/route_localiser.hpp"

namespace qnav::pipeline {

struct RepeatSessionConfig {
  route::LocaliserConfig localiser{};
  std::size_t max_nodes = 0;              // the longest route a pass may run on (experience index)
  std::uint16_t experiences_per_node = 0;  // 0: the route's experiences are never read nor learnt
  route::ExperienceLearnConfig learn{};
  bool backfill = false;  // learning passes also learn the tiles before their first confirmed fix
  // Share of the start belief on the route's entry end (qnavd: route.entry_prior). 0: uniform, for
  // passes that may join the route anywhere. In [0, 1); init() refuses anything else.
  double entry_prior = kDefaultEntryPrior;
};

// What open_experiences() did. ok(): read (or opened for learning), or there is no companion.
struct ExperiencesOpened {
  Status status;                                  // the first error (open or attach)
  bool at_attach = false;                         // the file was read but the localiser refused it
  drivers::route_store::ExperienceOpenReport report{};
  bool ok() const noexcept { return status.is_ok(); }
};

// One tile's outcome: the filter step's status, the learner's (an append that failed), whether the
// tile was learnt, and whether the filter ran the paper's eq. 5 motion model for it.
struct RepeatTileResult {
  Status step;
  Status learn;
  bool learned = false;
  bool eq5 = false;
};

class RouteRepeatSession {
 public:
  // A pass starts at the route's entry end (node 0 forwards, the last node in reverse): start() puts
  // config.entry_prior (default this share) of the filter's start belief there
  // (RouteFilter::apply_entry_prior, sigma 1 node), the rest uniform. A uniform start lost a weak pass's first 3-20 tiles (docs/route.md, "Routes that
  // learn"); the prior alone does not make the filter confident, and a pass joining the route
  // elsewhere is found by the wide search as before.
  static constexpr double kEntryPriorMass = kDefaultEntryPrior;
  static constexpr double kEntryPriorSigmaNodes = 1.0;
  explicit RouteRepeatSession(hal::FileStore& store) : experiences_(store) {}

  // arena: the localiser's buffers from the caller's (qnavd: its static block), nullptr: its own.
  Status init(const RepeatSessionConfig& config, Arena* arena = nullptr);
  // A pass over an opened route in the given direction (motion model: odometry).
  Status start(const route::RouteParams& params, Span<const route::NodeMeta> meta, route::NodeSource& nodes, bool reverse) noexcept;
  // The route's companion ROUTE.exp: read (learn: opened for appending, created when missing) and the
  // localiser attached to it. On any error the pass goes on without experiences (detached).
  ExperiencesOpened open_experiences(const char* route_path, bool learn) noexcept;
  // One finished tile. dvl_lost: judged by the caller at the tile's last ping. On a failed step the
  // guidance says HoldCourse with the side unknown.
  RepeatTileResult step(const RouteTile& tile, bool dvl_lost, route::LocaliserStep& out) noexcept;
  // The stride to the next tile's centre that frames it on the taught nodes (a reverse pass brought
  // into step with them), from this step and the configured stride.
  double next_stride_m(const route::LocaliserStep& step, double configured_stride_m) const noexcept;
  // The pass ends: an unconfirmed candidate dropped, the learnt experiences synced, the localiser
  // detached. Returns how many this pass learnt.
  std::uint32_t end() noexcept;

  bool with_experiences() const noexcept { return with_experiences_; }
  bool reverse() const noexcept { return reverse_; }
  std::uint32_t tiles() const noexcept { return tiles_; }
  const RouteRepeater& repeater() const noexcept { return repeater_; }
  const RouteExperiences& experiences() const noexcept { return experiences_; }
  const RepeatSessionConfig& config() const noexcept { return config_; }

 private:
  RepeatSessionConfig config_{};
  RouteRepeater repeater_;
  RouteExperiences experiences_;
  Span<const route::NodeMeta> meta_{};
  route::NodeSource* nodes_ = nullptr;
  route::RouteParams params_{};
  bool reverse_ = false;
  bool eq5_ = false;
  bool with_experiences_ = false;
  std::uint32_t tiles_ = 0;
  route::RouteDirection direction() const noexcept { return reverse_ ? route::RouteDirection::kReverse : route::RouteDirection::kForward; }
};

}  // namespace qnav::pipeline
