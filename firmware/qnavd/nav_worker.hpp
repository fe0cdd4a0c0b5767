// NavWorker: the nav thread of qnavd. One run_once() drains the queues from the I/O thread (a ping
// first, then every CAN frame and DVL sample sent before it, so a mode command or a heading that
// preceded a ping is applied before the ping), then runs the stages:
//   attitude  QNAV_ATTITUDE_IN or a DroneCAN AHRS Solution (29-bit frames): the heading.
//   modes     QNAV_MODE_CMD (range- and counter-checked by QnavCanReceiver): idle, teach, repeat
//             (forward or reverse), hold, vo, map (refused with UnsupportedMode unless map_runs():
//             map.enabled, and on the linux backend a downward camera map.device).
//             A refused transition keeps the current mode and reports why (NAV_STATUS ModeReject, log).
//   dead reckoning  DVL body velocity x attitude heading (pipeline::DeadReckoner); the ping's pose.
//   ping -> tile (pipeline::RouteTilePipeline) -> teach: RouteFileWriter.append (durable per node)
//                                               -> repeat: RouteRepeater.step -> guidance
//   downward frame (Mode = Map) -> pipeline::TopoMapper (the `qnav map` wiring: homography chain,
//             topological map) -> the map file daemon.route_dir/map_<id>.qmap rewritten durably
//             (firmware/tools/map_file over the FileStore) after every new node and when the mode is
//             left; a new map each time the mode is entered; a refused frame (black, saturated,
//             textureless, unregistered) is counted and logged, the pose and the map left as they were;
//             per frame QNAV_MAP_POSE + QNAV_MAP_STATUS (pose, node, node count, the frame's flags)
//   stereo pair (Mode = Vo) -> pipeline::VoOdometry with the attitude at the pair's time -> the
//             body's motion since the last QNAV_VO_STEP sent (an increment, never repeated)
//   mavlink   (mavlink.enabled) MavlinkEndpoint: the autopilot's ATTITUDE as an attitude source, its
//             mode commands (handled as QNAV_MODE_CMD, answered with COMMAND_ACK), and every loop the
//             outputs from a MavSnapshot of this worker and the NavEstimate (dead reckoning, VO in
//             Mode = Vo, route fixes in Repeat); mavlink_endpoint.hpp says what and when.
//   outputs   NAV_STATUS, ROUTE_GUIDANCE, ROUTE_STATUS, VO_STEP, MAP_POSE, MAP_STATUS, HEALTH, HEARTBEAT through QnavCanPublisher
//             into the can_tx queue; one log line per tile and per event; health every period.
// Leaving or changing a repeat clears what was said about the old route (guidance, status, localised).
// Sensor loss degrades, never stops: sonar or attitude lost -> guidance "hold course" (tiles are not
// built without a heading); DVL lost -> the route filter runs the paper's eq. 5 motion model
// (FaultDvlLost) until velocities return; in Mode = Vo no pair for vo.stale_s -> FaultCameraLost (no
// VO_STEP is sent: the autopilot dead-reckons on its own), a pair without attitude is not processed
// (FaultAttitudeLost), a pair the VO cannot measure is dead-reckoned from the last velocity
// (VO_STEP Inliers = 0). Sonar loss is not a fault in Mode = Vo, camera loss only there.
// Memory: everything is sized in init() from the configuration; run_once() does not allocate.
// Time: run_once() handles at most one ping or one stereo pair (the earlier by sample time) and at
// most the queue depths of CAN frames and samples.
#pragma once

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <vector>

#include "drivers/dronecan/ahrs_receiver.hpp"
#include "drivers/dvl/dvl_types.hpp"
#include "drivers/qnavcan/publisher.hpp"
#include "drivers/qnavcan/receiver.hpp"
#include "firmware/pipeline/dead_reckoner.hpp"
#include "firmware/pipeline/nav_estimate.hpp"
#include "firmware/pipeline/route_repeater.hpp"
#include "firmware/pipeline/route_tile_pipeline.hpp"
#include "firmware/pipeline/topo_mapper.hpp"
#include "firmware/pipeline/vo_odometry.hpp"
#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/deployment.hpp"
#include "firmware/qnavd/mavlink_endpoint.hpp"
#include "firmware/qnavd/messages.hpp"
#include "firmware/qnavd/static_memory.hpp"
#include "drivers/route_store/route_file.hpp"
#include "hal/core/file_store.hpp"
#include "hal/core/clock.hpp"
#include "nav/core/spsc_ring.hpp"

