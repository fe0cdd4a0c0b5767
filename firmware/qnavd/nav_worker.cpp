#include "firmware/qnavd/nav_worker.hpp"

#include <algorithm>
#include <cmath>

#include "firmware/qnavd/software_fault.hpp"

namespace qnav::daemon {

namespace qc = drivers::qnavcan;

NavWorker::NavWorker(const DaemonConfig& config, const hal::Clock& sample_clock, const hal::Clock& cpu_clock, hal::FileStore& store) noexcept
    : cfg_(config),
      sample_clock_(sample_clock),
      cpu_clock_(cpu_clock),
      ctx_{&config, nullptr, &clock_},
      inputs_(ctx_),
      tiles_(ctx_),
      teach_(ctx_, store),
      repeat_(ctx_, store),
      vo_(ctx_),
      map_(ctx_, store),
      source_(ctx_),
      health_(ctx_) {}

NavWorker::~NavWorker() { shutdown(); }

Status NavWorker::init(const NavQueues& q, TileObserver observer, void* observer_ctx, FILE* log, StaticMemory* mem) {
  q_ = q;
  observer_ = observer;
  observer_ctx_ = observer_ctx;
  ctx_.log = log;
  if (!q.pings || !q.free_slots || !q.can_rx || !q.can_tx || !q.dvl || !q.ping_pool || !q.io)
    return Status(StatusCode::kInvalidArgument, "nav worker: queues missing");
  if ((map_runs(cfg_) || cfg_.vo_enabled) && (!q.frames || !q.free_frames || !q.frame_pool))
    return Status(StatusCode::kInvalidArgument, "nav worker: frame queues missing");
  tx_bus_ = std::make_unique<QueueCanBus>(q.can_tx);
  QNAV_RETURN_IF_ERROR(source_.init(q.mav_rx, q.mav_tx, mem));
  publisher_ = std::make_unique<qc::QnavCanPublisher>(*tx_bus_);
  QNAV_RETURN_IF_ERROR(tiles_.init(mem));
  QNAV_RETURN_IF_ERROR(repeat_.init(mem, *publisher_));
  teach_.init();
  tile_sink_ = [this](const pipeline::RouteTile& t) { return on_tile(t); };
  QNAV_RETURN_IF_ERROR(map_.init(mem, *publisher_));
  QNAV_RETURN_IF_ERROR(vo_.init(mem, *publisher_));
  const NavParts parts{&inputs_, &teach_, &repeat_, &vo_, &map_, &source_, &tiles_.pipeline(), q.io, &counters_, &state_};
  health_.init(parts, *publisher_, cpu_clock_.now_ns());
  initialised_ = true;
  return Status::ok();
}

bool NavWorker::run_once() noexcept {
  if (shut_) return false;
  bool did = false;
  // One ping or one stereo pair per loop, the earlier by sample time.
  PingMsg ping;
  FrameMsg pair;
  bool have_ping = false, have_pair = false;
  q_.pop_earlier(ping, have_ping, pair, have_pair);
  // Every input sampled up to this ping or pair (mode commands, attitude, velocities), and none after
  // it: the sample is placed with the navigation of its own time, whatever the I/O thread queued since.
  // And only the inputs that had arrived when the ping or pair arrived: one sampled before it but
  // received after it (a DVL report stamped with its latency) waits for the next batch, so the ping
  // sees the same navigation whether this worker pops it at once or late, and a replay is
  // reproducible. Arrival stamps share one clock: monotonic (linux backend) or mission (sim).
  const std::int64_t until_ns = have_ping ? ping.stamp.sample_ns : (have_pair ? pair.stamp.sample_ns : INT64_MAX);
  const std::int64_t until_arrival_ns = have_ping ? ping.stamp.arrival_ns : (have_pair ? pair.stamp.arrival_ns : INT64_MAX);
  drain_inputs(until_ns, until_arrival_ns, have_ping || have_pair, did);
  if (have_ping) {
    clock_.now_ns = std::max(clock_.now_ns, ping.stamp.sample_ns);
    handle_ping(ping);
    QNAVD_CHECK(q_.free_slots->try_push(ping.slot).is_ok(), "free-slot queue full: a ping slot was returned twice");
    did = true;
  }
  if (have_pair) {
    clock_.now_ns = std::max(clock_.now_ns, pair.stamp.sample_ns);
    handle_pair(pair);
    QNAVD_CHECK(q_.free_frames->try_push(pair.slot).is_ok(), "free-frame queue full: a frame slot was returned twice");
    did = true;
  }
  if (!did) {
    // Idle queues: time still passes (a stalled sensor must show as stale).
    clock_.now_ns = std::max(clock_.now_ns, sample_clock_.now_ns());
  }
  if (!started_ns_set_) {
    clock_.start_ns = clock_.now_ns;
    health_.start_window(cpu_clock_.now_ns());
    next_health_ns_ = clock_.now_ns;
    started_ns_set_ = true;
  }
  const std::int64_t t0 = cpu_clock_.now_ns();
  outputs();
  if (clock_.now_ns >= next_health_ns_) {
    health_.log(cpu_clock_.now_ns());
    next_health_ns_ = clock_.now_ns + static_cast<std::int64_t>(cfg_.health_period_s * 1e9);
  }
  stage_time(Stage::kOutputs, t0);
  progress_.fetch_add(1, std::memory_order_relaxed);
  return did;
}

// The inputs up to (until_ns, until_arrival_ns), in sample-time order across the CAN and DVL queues
// (a heading before a velocity of the same instant), so a DVL sample is turned by the newest heading
// at or before its own time. With no ping or pair in hand, a batch stops at the first ping or pair
// queued while it runs (the I/O thread queues a ping before any input that follows it): that ping is
// taken next, with none of the inputs after it.
void NavWorker::drain_inputs(std::int64_t until_ns, std::int64_t until_arrival_ns, bool have_sample, bool& did) noexcept {
  const std::int64_t t0 = cpu_clock_.now_ns();
  mode_ns_ = 0;
  if (source_.pending()) {
    mavlink_inputs();
    did = true;
  }
  hal::CanRxFrame rx;
  drivers::dvl::DvlVelocity v;
  bool any = false;
  for (;;) {
    const hal::CanRxFrame* cf = q_.can_rx->front();
    const drivers::dvl::DvlVelocity* dv = q_.dvl->front();
    if (!have_sample) q_.bound_by_queued_samples(until_ns, until_arrival_ns);  // after the input fronts: a ping queued before them is seen
    const bool can_due = cf != nullptr && cf->stamp.sample_ns <= until_ns && cf->stamp.arrival_ns <= until_arrival_ns;
    const bool dvl_due = dv != nullptr && dv->stamp.sample_ns <= until_ns && dv->stamp.arrival_ns <= until_arrival_ns;
    if (!can_due && !dvl_due) break;
    if (can_due && (!dvl_due || cf->stamp.sample_ns <= dv->stamp.sample_ns)) {
      if (!q_.can_rx->try_pop(rx)) break;
      qc::ModeCmd cmd;
      if (inputs_.on_can(rx, &cmd)) handle_mode(cmd);
      clock_.now_ns = std::max(clock_.now_ns, rx.stamp.sample_ns);
      // Outputs keep their DBC periods in sample time, also in a fast replay, and a frame sent from
      // inside a batch carries the faults of its own time (a sensor that went stale in the batch says so).
      outputs();
    } else {
      if (!q_.dvl->try_pop(v)) break;
      inputs_.on_dvl(v);
      clock_.now_ns = std::max(clock_.now_ns, v.stamp.sample_ns);
    }
    any = true;
  }
  did = did || any;
  if (did) stage_time(Stage::kInputs, t0 + mode_ns_);  // a mode change inside is timed as its own stage
}

// The autopilot's MAVLink: its ATTITUDE to the inputs, its mode commands to the mode logic (at most
// a few per loop: each may open a route file; the rest waits for the next loop), each acknowledged.
void NavWorker::mavlink_inputs() noexcept {
  for (int i = 0; i < 4; ++i) {
    const MavInputs in = source_.drain();
    if (in.attitude) {
      inputs_.on_attitude(in.attitude_ns, in.roll_rad, in.pitch_rad, in.yaw_rad);
      clock_.now_ns = std::max(clock_.now_ns, in.attitude_ns);
    }
    if (!in.mode_cmd) break;
    handle_mode(in.cmd);
    source_.ack(state_.last_reject);
  }
}

// The faults of this instant, then every output: CAN (NAV_STATUS, HEALTH, HEARTBEAT and whatever the
// components set), MAVLink.
void NavWorker::outputs() noexcept {
  const std::uint16_t faults = health_.update(repeat_);
  health_.publish();
  if (source_.enabled()) source_.publish(state_.mode, faults, inputs_, vo_, state_.step);
}

void NavWorker::handle_mode(const qc::ModeCmd& cmd) noexcept {
  const std::int64_t t0 = cpu_clock_.now_ns();
  const std::uint16_t id = cmd.route_id != 0 ? cmd.route_id : cfg_.route_id;
  if (cmd.reset_nav) {
    inputs_.reset_nav();  // the autopilot sets the navigation origin anew (distance and position restart)
    source_.reset();
    ++counters_.nav_resets;
  }
  const qc::Mode mode = state_.mode;
  const bool uses_route = cmd.mode == qc::Mode::kTeach || cmd.mode == qc::Mode::kRepeat || cmd.mode == qc::Mode::kMap;
  const bool change = cmd.mode != mode || (uses_route && id != route_id_) || (cmd.mode == qc::Mode::kRepeat && cmd.reverse != reverse_);
  ModeReject why = ModeReject::kNone;
  if ((cmd.mode == qc::Mode::kMap && !map_.ready()) || (cmd.mode == qc::Mode::kVo && !vo_.ready())) why = ModeReject::kUnsupportedMode;
  if (why == ModeReject::kNone && change) why = enter_mode(cmd, id);
  state_.last_reject = why;
  if (why != ModeReject::kNone) ++counters_.mode_refused;
  if (ctx_.events())
    std::fprintf(ctx_.log, "{\"event\":\"mode\",\"t_s\":%.3f,\"cmd\":\"%s\",\"reverse\":%s,\"route_id\":%u,\"state\":\"%s\",\"refused\":%s%s%s}\n",
                 clock_.t_s(), qc::mode_name(cmd.mode), cmd.reverse ? "true" : "false", id, qc::mode_name(state_.mode),
                 why == ModeReject::kNone ? "false" : "\"", why == ModeReject::kNone ? "" : to_string(why), why == ModeReject::kNone ? "" : "\"");
  stage_time(Stage::kModes, t0);
  mode_ns_ += cpu_clock_.now_ns() - t0;
}

// A change of mode, route or direction: checked, the old mode left, the new one entered.
ModeReject NavWorker::enter_mode(const qc::ModeCmd& cmd, std::uint16_t id) noexcept {
  // Teach and 3D-VME need the heading; 6D-VME (a rig without an attitude sensor) measures its own rotation.
  const bool needs_heading = cmd.mode == qc::Mode::kTeach || (cmd.mode == qc::Mode::kVo && cfg_.vo.mode == vo::VmeMode::k3D);
  if (needs_heading && inputs_.dr().heading_age_s(clock_.now_ns) > cfg_.attitude_stale_s) return ModeReject::kNoHeading;
  if (cmd.mode == qc::Mode::kRepeat) {
    const ModeReject why = repeat_.probe(id);  // refused before the current mode is left when the route is not there
    if (why != ModeReject::kNone) return why;
  }
  leave_mode();
  ModeReject why = ModeReject::kNone;
  if (cmd.mode == qc::Mode::kTeach) why = teach_.enter(id, spacing_m_, swath_m_);
  if (cmd.mode == qc::Mode::kRepeat) why = repeat_.enter(id, cmd.reverse);
  if (cmd.mode == qc::Mode::kMap) {
    why = map_.enter(id);
    source_.map_start();
  }
  if (cmd.mode == qc::Mode::kVo) vo_.reset(clock_.now_ns);
  if (why == ModeReject::kNone) {
    const bool uses_route = cmd.mode == qc::Mode::kTeach || cmd.mode == qc::Mode::kRepeat || cmd.mode == qc::Mode::kMap;
    state_.mode = cmd.mode;
    reverse_ = cmd.reverse;
    route_id_ = uses_route ? id : route_id_;  // the dead reckoning runs on across modes: poses depend on the samples only
  } else {
    state_.mode = qc::Mode::kIdle;  // the old mode was left: a defined state
  }
  return why;
}

void NavWorker::leave_mode() noexcept {
  if (state_.mode == qc::Mode::kTeach && teach_.open()) {
    // The node in progress: a tile of at least half the configured scanlines is finished, less is discarded.
    const Status fs = tiles_.flush(tile_sink_);
    if (!fs) {
      teach_.count_error();
      if (ctx_.log) std::fprintf(ctx_.log, "{\"event\":\"error\",\"what\":\"teach: the node in progress was lost: %s\"}\n", fs.message());
    }
    teach_.close();
  }
  if (state_.mode == qc::Mode::kRepeat) repeat_.leave();
  if (state_.mode == qc::Mode::kMap) map_.leave(route_id_);
  tiles_.reset_pass();
  // Nothing said about the previous route may reach the autopilot as if it held for the next one.
  report_.step = route::LocaliserStep{};
  state_.step = route::LocaliserStep{};
  repeat_.forget(counters_.tiles);
  source_.forget();
}

void NavWorker::handle_ping(const PingMsg& p) noexcept {
  const std::int64_t t0 = cpu_clock_.now_ns();
  ++counters_.pings;
  // A ping stamped at or before the previous one (a clock stepped back, a duplicate, a reordered
  // delivery) cannot be placed on the dead-reckoned track: counted and dropped.
  if (!ping_order_.advance(p.stamp.sample_ns)) {
    ++counters_.pings_out_of_order;
    return;
  }
  state_.last_ping_ns = p.stamp.sample_ns;
  const qc::Mode mode = state_.mode;
  if (mode != qc::Mode::kTeach && mode != qc::Mode::kRepeat) return;
  const pipeline::DeadReckoner& dr = inputs_.dr();
  if (!dr.has_heading() || dr.heading_age_s(p.stamp.sample_ns) > cfg_.attitude_stale_s) return;  // no tiles without a heading
  if (mode == qc::Mode::kTeach && cfg_.dvl_enabled && dr.velocity_age_s(p.stamp.sample_ns) > cfg_.dvl_stale_s) {
    ++counters_.teach_no_odometry;  // a taught node needs its true place: none is built while the DVL is lost
    return;
  }
  const std::size_t half = q_.ping_pool_stride / 2;
  if (!QNAVD_CHECK(p.port_samples <= half && p.stbd_samples <= half, "ping larger than its pool slot")) return;
  const Pose2 nav = dr.pose_at(p.stamp.sample_ns);
  ping_rx_cpu_ns_ = t0;
  report_.truth_along_m = -1.0;
  const std::uint32_t tiles_before = counters_.tiles;
  const Status s = tiles_.push(p, q_.ping_pool, q_.ping_pool_stride, nav, tile_sink_);
  QNAVD_CHECK(s.is_ok(), "tile pipeline refused a ping (its rejections are counted, not returned)");
  // The ping that completes a tile runs the whole tile stage (raster, features, teach append or
  // repeat update): it is timed against the tile budget, every other ping against the ping budget.
  stage_time(counters_.tiles != tiles_before ? Stage::kTile : Stage::kPing, t0);
}

// A finished tile (the tile pipeline's sink): to the teach or the repeat, then reported.
bool NavWorker::on_tile(const pipeline::RouteTile& t) noexcept {
  TileReport& r = report_;
  r = TileReport{};
  r.seq = counters_.tiles++;
  r.mode = state_.mode;
  r.reverse = reverse_;
  r.route_id = route_id_;
  r.nav_step_m = t.nav_step_m;
  r.truth_along_m = t.truth_along_m;
  r.truth_lateral_m = t.truth_lateral_m;
  r.stamp_ns = static_cast<std::int64_t>(t.node.meta.stamp_ns);
  if (state_.mode == qc::Mode::kTeach && teach_.writing()) {
    r.node_written = teach_.append(t.node);
  } else if (state_.mode == qc::Mode::kRepeat) {
    // Judged at the tile's last ping (sample time), not at "now": the same data gives the same answer.
    const pipeline::DeadReckoner& dr = inputs_.dr();
    const bool dvl_lost = !dr.has_velocity() || dr.velocity_age_s(state_.last_ping_ns) > cfg_.dvl_stale_s;
    r.eq5_motion = repeat_.step(t, r.seq, dvl_lost, r.step);
    state_.step = r.step;
    // The next tile framed on the taught nodes (a reverse pass brought into step with them), as the tool does.
    tiles_.set_next_stride_m(repeat_.next_stride_m(r.step));
    if (source_.enabled()) {
      const std::uint32_t n = r.step.guidance.node;
      source_.route_fix(t, r.step, n < repeat_.meta().size() ? &repeat_.meta()[n] : nullptr, reverse_, dr);
    }
  }
  r.latency_ms = static_cast<double>(cpu_clock_.now_ns() - ping_rx_cpu_ns_) * 1e-6;
  tiles_.log(r);
  if (observer_) observer_(observer_ctx_, r);
  return true;
}

void NavWorker::handle_pair(const FrameMsg& f) noexcept {
  const std::int64_t t0 = cpu_clock_.now_ns();
  ++counters_.frames;
  // A pair (or a downward frame) stamped at or before the previous one of its camera cannot be a step
  // forward in time: counted, dropped. The two cameras are separate devices: each has its own order.
  if (!(f.downward ? map_.in_order(f.stamp.sample_ns) : vo_.in_order(f.stamp.sample_ns))) {
    ++counters_.frames_out_of_order;
    return;
  }
  const std::size_t pair_bytes = 2 * static_cast<std::size_t>(cfg_.vo.max_width) * static_cast<std::size_t>(cfg_.vo.max_height);
  if (f.downward) {
    if (state_.mode != qc::Mode::kMap || !map_.ready() || !map_.on_frame(f, q_.frame_slot(f.slot, pair_bytes))) return;
    if (source_.enabled() && map_.step().observed) source_.map_step(map_.step().place, inputs_.dr());
    stage_time(Stage::kMap, t0);
    map_.log_frame(f, static_cast<double>(cpu_clock_.now_ns() - t0) * 1e-6);
    return;
  }
  if (state_.mode != qc::Mode::kVo || !vo_.ready()) return;
  FrameReport* r = vo_.on_pair(f, q_.frame_slot(f.slot, pair_bytes), inputs_);
  if (r == nullptr) return;
  stage_time(Stage::kVo, t0);
  r->latency_ms = static_cast<double>(cpu_clock_.now_ns() - t0) * 1e-6;
  vo_.log_pair(*r);
  if (frame_observer_) frame_observer_(frame_ctx_, *r);
}

void NavWorker::shutdown() noexcept {
  if (shut_) return;
  if (initialised_) {
    leave_mode();
    health_.log(cpu_clock_.now_ns());  // the final counters
  }
  state_.mode = qc::Mode::kIdle;
  shut_ = true;
}

}  // namespace qnav::daemon
