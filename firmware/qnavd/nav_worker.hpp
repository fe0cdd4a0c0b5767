// NavWorker: the nav thread of qnavd, a topology of components (components/component.hpp draws it).
// One run_once() drains the queues from the I/O thread (a ping first, then every CAN frame and DVL
// sample sent before it, so a mode command or a heading that preceded a ping is applied before the
// ping), then runs the components:
//   NavInputs     attitude (QNAV_ATTITUDE_IN, a DroneCAN AHRS Solution, the autopilot's MAVLink
//                 ATTITUDE), DVL dead reckoning, depth; the mode commands it decodes come back here.
//   modes (here)  QNAV_MODE_CMD or the MAVLink mode command: idle, teach, repeat (forward or reverse),
//                 hold, vo, map (refused with UnsupportedMode unless map_runs(): map.enabled, and on the
//                 linux backend a downward camera map.device). A refused transition keeps the current
//                 mode and reports why (NAV_STATUS ModeReject, log).
//   ping -> SonarTiles (pipeline::RouteTilePipeline) -> RouteTeach (durable node append)
//                                                    -> RouteRepeat (filter step -> guidance)
//   stereo pair (Mode = Vo) -> VoComponent (VO_STEP increments)
//   downward frame (Mode = Map) -> MapComponent (map pose, map file)
//   NavSource     (mavlink.enabled) the MAVLink endpoint and the estimate it publishes
//   NavHealth     faults, NAV_STATUS, HEALTH, HEARTBEAT, stage times, the health log
// Each component's header says what it consumes and produces, its memory and its time bound.
// Leaving or changing a repeat clears what was said about the old route (guidance, status, localised).
// Sensor loss degrades, never stops: sonar or attitude lost -> guidance "hold course" (tiles are not
// built without a heading); DVL lost -> the route filter runs the paper's eq. 5 motion model
// (FaultDvlLost) until velocities return; in Mode = Vo no pair for vo.stale_s -> FaultCameraLost.
// Sonar loss is not a fault in Mode = Vo, camera loss only there.
// Memory: everything is sized in init() from the configuration; run_once() does not allocate.
// Time: run_once() handles at most one ping or one stereo pair (the earlier by sample time) and at
// most the queue depths of CAN frames and samples.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <memory>

#include "drivers/qnavcan/publisher.hpp"
#include "firmware/qnavd/components/component.hpp"
#include "firmware/qnavd/components/map_component.hpp"
#include "firmware/qnavd/components/nav_health.hpp"
#include "firmware/qnavd/components/nav_inputs.hpp"
#include "firmware/qnavd/components/nav_source.hpp"
#include "firmware/qnavd/components/route_repeat.hpp"
#include "firmware/qnavd/components/route_teach.hpp"
#include "firmware/qnavd/components/sonar_tiles.hpp"
#include "firmware/qnavd/components/vo_component.hpp"
#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/messages.hpp"
#include "firmware/qnavd/static_memory.hpp"
#include "hal/core/clock.hpp"
#include "hal/core/file_store.hpp"
#include "nav/core/spsc_ring.hpp"

namespace qnav::daemon {

using TileObserver = void (*)(void* ctx, const TileReport& r);

using FrameObserver = void (*)(void* ctx, const FrameReport& r);

struct NavQueues {
  SpscRing<PingMsg>* pings = nullptr;
  SpscRing<std::uint32_t>* free_slots = nullptr;
  SpscRing<hal::CanRxFrame>* can_rx = nullptr;
  SpscRing<hal::CanFrame>* can_tx = nullptr;
  SpscRing<drivers::dvl::DvlVelocity>* dvl = nullptr;
  const float* ping_pool = nullptr;       // slot s: port at s * stride, starboard at s * stride + stride / 2
  std::size_t ping_pool_stride = 0;
  SpscRing<FrameMsg>* frames = nullptr;   // null when vo.enabled = false
  SpscRing<std::uint32_t>* free_frames = nullptr;
  const std::uint8_t* frame_pool = nullptr;  // slot s: at s * frame_slot_bytes: left, right W * H after it; or a downward frame
  std::size_t frame_slot_bytes = 0;       // 0 = 2 * vo.width * vo.height (stereo pairs only)
  IoCounters* io = nullptr;
  SpscRing<MavBytes>* mav_rx = nullptr;   // null when mavlink.enabled = false
  SpscRing<MavBytes>* mav_tx = nullptr;