namespace qnav::daemon {

// Why a mode command was refused (NAV_STATUS ModeReject).
enum class ModeReject : std::uint8_t {
  kNone = 0, kUnsupportedMode, kRouteMissing, kRouteDamaged, kRouteTooShort, kStorage, kNoHeading, kRouteTooLong, kRouteMismatch
};
const char* to_string(ModeReject r) noexcept;

// One sensed tile as the nav worker reported it (log line, tests).
struct TileReport {
  std::uint32_t seq = 0;
  drivers::qnavcan::Mode mode = drivers::qnavcan::Mode::kIdle;
  bool reverse = false;
  std::uint16_t route_id = 0;
  std::uint32_t node_written = 0;         // teach: index of the node appended
  route::LocaliserStep step;              // repeat
  double nav_step_m = 0.0;
  bool eq5_motion = false;                // DVL lost: the paper's motion model
  double truth_along_m = -1.0;            // sim backend only
  double truth_lateral_m = 0.0;
  std::int64_t stamp_ns = 0;
  double latency_ms = 0.0;                // last ping of the tile received -> outputs queued
};
using TileObserver = void (*)(void* ctx, const TileReport& r);

// One stereo pair as the nav worker reported it (log line, tests).
struct FrameReport {
  std::uint32_t seq = 0;
  std::uint32_t flags = 0;       // nav/vo VoFlag bits (0 when not processed)
  bool processed = false;        // false: no attitude at the pair's time
  bool visual = false;
  std::uint32_t inliers = 0;
  Pose3 world_T_body;            // the VO's body pose (NED, from the start of the Vo mode)
  bool has_truth = false;
  Pose3 truth_world_T_body;
  double truth_path_m = 0.0;
  std::int64_t stamp_ns = 0;
  double latency_ms = 0.0;       // pair popped -> outputs queued
};
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
  drivers::qnavcan::Mode mode() const noexcept { return mode_; }
  std::uint32_t deadline_misses() const noexcept { return deadline_misses_; }
  std::uint16_t fault_flags() const noexcept { return faults_; }
  ModeReject last_reject() const noexcept { return last_reject_; }
  std::uint32_t tiles() const noexcept { return tile_seq_; }
  std::uint32_t pings() const noexcept { return pings_; }
  // Inputs taken off the queues (each then handled or counted as rejected by its receiver).
  std::uint64_t can_frames() const noexcept { return can_frames_; }
  std::uint64_t dvl_samples() const noexcept { return dvl_samples_; }
  // Pings the tile pipeline's corrector refused as damaged (range, samples, altitude), and pings
  // stamped at or before the previous one (dropped).
  std::uint32_t pings_rejected() const noexcept {
    const auto& c = tiles_.corrector().counters();
    return c.get(sonar::CorrectorCounter::kBadSampleCount) + c.get(sonar::CorrectorCounter::kBadRange) +
           c.get(sonar::CorrectorCounter::kNonFiniteSample) + c.get(sonar::CorrectorCounter::kBadAltitude);
  }
  std::uint32_t pings_out_of_order() const noexcept { return pings_out_of_order_; }
  // Stereo pairs taken off the queue; of those processed by the VO; without attitude; out of order.
  std::uint32_t frames() const noexcept { return frames_; }
  std::uint32_t vo_frames() const noexcept { return vo_.frames(); }
  std::uint32_t vo_visual() const noexcept { return vo_.visual_steps(); }
  std::uint32_t vo_no_attitude() const noexcept { return vo_no_attitude_; }
  std::uint32_t frames_out_of_order() const noexcept { return frames_out_of_order_; }
  // Mode = Map: downward frames given to the mapper; of those refused (flagged, map untouched); map
  // file rewrites and failed ones.
  std::uint32_t map_frames() const noexcept { return map_frames_; }
  std::uint32_t map_bad_frames() const noexcept { return map_bad_frames_; }
  std::uint32_t map_saves() const noexcept { return map_saves_; }
  std::uint32_t map_save_errors() const noexcept { return map_save_errors_; }
  const pipeline::TopoMapper& mapper() const noexcept { return mapper_; }
  // qnav CAN frames refused by the receiver (format, length, range, invalid, stale, error frames).
  std::uint32_t can_rejected() const noexcept {
    return receiver_.counters().total() - receiver_.counters().get(drivers::qnavcan::RxCounter::kUnknownId);
  }
  std::uint32_t can_error_frames() const noexcept { return receiver_.counters().get(drivers::qnavcan::RxCounter::kErrorFrame); }
  bool bus_off() const noexcept { return bus_off_; }
  std::uint32_t writer_errors() const noexcept { return writer_errors_; }
  // The last teach could not be committed (the route stays under .new; the exit code says so).
  bool commit_failed() const noexcept { return commit_failed_; }
  // The bytes its "route_meta" buffer holds (the deployment test compares them with the table).
  std::size_t route_meta_bytes() const noexcept { return meta_.capacity() * sizeof(route::NodeMeta); }
  // MAVLink (mavlink.enabled): the endpoint (nullptr when off) and the estimate it publishes.
  const MavlinkEndpoint* mavlink() const noexcept { return mav_.get(); }
  const pipeline::NavEstimate& estimate() const noexcept { return est_; }

