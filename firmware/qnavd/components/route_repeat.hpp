// RouteRepeat: Mode = Repeat. The taught route opened by the one route-open policy
// (drivers/route_store/route_open.hpp, as `qnav route repeat` applies it: a damaged node with a good
// prefix before it repeats the prefix and keeps FaultRouteDamaged raised), then the repeat component
// (pipeline::RouteRepeatSession, the same one `qnav route repeat` runs: one Bayes filter step, the
// paper's eqs. 1-5, per finished tile, experiences, the framing stride). This is qnavd's side of it:
// the route files by id, the CAN outputs and the JSON events.
// Consumes: enter(route id, reverse) when the mode is entered; step(tile, tile seq, DVL lost) per
//   finished tile; hold(sonar or attitude lost) every loop; leave() when the mode is left.
// Produces: QNAV_ROUTE_GUIDANCE and QNAV_ROUTE_STATUS on the publisher (values in the DBC ranges,
//   pipeline::route_can_messages); the filter step (LocaliserStep) to the worker's tile report; the
//   route's node metadata (for route fixes); route_damaged() for FaultRouteDamaged.
// DVL lost at a tile's last ping: the filter runs the paper's eq. 5 motion model until it returns.
// Leaving or changing a repeat clears what was said about the old route (forget()).
// Experiences (issue 29; pipeline::RouteExperiences, as `qnav route repeat` uses it): the route's
// companion ROUTE.exp, when there is one, is read at enter() and every tile is registered against the
// taught node and its experiences; with route.learn the pass appends its confirmed tiles to it
// (durably, one record per learnt tile, on this thread). A companion that cannot be used (damaged,
// of another teach) is logged and the repeat goes on without it.
// Memory: the localiser's arena (the table's "localiser" buffer), the node metadata (reserved for
// route.max_nodes: the table's "route_meta") and the experience index and learner (the table's
// "route_experiences", allocated in init()). Time: one filter update per tile (route_update budget;
// with experiences at most 16 more registrations), plus a ~10 KB durable append when a tile is learnt.
#pragma once

#include <cstdint>
#include <vector>

#include "drivers/qnavcan/publisher.hpp"
#include "drivers/route_store/route_file.hpp"
#include "firmware/pipeline/route_repeat_session.hpp"
#include "firmware/pipeline/route_tile_pipeline.hpp"
#include "firmware/qnavd/components/component.hpp"
#include "hal/core/file_store.hpp"

namespace qnav::daemon {

class RouteRepeat {
 public:
  RouteRepeat(const NavContext& ctx, hal::FileStore& store) noexcept : ctx_(ctx), reader_(store), store_(store), session_(store) {}
  Status init(StaticMemory* mem, drivers::qnavcan::QnavCanPublisher& publisher);

  // Refused before the current mode is left when the route is not there at all.
  ModeReject probe(std::uint16_t route_id) noexcept;
  ModeReject enter(std::uint16_t route_id, bool reverse) noexcept;
  void leave() noexcept;
  // One finished tile: a filter step, the guidance set on the publisher. dvl_lost: judged at the
  // tile's last ping (sample time), so the same data gives the same answer. Returns the eq. 5 state.
  bool step(const pipeline::RouteTile& t, std::uint32_t tile_seq, bool dvl_lost, route::LocaliserStep& out) noexcept;
  // Every loop: degraded repeat (no sonar or no heading: no fix) tells the autopilot to hold course;
  // outside Repeat the status is cleared.
  void hold(bool in_repeat, bool no_fix_possible, std::uint32_t tile_seq) noexcept;
  // Nothing said about the previous route may reach the autopilot as if it held for the next one.
  void forget(std::uint32_t tile_seq) noexcept;

  bool route_damaged() const noexcept { return route_damaged_; }
  bool reverse() const noexcept { return session_.reverse(); }
  const std::vector<route::NodeMeta>& meta() const noexcept { return meta_; }
  // The stride that frames the next tile on the taught nodes (the tool's framing too).
  double next_stride_m(const route::LocaliserStep& step) const noexcept { return session_.next_stride_m(step, ctx_.cfg->tiles.tiles.tile_stride_m); }
  std::size_t meta_bytes() const noexcept { return meta_.capacity() * sizeof(route::NodeMeta); }
  std::uint32_t step_errors() const noexcept { return step_errors_; }
  // Experiences learnt since start; appends or companions that failed (logged).
  std::uint32_t learned() const noexcept { return learned_; }
  std::uint32_t experience_errors() const noexcept { return experience_errors_; }
  // Registrations guidance refused: they disagreed with dead reckoning from the last fix (GuidanceConfig::verify_gate_m).
  std::uint32_t registrations_rejected() const noexcept { return registrations_rejected_; }

 private:
  const NavContext& ctx_;  // the worker's: its log is set in NavWorker::init
  drivers::route_store::RouteFileReader reader_;
  hal::FileStore& store_;
  std::vector<route::NodeMeta> meta_;
  pipeline::RouteRepeatSession session_;
  StageArena arena_;
  drivers::qnavcan::QnavCanPublisher* publisher_ = nullptr;
  drivers::qnavcan::RouteStatus route_status_{};
  drivers::qnavcan::RouteGuidance guidance_{};
  bool route_damaged_ = false;
  std::uint32_t step_errors_ = 0, learned_ = 0, experience_errors_ = 0, registrations_rejected_ = 0;
  void open_experiences(const char* path) noexcept;
};

}  // namespace qnav::daemon