  // Frame slot s of the pool (pair_bytes: a stereo pair's size, used when frame_slot_bytes is 0).
  const std::uint8_t* frame_slot(std::uint32_t slot, std::size_t pair_bytes) const noexcept {
    return frame_pool + static_cast<std::size_t>(slot) * (frame_slot_bytes != 0 ? frame_slot_bytes : pair_bytes);
  }
  // Takes the earlier queued sample by sample time: a ping or a stereo pair / downward frame.
  void pop_earlier(PingMsg& ping, bool& have_ping, FrameMsg& frame, bool& have_frame) const noexcept {
    const PingMsg* np = pings->front();
    const FrameMsg* nf = frames != nullptr ? frames->front() : nullptr;
    const bool take_frame = nf != nullptr && (np == nullptr || nf->stamp.sample_ns < np->stamp.sample_ns);
    have_ping = !take_frame && pings->try_pop(ping).is_ok();
    have_frame = take_frame && frames->try_pop(frame).is_ok();
  }
  // Bounds (until_ns, until_arrival_ns) by the first ping and frame queued now, if any.
  void bound_by_queued_samples(std::int64_t& until_ns, std::int64_t& until_arrival_ns) const noexcept {
    const PingMsg* np = pings->front();
    const FrameMsg* nf = frames != nullptr ? frames->front() : nullptr;
    if (np != nullptr) until_ns = std::min(until_ns, np->stamp.sample_ns), until_arrival_ns = std::min(until_arrival_ns, np->stamp.arrival_ns);
    if (nf != nullptr) until_ns = std::min(until_ns, nf->stamp.sample_ns), until_arrival_ns = std::min(until_arrival_ns, nf->stamp.arrival_ns);
  }
};

// The can_tx queue as a CanBus for the publisher (send = push; a full queue is "busy").
class QueueCanBus final : public hal::CanBus {
 public:
  explicit QueueCanBus(SpscRing<hal::CanFrame>* q) noexcept : q_(q) {}
  Status send(const hal::CanFrame& f) noexcept override { return q_->try_push(f); }
  Status receive(hal::CanRxFrame&, int) noexcept override { return Status(StatusCode::kUnsupported, "tx only"); }
  hal::CanBusStats stats() const noexcept override { return {}; }

 private:
  SpscRing<hal::CanFrame>* q_;
};

class NavWorker {
 public:
  // store: where route files live (the host's file system in qnavd; a memory store in tests).
  NavWorker(const DaemonConfig& config, const hal::Clock& sample_clock, const hal::Clock& cpu_clock, hal::FileStore& store) noexcept;
  ~NavWorker();
  // mem: the daemon's static block; the stage arenas (tile_pipeline, localiser, vo, map) are carved
  // from it by their deployment-table names. nullptr: each arena is allocated here (a worker built alone).
  Status init(const NavQueues& q, TileObserver observer, void* observer_ctx, FILE* log, StaticMemory* mem = nullptr);
  void set_frame_observer(FrameObserver f, void* ctx) noexcept { frame_observer_ = f, frame_ctx_ = ctx; }
  // The node spacing and swath written into the header of a route taught here (before start).
  void set_route_geometry(double spacing_m, double swath_m) noexcept { spacing_m_ = spacing_m, swath_m_ = swath_m; }
  // One pass over the queues and stages; false when there was nothing to do.
  bool run_once() noexcept;
  // Stop: finish or discard the node in progress, close the route durably. Idempotent.
  void shutdown() noexcept;