 private:
  static Result<Arena*> stage_arena(StaticMemory* mem, const char* name, std::size_t bytes, std::unique_ptr<ArenaStorage>& own,
                                    std::unique_ptr<Arena>& view);
  void handle_frame(const hal::CanRxFrame& rx) noexcept;
  void handle_mode(const drivers::qnavcan::ModeCmd& cmd) noexcept;
  ModeReject enter_teach(std::uint16_t id) noexcept;
  ModeReject enter_repeat(std::uint16_t id, bool reverse) noexcept;
  void leave_mode() noexcept;
  void handle_ping(const PingMsg& p) noexcept;
  void handle_pair(const FrameMsg& f) noexcept;
  void handle_downward(const FrameMsg& f, std::int64_t t0) noexcept;
  ModeReject enter_map(std::uint16_t id) noexcept;
  void save_map() noexcept;
  void log_map_frame(const FrameMsg& f, const pipeline::MapperStep& st, double latency_ms) noexcept;
  void publish_map_frame(const FrameMsg& f, const pipeline::MapperStep& st) noexcept;
  const std::uint8_t* frame_slot(std::uint32_t slot) const noexcept;
  void publish_vo_increment(std::uint32_t inliers) noexcept;
  bool on_tile(const pipeline::RouteTile& t) noexcept;
  void update_faults() noexcept;
  void publish() noexcept;
  void log_health() noexcept;
  void route_path(std::uint16_t id, const char* suffix, char* out, std::size_t n) const noexcept;
  void forget_guidance() noexcept;
  void stage_time(Stage s, std::int64_t t0_ns) noexcept;
  void mavlink_inputs() noexcept;
  void mavlink_publish() noexcept;
  void route_fix(const pipeline::RouteTile& t, const route::GuidanceOutput& g, bool confident) noexcept;

  const DaemonConfig& cfg_;
  const hal::Clock& sample_clock_;
  const hal::Clock& cpu_clock_;
  NavQueues q_{};
  TileObserver observer_ = nullptr;
  void* observer_ctx_ = nullptr;
  FILE* log_ = nullptr;

