// NavSource: qnavd as the autopilot's external navigation source over MAVLink (mavlink.enabled;
// docs/interfaces.md "MAVLink"). Wraps MavlinkEndpoint (parsing, decisions, encoding) and owns the
// one position estimate it publishes (pipeline::NavEstimate).
// Consumes: the bytes in [mav_rx] (drain(): the autopilot's ATTITUDE and mode commands come back to
//   the worker, which gives the attitude to NavInputs and the command to its mode logic, then ack());
//   route fixes from RouteRepeat's confident registrations (route_fix()); in Mode = Map each observed
//   frame's place (map_step()); every loop the navigation state (publish(): dead reckoning from
//   NavInputs, the VO body pose in Mode = Vo, the repeat's step).
// Produces: HEARTBEAT, ODOMETRY, VISION_POSITION_DELTA, DISTANCE_SENSOR, NAMED_VALUE_FLOAT,
//   STATUSTEXT, COMMAND_ACK and (mavlink.guided) SET_POSITION_TARGET_LOCAL_NED into [mav_tx].
// A route fix: the taught node's position (route frame) plus the registered along- and cross-track
// offsets is where the tile's centre was; the vehicle has dead-reckoned on from there since. Applied
// as a jump with reset_counter (nav_estimate.hpp says why).
// A map fix (Mode = Map): the published position is kept for every map node when it is created; when
// the topological map recognises a revisit (a node last seen long ago: a loop closed), the vehicle is
// back at that place, and the position jumps to the one kept for the node (the drift accumulated
// around the loop removed; the error left is the node's gate, map.node_spacing_m). Frames matching the
// node they just left, or a new map, move nothing. The map frame's own geometry is not needed: both
// positions are in the published frame.
// Memory: the endpoint's parsers (~3 KB, one heap allocation at init); the per-node positions (the
// table's "map_fixes": map.max_nodes x 16 B, when the map runs); no heap after. Time: O(bytes
// queued) per drain, a few frames per publish.
#pragma once

#include <cstdint>
#include <memory>

#include "firmware/pipeline/nav_estimate.hpp"
#include "firmware/pipeline/route_tile_pipeline.hpp"
#include "nav/topo/topo_map.hpp"
#include "firmware/qnavd/components/component.hpp"
#include "firmware/qnavd/components/nav_inputs.hpp"
#include "firmware/qnavd/components/vo_component.hpp"
#include "firmware/qnavd/mavlink_endpoint.hpp"

namespace qnav::daemon {

// A map node's kept position (north, east metres in the published frame; NaN: none). Plain doubles:
// the static block hands out max_align_t-aligned buffers, and an Eigen vector wants 16 bytes on armhf.
struct KeptPosition {
  double north_m, east_m;
};

class NavSource {
 public:
  explicit NavSource(const NavContext& ctx) noexcept : ctx_(ctx) {}
  // Nothing to do unless mavlink.enabled; then both queues are required.
  Status init(SpscRing<MavBytes>* rx, SpscRing<MavBytes>* tx, StaticMemory* mem);
  bool enabled() const noexcept { return mav_ != nullptr; }
  bool pending() const noexcept { return mav_ != nullptr && rx_->front() != nullptr; }
  // Parses up to and including the next accepted mode command (MavlinkEndpoint::drain).
  MavInputs drain() noexcept { return mav_->drain(*rx_); }
  // The answer to the mode command drain() returned.
  void ack(ModeReject why) noexcept { mav_->ack(why == ModeReject::kNone, to_string(why), *tx_); }
  // The autopilot set a new navigation origin.
  void reset() noexcept { est_.reset(); }
  // A repeat tile's guidance: the look-ahead waypoint kept; a confident registration is a route fix.
  void route_fix(const pipeline::RouteTile& t, const route::LocaliserStep& step, const route::NodeMeta* node, bool reverse,
                 const pipeline::DeadReckoner& dr) noexcept;
  // Mode = Map: a new map (no node positions kept), and each observed frame's place.
  void map_start() noexcept;
  void map_step(const topo::ObserveResult& place, const pipeline::DeadReckoner& dr) noexcept;
  // Leaving or changing a repeat: no fix and no target from the old route.
  void forget() noexcept { route_fix_ = false, guidance_valid_ = false; }
  void publish(drivers::qnavcan::Mode mode, std::uint16_t faults, const NavInputs& in, const VoComponent& vo,
               const route::LocaliserStep& step) noexcept;

  const MavlinkEndpoint* endpoint() const noexcept { return mav_.get(); }
  const pipeline::NavEstimate& estimate() const noexcept { return est_; }
  std::uint64_t rejected() const noexcept { return mav_ ? mav_->rejected() : 0; }
  void log_counters(const IoCounters& io) const noexcept;

 private:
  const NavContext& ctx_;  // the worker's: its log is set in NavWorker::init
  std::unique_ptr<MavlinkEndpoint> mav_;
  SpscRing<MavBytes>* rx_ = nullptr;
  SpscRing<MavBytes>* tx_ = nullptr;
  pipeline::NavEstimate est_;
  bool on_vo_ = false;         // the estimate follows the VO body pose (Mode = Vo), else the dead reckoning
  bool route_fix_ = false;     // a route fix placed the estimate in this repeat's route frame
  Vec2d waypoint_ne_ = Vec2d::Zero();
  bool guidance_valid_ = false;
  Span<KeptPosition> map_fixes_;                   // per map node: the published position at its creation
  std::unique_ptr<KeptPosition[]> own_map_fixes_;  // a worker built without a static block
};

}  // namespace qnav::daemon