  std::uint64_t progress() const noexcept { return progress_.load(std::memory_order_relaxed); }
  drivers::qnavcan::Mode mode() const noexcept { return state_.mode; }
  std::uint32_t deadline_misses() const noexcept { return health_.deadline_misses(); }
  std::uint16_t fault_flags() const noexcept { return health_.faults(); }
  ModeReject last_reject() const noexcept { return state_.last_reject; }
  std::uint32_t tiles() const noexcept { return counters_.tiles; }
  std::uint32_t pings() const noexcept { return counters_.pings; }
  // Pings the tile pipeline's corrector refused as damaged (range, samples, altitude), and pings
  // stamped at or before the previous one (dropped).
  std::uint32_t pings_rejected() const noexcept { return health_.pings_rejected(); }
  std::uint32_t pings_out_of_order() const noexcept { return counters_.pings_out_of_order; }
  // Stereo pairs taken off the queue; out of order.
  std::uint32_t frames() const noexcept { return counters_.frames; }
  std::uint32_t frames_out_of_order() const noexcept { return counters_.frames_out_of_order; }
  std::uint32_t writer_errors() const noexcept { return teach_.errors() + map_.save_errors(); }
  // The last teach could not be committed (the route stays under .new; the exit code says so).
  bool commit_failed() const noexcept { return teach_.commit_failed(); }
  // The components, read-only, for their counters (each header lists them): the inputs (CAN frames and
  // DVL samples taken off the queues, CAN frames the receiver refused, bus-off), the repeat (experiences
  // learnt and failed, its "route_meta" bytes), VO (frames, visual steps, without attitude), the map
  // (frames, refused frames, map file saves and failures, the mapper).
  const NavInputs& inputs() const noexcept { return inputs_; }
  const RouteRepeat& repeat() const noexcept { return repeat_; }
  const VoComponent& vo() const noexcept { return vo_; }
  const MapComponent& map() const noexcept { return map_; }
  // MAVLink (mavlink.enabled): the endpoint (nullptr when off) and the estimate it publishes.
  const MavlinkEndpoint* mavlink() const noexcept { return source_.endpoint(); }
  const pipeline::NavEstimate& estimate() const noexcept { return source_.estimate(); }

 private:
  void drain_inputs(std::int64_t until_ns, std::int64_t until_arrival_ns, bool have_sample, bool& did) noexcept;
  void mavlink_inputs() noexcept;
  void handle_mode(const drivers::qnavcan::ModeCmd& cmd) noexcept;
  ModeReject enter_mode(const drivers::qnavcan::ModeCmd& cmd, std::uint16_t id) noexcept;
  void leave_mode() noexcept;
  void handle_ping(const PingMsg& p) noexcept;
  void handle_pair(const FrameMsg& f) noexcept;
  bool on_tile(const pipeline::RouteTile& t) noexcept;
  void outputs() noexcept;
  void stage_time(Stage s, std::int64_t t0_ns) noexcept { health_.stage_time(s, t0_ns, cpu_clock_.now_ns()); }

  const DaemonConfig& cfg_;
  const hal::Clock& sample_clock_;
  const hal::Clock& cpu_clock_;
  NavQueues q_{};
  TileObserver observer_ = nullptr;
  void* observer_ctx_ = nullptr;
  FrameObserver frame_observer_ = nullptr;
  void* frame_ctx_ = nullptr;
  double spacing_m_ = 60.0, swath_m_ = 100.0;

  // The topology: what every component reads, then the components in data-flow order.
  NavClock clock_;
  NavContext ctx_;
  NavCounters counters_;
  NavModeState state_;
  std::unique_ptr<QueueCanBus> tx_bus_;
  std::unique_ptr<drivers::qnavcan::QnavCanPublisher> publisher_;
  NavInputs inputs_;
  SonarTiles tiles_;
  pipeline::RouteTileSink tile_sink_;
  RouteTeach teach_;
  RouteRepeat repeat_;
  VoComponent vo_;
  MapComponent map_;                 // (PlaceEncoder: 32 KB inside; the worker lives on the heap)
  NavSource source_;
  NavHealth health_;

  bool reverse_ = false;
  std::uint16_t route_id_ = 0;
  SampleOrder ping_order_;
  std::int64_t ping_rx_cpu_ns_ = 0;
  std::int64_t mode_ns_ = 0;  // time spent in handle_mode during this loop's input drain
  bool started_ns_set_ = false;
  std::int64_t next_health_ns_ = 0;
  TileReport report_{};
  std::atomic<std::uint64_t> progress_{0};
  bool initialised_ = false;  // init() succeeded: shutdown() has a mode to leave
  bool shut_ = false;
};

}  // namespace qnav::daemon