  std::unique_ptr<QueueCanBus> tx_bus_;
  std::unique_ptr<drivers::qnavcan::QnavCanPublisher> publisher_;
  drivers::qnavcan::QnavCanReceiver receiver_;
  drivers::dronecan::DroneCanAhrsReceiver ahrs_;  // a DroneCAN AHRS as the attitude source (extended frames)
  pipeline::DeadReckoner dr_;
  pipeline::RouteTilePipeline tiles_;
  pipeline::RouteRepeater repeater_;
  pipeline::RouteTileSink tile_sink_;
  pipeline::VoOdometry vo_;
  bool vo_ready_ = false;
  pipeline::TopoMapper mapper_;              // Mode = Map (PlaceEncoder: 32 KB inside; the worker lives on the heap)
  Arena* map_arena_ = nullptr;                 // the table's "map" buffer; reused by each new map
  std::unique_ptr<ArenaStorage> own_arenas_[4];  // tile pipeline, localiser, map, vo: a worker built without a static block
  std::unique_ptr<Arena> arena_views_[4];        // the same over the static block's buffers
  pipeline::MapperStep map_step_{};
  bool map_ready_ = false, map_open_ = false;
  char map_path_[1024] = {};
  std::uint32_t map_frames_ = 0, map_bad_frames_ = 0, map_saves_ = 0, map_save_errors_ = 0;
  FrameObserver frame_observer_ = nullptr;
  void* frame_ctx_ = nullptr;
  std::int64_t last_frame_ns_ = -1;     // the last stereo pair's sample time
  std::int64_t last_downward_ns_ = -1;  // the last downward frame's sample time
  std::int64_t map_mode_start_ns_ = 0;  // when Mode = Map was entered (map.stale_s counts from it)
  std::uint16_t map_node_ = topo::kNoNode;   // the node the last observed downward frame was placed at
  std::int64_t vo_mode_start_ns_ = 0;
  std::uint32_t frames_ = 0, vo_no_attitude_ = 0, frames_out_of_order_ = 0;
  Pose3 vo_anchor_, vo_last_set_;     // body poses: at the start of the pending increment, at its last update
  std::uint32_t vo_interval_inliers_ = 0;  // smallest inlier count of the increment's steps (0 = one was not visual)
  FrameReport frame_report_{};
  Pose2 vo_prev_dr_{};                // dead-reckoned pose at the previous pair (the VO's odometry prior)
  bool vo_prev_dr_valid_ = false;
  bool vo_chain_started_ = false;     // the first pair of this Vo mode was processed
  bool have_att_ = false;             // the newest attitude sample (QNAV_ATTITUDE_IN or DroneCAN AHRS)
  std::int64_t att_ns_ = 0;
  Mat3d att_R_ = Mat3d::Identity();   // world (NED) <- body (FRD)
  drivers::route_store::RouteFileWriter writer_;
  drivers::route_store::RouteFileReader reader_;
  std::vector<route::NodeMeta> meta_;  // reserved for route.max_nodes at init
  hal::FileStore& store_;
  double spacing_m_ = 60.0, swath_m_ = 100.0;

  drivers::qnavcan::Mode mode_ = drivers::qnavcan::Mode::kIdle;
  bool reverse_ = false;
  std::uint16_t route_id_ = 0;
  ModeReject last_reject_ = ModeReject::kNone;
  bool teach_open_ = false;
  bool eq5_ = false;
  std::uint16_t faults_ = 0;
  std::int64_t nav_now_ns_ = 0;
  std::int64_t last_ping_ns_ = -1;
  std::int64_t ping_rx_cpu_ns_ = 0;
  std::uint32_t pings_ = 0, tile_seq_ = 0, pass_ping_ = 0;
  std::uint32_t deadline_misses_ = 0;
  std::uint64_t can_frames_ = 0, dvl_samples_ = 0;
  std::uint32_t pings_out_of_order_ = 0;
  bool bus_off_ = false;
  bool leak_logged_ = false;  // the `leak` event is logged once, when the detector latches
  bool teach_stopped_ = false;  // an append failed: this teach ends at its last durable node
  std::uint32_t stage_misses_[static_cast<int>(Stage::kCount)] = {};
  std::int64_t stage_max_ns_[static_cast<int>(Stage::kCount)] = {};
  std::uint32_t budgets_us_[static_cast<int>(Stage::kCount)] = {};
  std::uint32_t dr_rejected_ = 0, mode_refused_ = 0, step_errors_ = 0, writer_errors_ = 0;
  std::uint32_t teach_no_odometry_ = 0, nav_resets_ = 0, software_faults_logged_ = 0;
  bool commit_failed_ = false;
  std::int64_t next_health_ns_ = 0;
  std::int64_t busy_ns_ = 0, busy_window_start_ns_ = 0;
  std::int64_t mode_ns_ = 0;  // time spent in handle_mode during this loop's input drain
  double cpu_load_pct_ = 0.0;
  bool started_ns_set_ = false;
  std::int64_t start_ns_ = 0;
  TileReport report_{};
  drivers::qnavcan::RouteStatus route_status_{};
  drivers::qnavcan::RouteGuidance guidance_{};
  std::unique_ptr<MavlinkEndpoint> mav_;
  pipeline::NavEstimate est_;
  bool est_on_vo_ = false;         // the estimate follows the VO body pose (Mode = Vo), else the dead reckoning
  bool route_fix_ = false;         // a route fix placed the estimate in this repeat's route frame
  Vec2d waypoint_ne_ = Vec2d::Zero();
  bool guidance_valid_ = false;
  double dvl_altitude_m_ = -1.0;   // the newest DVL altitude (< 0: none)
  std::atomic<std::uint64_t> progress_{0};
  bool shut_ = false;
};

}  // namespace qnav::daemon
