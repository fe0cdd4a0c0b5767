#include "firmware/qnavd/nav_worker.hpp"

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstring>

#include "firmware/qnavd/software_fault.hpp"
#include "drivers/map_store/map_file.hpp"
#include "drivers/route_store/route_open.hpp"
#include "firmware/pipeline/route_can.hpp"
#include "nav/core/geometry.hpp"

namespace qnav::daemon {

namespace qc = drivers::qnavcan;

const char* to_string(ModeReject r) noexcept {
  switch (r) {
    case ModeReject::kNone: return "none";
    case ModeReject::kUnsupportedMode: return "mode not supported by this build";
    case ModeReject::kRouteMissing: return "route file not found";
    case ModeReject::kRouteDamaged: return "route file damaged";
    case ModeReject::kRouteTooShort: return "route has fewer than 2 nodes";
    case ModeReject::kStorage: return "route storage error";
    case ModeReject::kNoHeading: return "no recent attitude (heading)";
    case ModeReject::kRouteTooLong: return "route has more nodes than route.max_nodes";
    case ModeReject::kRouteMismatch: return "route does not fit this configuration (sensor or geometry)";
  }
  return "?";
}

namespace {
constexpr std::int64_t kNsPerS = 1000000000;
}  // namespace

NavWorker::NavWorker(const DaemonConfig& config, const hal::Clock& sample_clock, const hal::Clock& cpu_clock, hal::FileStore& store) noexcept
    : cfg_(config), sample_clock_(sample_clock), cpu_clock_(cpu_clock), writer_(store), reader_(store), store_(store) {}

NavWorker::~NavWorker() { shutdown(); }

// A nav stage's arena: its buffer in the static block (qnavd), or one of its own (a worker built alone).
Result<Arena*> NavWorker::stage_arena(StaticMemory* mem, const char* name, std::size_t bytes, std::unique_ptr<ArenaStorage>& own,
                                      std::unique_ptr<Arena>& view) {
  if (mem != nullptr) {
    Result<Span<std::byte>> r = mem->take(name);
    if (!r) return r.status();
    view = std::make_unique<Arena>(r.value());
    return view.get();
  }
  own = std::make_unique<ArenaStorage>(bytes);
  if (!own->valid()) return Status(StatusCode::kCapacityExceeded, "nav worker: cannot allocate a stage arena");
  return static_cast<Arena*>(own.get());
}

Status NavWorker::init(const NavQueues& q, TileObserver observer, void* observer_ctx, FILE* log, StaticMemory* mem) {
  q_ = q;
  observer_ = observer;
  observer_ctx_ = observer_ctx;
  log_ = log;
  if (!q.pings || !q.free_slots || !q.can_rx || !q.can_tx || !q.dvl || !q.ping_pool || !q.io)
    return Status(StatusCode::kInvalidArgument, "nav worker: queues missing");
  tx_bus_ = std::make_unique<QueueCanBus>(q.can_tx);
  if (cfg_.mavlink_enabled) {
    if (!q.mav_rx || !q.mav_tx) return Status(StatusCode::kInvalidArgument, "nav worker: mavlink queues missing");
    mav_ = std::make_unique<MavlinkEndpoint>(cfg_, log);
  }
  publisher_ = std::make_unique<qc::QnavCanPublisher>(*tx_bus_);
  Result<Arena*> a = stage_arena(mem, "tile_pipeline", pipeline::RouteTilePipeline::arena_bytes(cfg_.tiles), own_arenas_[0], arena_views_[0]);
  if (!a) return a.status();
  QNAV_RETURN_IF_ERROR(tiles_.init(cfg_.tiles, *a.value()));
  const route::LocaliserConfig lc = repeat_localiser_config(cfg_);
  a = stage_arena(mem, "localiser", route::RouteLocaliser::arena_bytes(lc), own_arenas_[1], arena_views_[1]);
  if (!a) return a.status();
  QNAV_RETURN_IF_ERROR(repeater_.init(lc, *a.value()));
  meta_.reserve(cfg_.max_nodes);
  writer_.reserve(route::record_bytes(route::kMaxKeypointsPerNode));
  reader_.reserve(route::record_bytes(route::kMaxKeypointsPerNode));
  tile_sink_ = [this](const pipeline::RouteTile& t) { return on_tile(t); };
  if (map_runs(cfg_)) {
    if (!q.frames || !q.free_frames || !q.frame_pool) return Status(StatusCode::kInvalidArgument, "nav worker: frame queues missing");
    const pipeline::TopoMapperConfig mc = map_mapper_config(cfg_);
    a = stage_arena(mem, "map", pipeline::TopoMapper::arena_bytes(mc), own_arenas_[2], arena_views_[2]);
    if (!a) return a.status();
    map_arena_ = a.value();
    QNAV_RETURN_IF_ERROR(mapper_.init(mc, *map_arena_));
    map_ready_ = true;
  }
  if (cfg_.vo_enabled) {
    if (!q.frames || !q.free_frames || !q.frame_pool) return Status(StatusCode::kInvalidArgument, "nav worker: frame queues missing");
    a = stage_arena(mem, "vo", vo::StereoVo::arena_bytes(cfg_.vo), own_arenas_[3], arena_views_[3]);
    if (!a) return a.status();
    QNAV_RETURN_IF_ERROR(vo_.init(cfg_.vo, vo_body_T_cam(cfg_), cfg_.vo_prior, *a.value()));
    vo_ready_ = true;
  }
  const Deployment d = make_deployment(cfg_);
  for (int i = 0; i < static_cast<int>(Stage::kCount); ++i) budgets_us_[i] = d.stages[i].budget_us;
  return Status::ok();
}

void NavWorker::stage_time(Stage s, std::int64_t t0_ns) noexcept {
  const std::int64_t dt = cpu_clock_.now_ns() - t0_ns;
  const int i = static_cast<int>(s);
  stage_max_ns_[i] = std::max(stage_max_ns_[i], dt);
  busy_ns_ += dt;
  if (budgets_us_[i] > 0 && dt > static_cast<std::int64_t>(budgets_us_[i]) * 1000) {
    ++stage_misses_[i];
    ++deadline_misses_;
  }
}

bool NavWorker::run_once() noexcept {
  if (shut_) return false;
  bool did = false;
  // One ping or one stereo pair per loop, the earlier by sample time.
  PingMsg ping;
  FrameMsg pair;
  const PingMsg* next_ping = q_.pings->front();
  const FrameMsg* next_pair = q_.frames != nullptr ? q_.frames->front() : nullptr;
  const bool take_pair = next_pair != nullptr && (next_ping == nullptr || next_pair->stamp.sample_ns < next_ping->stamp.sample_ns);
  const bool have_ping = !take_pair && q_.pings->try_pop(ping).is_ok();
  const bool have_pair = take_pair && q_.frames->try_pop(pair).is_ok();
  // Every input sampled up to this ping or pair (mode commands, attitude, velocities), and none after
  // it: the sample is placed with the navigation of its own time, whatever the I/O thread queued since.
  // And only the inputs that had arrived when the ping or pair arrived: one sampled before it but
  // received after it (a DVL report stamped with its latency) waits for the next batch, so the ping
  // sees the same navigation whether this worker pops it at once or late, and a replay is
  // reproducible. Arrival stamps share one clock: monotonic (linux backend) or mission (sim).
  // With no ping or pair in hand, a batch of inputs stops at the first ping or pair queued while it
  // runs (the I/O thread queues a ping before any input that follows it): that ping is taken next,
  // with none of the inputs after it.
  std::int64_t until_ns = have_ping ? ping.stamp.sample_ns : (have_pair ? pair.stamp.sample_ns : INT64_MAX);
  std::int64_t until_arrival_ns = have_ping ? ping.stamp.arrival_ns : (have_pair ? pair.stamp.arrival_ns : INT64_MAX);
  hal::CanRxFrame rx;
  std::int64_t t0 = cpu_clock_.now_ns();
  mode_ns_ = 0;
  if (mav_ && q_.mav_rx->front() != nullptr) {
    mavlink_inputs();
    did = true;
  }
  drivers::dvl::DvlVelocity v;
  // In sample-time order across the two queues (a heading before a velocity of the same instant), so
  // a DVL sample is turned by the newest heading at or before its own time.
  for (;;) {
    const hal::CanRxFrame* cf = q_.can_rx->front();
    const drivers::dvl::DvlVelocity* dv = q_.dvl->front();
    if (!have_ping && !have_pair) {  // after the input fronts: a ping queued before them is seen
      const PingMsg* np = q_.pings->front();
      const FrameMsg* nf = q_.frames != nullptr ? q_.frames->front() : nullptr;
      if (np != nullptr) until_ns = std::min(until_ns, np->stamp.sample_ns), until_arrival_ns = std::min(until_arrival_ns, np->stamp.arrival_ns);
      if (nf != nullptr) until_ns = std::min(until_ns, nf->stamp.sample_ns), until_arrival_ns = std::min(until_arrival_ns, nf->stamp.arrival_ns);
    }
    const bool can_due = cf != nullptr && cf->stamp.sample_ns <= until_ns && cf->stamp.arrival_ns <= until_arrival_ns;
    const bool dvl_due = dv != nullptr && dv->stamp.sample_ns <= until_ns && dv->stamp.arrival_ns <= until_arrival_ns;
    if (!can_due && !dvl_due) break;
    if (can_due && (!dvl_due || cf->stamp.sample_ns <= dv->stamp.sample_ns)) {
      if (!q_.can_rx->try_pop(rx)) break;
      ++can_frames_;
      handle_frame(rx);
      nav_now_ns_ = std::max(nav_now_ns_, rx.stamp.sample_ns);
      // Outputs keep their DBC periods in sample time, also in a fast replay, and a frame sent from
      // inside a batch carries the faults of its own time (a sensor that went stale in the batch says so).
      update_faults();
      publish();
    } else {
      if (!q_.dvl->try_pop(v)) break;
      ++dvl_samples_;
      if (!dr_.on_velocity(v.stamp.sample_ns, v.vx_mps, v.vy_mps, 10.0, cfg_.dvl_stale_s)) ++dr_rejected_;
      dvl_altitude_m_ = std::isfinite(v.altitude_m) ? v.altitude_m : -1.0;
      nav_now_ns_ = std::max(nav_now_ns_, v.stamp.sample_ns);
    }
    did = true;
  }
  if (did) stage_time(Stage::kInputs, t0 + mode_ns_);  // a mode change inside is timed as its own stage
  if (have_ping) {
    nav_now_ns_ = std::max(nav_now_ns_, ping.stamp.sample_ns);
    handle_ping(ping);
    QNAVD_CHECK(q_.free_slots->try_push(ping.slot).is_ok(), "free-slot queue full: a ping slot was returned twice");
    did = true;
  }
  if (have_pair) {
    nav_now_ns_ = std::max(nav_now_ns_, pair.stamp.sample_ns);
    handle_pair(pair);
    QNAVD_CHECK(q_.free_frames->try_push(pair.slot).is_ok(), "free-frame queue full: a frame slot was returned twice");
    did = true;
  }
  if (!did) {
    // Idle queues: time still passes (a stalled sensor must show as stale).
    nav_now_ns_ = std::max(nav_now_ns_, sample_clock_.now_ns());
  }
  if (!started_ns_set_) {
    start_ns_ = nav_now_ns_;
    busy_ns_ = 0;
    busy_window_start_ns_ = cpu_clock_.now_ns();
    next_health_ns_ = nav_now_ns_;
    started_ns_set_ = true;
  }
  t0 = cpu_clock_.now_ns();
  update_faults();
  publish();
  if (nav_now_ns_ >= next_health_ns_) {
    log_health();
    next_health_ns_ = nav_now_ns_ + static_cast<std::int64_t>(cfg_.health_period_s * 1e9);
  }
  stage_time(Stage::kOutputs, t0);
  progress_.fetch_add(1, std::memory_order_relaxed);
  return did;
}

void NavWorker::handle_frame(const hal::CanRxFrame& rx) noexcept {
  if (rx.frame.extended && !rx.frame.error) {
    // DroneCAN (29-bit): an AHRS Solution's orientation quaternion (NED) gives the compass heading.
    if (ahrs_.on_frame(rx) == drivers::dronecan::AhrsUpdate::kSolution) {
      const float* q = ahrs_.solution().value.orientation_xyzw;
      const double x = static_cast<double>(q[0]), y = static_cast<double>(q[1]), z = static_cast<double>(q[2]), w = static_cast<double>(q[3]);
      double yaw = std::atan2(2.0 * (w * z + x * y), w * w + x * x - y * y - z * z);  // exact for a quaternion of any norm
      if (yaw < 0.0) yaw += 2.0 * 3.14159265358979323846;
      if (!dr_.on_heading(ahrs_.solution().stamp.sample_ns, yaw)) ++dr_rejected_;
      const double n = std::sqrt(x * x + y * y + z * z + w * w);
      if (std::isfinite(n) && n > 0.5 && n < 2.0) {  // the full attitude, for the visual odometry
        att_R_ = Eigen::Quaterniond(w / n, x / n, y / n, z / n).toRotationMatrix();
        att_ns_ = ahrs_.solution().stamp.sample_ns;
        have_att_ = true;
      }
    }
    return;  // rejections counted by the AHRS receiver
  }
  if (rx.frame.error) {  // the controller's own report: bus-off until it says it restarted
    if (rx.frame.id & hal::can_error::kBusOff) bus_off_ = true;
    if (rx.frame.id & hal::can_error::kRestarted) bus_off_ = false;
  }
  if (!receiver_.on_frame(rx)) return;  // counted by the receiver
  if (rx.frame.id == qc::kIdAttitudeIn) {
    qc::Stamped<qc::AttitudeIn> a;
    if (receiver_.latest_attitude(rx.stamp.sample_ns, INT64_MAX / 2, a)) {
      if (!dr_.on_heading(a.stamp.sample_ns, a.value.heading_rad)) ++dr_rejected_;
      att_R_ = rotation_from_rpy(a.value.roll_rad, a.value.pitch_rad, a.value.heading_rad);
      att_ns_ = a.stamp.sample_ns;
      have_att_ = true;
    }
  } else if (rx.frame.id == qc::kIdModeCmd) {
    handle_mode(receiver_.last_mode().value);
  }
}

void NavWorker::route_path(std::uint16_t id, const char* suffix, char* out, std::size_t n) const noexcept {
  std::snprintf(out, n, "%s/route_%u.qroute%s", cfg_.route_dir.c_str(), static_cast<unsigned>(id), suffix);
}

ModeReject NavWorker::enter_teach(std::uint16_t id) noexcept {
  char final_path[1024];
  route_path(id, "", final_path, sizeof final_path);
  // Taught under route_<id>.qroute.new and committed over route_<id>.qroute when the teach ends (the
  // old route stays whole until then). A run that was cut off (power, kill -9) or too short to commit
  // left its nodes under .new: the route store moves them aside to .new.kept.<n>, never deletes them.
  drivers::route_store::RouteWriterOptions o;
  o.replace_existing = true;
  drivers::route_store::RouteReplaceReport rep;
  const route::RouteParams params = pipeline::side_scan_route_params(cfg_.tiles, spacing_m_, swath_m_);
  const Status s = writer_.create_replacement(final_path, params, o, &rep);
  if (rep.previous_kept && log_) std::fprintf(log_, "{\"event\":\"teach_previous_kept\",\"file\":\"%s\"}\n", rep.kept_path);
  if (!s) {
    if (log_) std::fprintf(log_, "{\"event\":\"error\",\"what\":\"teach: %s.new: %s\"}\n", final_path, s.message());
    return ModeReject::kStorage;
  }
  teach_open_ = true;
  teach_stopped_ = false;
  return ModeReject::kNone;
}

ModeReject NavWorker::enter_repeat(std::uint16_t id, bool reverse) noexcept {
  char path[1024];
  route_path(id, "", path, sizeof path);
  // The one route-open policy (drivers/route_store/route_open.hpp), as `qnav route repeat` applies it.
  using drivers::route_store::RepeatOpen;
  const drivers::route_store::RepeatOpenReport r = drivers::route_store::open_route_for_repeat(reader_, path, meta_, cfg_.max_nodes);
  switch (r.outcome) {
    case RepeatOpen::kMissing:
    case RepeatOpen::kStorage:
    case RepeatOpen::kUnreadable:
    case RepeatOpen::kTooLong:
    case RepeatOpen::kTooShort:
      if (log_) std::fprintf(log_, "{\"event\":\"route_refused\",\"file\":\"%s\",\"why\":\"%s\"}\n", path, r.why.message());
      if (r.outcome == RepeatOpen::kMissing) return ModeReject::kRouteMissing;
      if (r.outcome == RepeatOpen::kStorage) return ModeReject::kStorage;
      if (r.outcome == RepeatOpen::kTooLong) return ModeReject::kRouteTooLong;
      if (r.outcome == RepeatOpen::kTooShort) return ModeReject::kRouteTooShort;
      faults_ |= qc::fault::kRouteDamaged;
      return ModeReject::kRouteDamaged;
    case RepeatOpen::kDamaged:
      if (log_) std::fprintf(log_, "{\"event\":\"route_damaged\",\"file\":\"%s\",\"first_bad_node\":%u,\"why\":\"%s\"}\n", path, r.first_bad_node, r.why.message());
      faults_ |= qc::fault::kRouteDamaged;
      return ModeReject::kRouteDamaged;
    case RepeatOpen::kOk:
    case RepeatOpen::kGoodPrefix:
      break;
  }
  if (r.cut_off || r.torn_bytes > 0) {
    // Still usable (every complete node was checked), but the autopilot's operator should know.
    if (log_)
      std::fprintf(log_, "{\"event\":\"route_cut_off\",\"file\":\"%s\",\"nodes\":%u,\"torn_bytes\":%llu,\"partial_node_dropped\":%s,\"end\":\"%s\"}\n", path,
                   r.file_nodes, static_cast<unsigned long long>(r.torn_bytes), r.torn_bytes > 0 ? "true" : "false",
                   drivers::route_store::to_string(reader_.end()));
  }
  // A damaged node with a good prefix before it: the repeat runs on the prefix, and the fault stays
  // raised while it does (the route file needs attention).
  const bool prefix_only = r.outcome == RepeatOpen::kGoodPrefix;
  if (prefix_only && log_)
    std::fprintf(log_, "{\"event\":\"route_damaged\",\"file\":\"%s\",\"first_bad_node\":%u,\"why\":\"%s\",\"repeating_nodes\":%u,\"nodes_unused\":%u}\n",
                 path, r.first_bad_node, r.why.message(), r.nodes_used, r.file_nodes - r.nodes_used);
  repeater_.set_motion(reverse ? route::RouteDirection::kReverse : route::RouteDirection::kForward, route::MotionModel::kOdometry);
  const Status s = repeater_.start(reader_.params(), Span<const route::NodeMeta>(meta_.data(), meta_.size()), reader_);
  if (!s) {
    // e.g. a route taught with another sensor or tile geometry than this configuration's
    if (log_) std::fprintf(log_, "{\"event\":\"route_refused\",\"file\":\"%s\",\"why\":\"%s\"}\n", path, s.message());
    reader_.close();
    return ModeReject::kRouteMismatch;
  }
  if (prefix_only)
    faults_ |= qc::fault::kRouteDamaged;
  else
    faults_ &= static_cast<std::uint16_t>(~qc::fault::kRouteDamaged);  // this route is good
  eq5_ = false;
  return ModeReject::kNone;
}

void NavWorker::leave_mode() noexcept {
  if (mode_ == qc::Mode::kTeach && teach_open_) {
    // The node in progress: a tile of at least half the configured scanlines is finished, less is discarded.
    const Status fs = tiles_.flush(tile_sink_);
    if (!fs) {
      ++writer_errors_;
      if (log_) std::fprintf(log_, "{\"event\":\"error\",\"what\":\"teach: the node in progress was lost: %s\"}\n", fs.message());
    }
    char final_path[1024];
    route_path(route_id_, "", final_path, sizeof final_path);
    const std::uint32_t nodes = writer_.node_count();
    Status s;
    if (nodes >= 2) {
      s = writer_.commit_as(final_path);
    } else {
      s = writer_.close();  // kept as .new: too short to repeat, but nothing taught is deleted
    }
    if (log_)
      std::fprintf(log_, "{\"event\":\"teach_closed\",\"route_id\":%u,\"nodes\":%u,\"file\":\"%s%s\",\"ok\":%s,\"why\":\"%s\"}\n", route_id_, nodes,
                   final_path, nodes >= 2 ? "" : ".new", s ? "true" : "false", s ? "" : s.message());
    if (!s) commit_failed_ = true;
    if (!s) ++writer_errors_;
    teach_open_ = false;
  }
  if (mode_ == qc::Mode::kRepeat) reader_.close();
  if (mode_ == qc::Mode::kMap && map_open_) {
    save_map();  // the map as it ends (adapted since its last new node)
    if (log_)
      std::fprintf(log_, "{\"event\":\"map_closed\",\"route_id\":%u,\"nodes\":%zu,\"edges\":%zu,\"frames\":%u,\"bad_frames\":%u,"  // frames: since start
                         "\"file\":\"%s\",\"saves\":%u,\"save_errors\":%u}\n",
                   route_id_, mapper_.map().node_count(), mapper_.map().edge_count(), map_frames_, map_bad_frames_, map_path_, map_saves_,
                   map_save_errors_);
    map_open_ = false;
  }
  tiles_.reset_pass();
  pass_ping_ = 0;
  forget_guidance();
}

// Nothing said about the previous route may reach the autopilot as if it held for the next one.
void NavWorker::forget_guidance() noexcept {
  report_.step = route::LocaliserStep{};
  guidance_ = qc::RouteGuidance{};
  route_status_ = qc::RouteStatus{};
  route_status_.status = qc::GuidanceState::kHoldCourse;
  route_status_.tile_seq = static_cast<std::uint16_t>(tile_seq_ & 0xFFFF);
  publisher_->set(guidance_);
  publisher_->set(route_status_);
  route_fix_ = false;
  guidance_valid_ = false;
}

void NavWorker::handle_mode(const qc::ModeCmd& cmd) noexcept {
  const std::int64_t t0 = cpu_clock_.now_ns();
  const std::uint16_t id = cmd.route_id != 0 ? cmd.route_id : cfg_.route_id;
  ModeReject why = ModeReject::kNone;
  if (cmd.reset_nav) {
    dr_.reset();  // the autopilot sets the navigation origin anew (distance and position restart)
    est_.reset();
    ++nav_resets_;
  }
  const bool uses_route = cmd.mode == qc::Mode::kTeach || cmd.mode == qc::Mode::kRepeat || cmd.mode == qc::Mode::kMap;
  const bool change = cmd.mode != mode_ || (uses_route && id != route_id_) || (cmd.mode == qc::Mode::kRepeat && cmd.reverse != reverse_);
  if ((cmd.mode == qc::Mode::kMap && !map_ready_) || (cmd.mode == qc::Mode::kVo && !vo_ready_)) why = ModeReject::kUnsupportedMode;
  if (why == ModeReject::kNone && change) {
    // Teach and 3D-VME need the heading; 6D-VME (a rig without an attitude sensor) measures its own rotation.
    const bool needs_heading = cmd.mode == qc::Mode::kTeach || (cmd.mode == qc::Mode::kVo && cfg_.vo.mode == vo::VmeMode::k3D);
    if (needs_heading && dr_.heading_age_s(nav_now_ns_) > cfg_.attitude_stale_s) why = ModeReject::kNoHeading;
    if (cmd.mode == qc::Mode::kRepeat) {
      // Refused before the current mode is left when the route is not there at all.
      char path[1024];
      route_path(id, "", path, sizeof path);
      Result<int> probe = store_.open(path, hal::FileMode::kRead);
      if (probe) {
        store_.close(*probe);
      } else {
        if (log_) std::fprintf(log_, "{\"event\":\"route_refused\",\"file\":\"%s\",\"why\":\"%s\"}\n", path, probe.status().message());
        why = probe.status().code() == StatusCode::kNotFound ? ModeReject::kRouteMissing : ModeReject::kStorage;
      }
    }
    if (why == ModeReject::kNone) {
      leave_mode();
      if (cmd.mode == qc::Mode::kTeach) why = enter_teach(id);
      if (cmd.mode == qc::Mode::kRepeat) why = enter_repeat(id, cmd.reverse);
      if (cmd.mode == qc::Mode::kMap) why = enter_map(id);
      if (cmd.mode == qc::Mode::kVo) {
        // A new chain: the body at the origin of this run, in the attitude of its first pair.
        vo_.reset();
        vo_anchor_ = vo_last_set_ = Pose3{};
        vo_interval_inliers_ = 0;
        vo_mode_start_ns_ = nav_now_ns_;
        vo_prev_dr_valid_ = false;
        vo_chain_started_ = false;
      }
      if (why == ModeReject::kNone) {
        mode_ = cmd.mode;
        reverse_ = cmd.reverse;
        route_id_ = uses_route ? id : route_id_;  // the dead reckoning runs on across modes: poses depend on the samples only
      } else {
        mode_ = qc::Mode::kIdle;  // the old mode was left: a defined state
      }
    }
  }
  last_reject_ = why;
  if (why != ModeReject::kNone) ++mode_refused_;
  if (log_ && cfg_.log != LogFormat::kOff)
    std::fprintf(log_, "{\"event\":\"mode\",\"t_s\":%.3f,\"cmd\":\"%s\",\"reverse\":%s,\"route_id\":%u,\"state\":\"%s\",\"refused\":%s%s%s}\n",
                 static_cast<double>(nav_now_ns_ - start_ns_) * 1e-9, qc::mode_name(cmd.mode), cmd.reverse ? "true" : "false", id, qc::mode_name(mode_),
                 why == ModeReject::kNone ? "false" : "\"", why == ModeReject::kNone ? "" : to_string(why), why == ModeReject::kNone ? "" : "\"");
  stage_time(Stage::kModes, t0);
  mode_ns_ += cpu_clock_.now_ns() - t0;
}

void NavWorker::handle_ping(const PingMsg& p) noexcept {
  const std::int64_t t0 = cpu_clock_.now_ns();
  ++pings_;
  // A ping stamped at or before the previous one (a clock stepped back, a duplicate, a reordered
  // delivery) cannot be placed on the dead-reckoned track: counted and dropped.
  if (last_ping_ns_ >= 0 && p.stamp.sample_ns <= last_ping_ns_) {
    ++pings_out_of_order_;
    return;
  }
  last_ping_ns_ = p.stamp.sample_ns;
  if (mode_ != qc::Mode::kTeach && mode_ != qc::Mode::kRepeat) return;
  if (!dr_.has_heading() || dr_.heading_age_s(p.stamp.sample_ns) > cfg_.attitude_stale_s) return;  // no tiles without a heading
  if (mode_ == qc::Mode::kTeach && cfg_.dvl_enabled && dr_.velocity_age_s(p.stamp.sample_ns) > cfg_.dvl_stale_s) {
    ++teach_no_odometry_;  // a taught node needs its true place: none is built while the DVL is lost
    return;
  }
  const std::size_t half = q_.ping_pool_stride / 2;
  if (!QNAVD_CHECK(p.port_samples <= half && p.stbd_samples <= half, "ping larger than its pool slot")) return;
  const float* base = q_.ping_pool + static_cast<std::size_t>(p.slot) * q_.ping_pool_stride;
  sonar::SonarPing ping;
  ping.stamp_ns = static_cast<std::uint64_t>(p.stamp.sample_ns);
  ping.ping_number = pass_ping_++;
  ping.port = Span<const float>(base, p.port_samples);
  ping.stbd = Span<const float>(base + half, p.stbd_samples);
  ping.slant_range_m = p.slant_range_m;
  ping.altitude_m = p.altitude_m;
  const Pose2 nav = dr_.pose_at(p.stamp.sample_ns);
  ping_rx_cpu_ns_ = t0;
  report_.truth_along_m = -1.0;
  const std::uint32_t tiles_before = tile_seq_;
  Status s = p.has_truth ? tiles_.push_ping(ping, nav, p.truth, tile_sink_, nullptr) : tiles_.push_ping(ping, nav, tile_sink_, nullptr);
  QNAVD_CHECK(s.is_ok(), "tile pipeline refused a ping (its rejections are counted, not returned)");
  // The ping that completes a tile runs the whole tile stage (raster, features, teach append or
  // repeat update): it is timed against the tile budget, every other ping against the ping budget.
  stage_time(tile_seq_ != tiles_before ? Stage::kTile : Stage::kPing, t0);
}

void NavWorker::handle_pair(const FrameMsg& f) noexcept {
  const std::int64_t t0 = cpu_clock_.now_ns();
  ++frames_;
  // A pair (or a downward frame) stamped at or before the previous one of its camera cannot be a step
  // forward in time: counted, dropped. The two cameras are separate devices: each has its own order.
  std::int64_t& last_ns = f.downward ? last_downward_ns_ : last_frame_ns_;
  if (last_ns >= 0 && f.stamp.sample_ns <= last_ns) {
    ++frames_out_of_order_;
    return;
  }
  last_ns = f.stamp.sample_ns;
  if (f.downward) {
    handle_downward(f, t0);
    return;
  }
  if (mode_ != qc::Mode::kVo || !vo_ready_) return;
  const int W = cfg_.vo.max_width, H = cfg_.vo.max_height;
  if (!QNAVD_CHECK(f.width == W && f.height == H, "stereo pair of another size than its pool slot")) return;
  FrameReport& r = frame_report_;
  r = FrameReport{};
  r.seq = f.sequence;
  r.stamp_ns = f.stamp.sample_ns;
  r.has_truth = f.has_truth;
  r.truth_world_T_body = f.truth_world_T_body;
  r.truth_path_m = f.truth_path_m;
  const std::size_t n = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
  const std::uint8_t* left = frame_slot(f.slot);
  pipeline::VoFrameInput in;
  in.left = ConstImageViewU8::make(left, W, H).value();
  in.right = ConstImageViewU8::make(left + n, W, H).value();
  in.stamp_ns = static_cast<std::uint64_t>(f.stamp.sample_ns);
  // The newest attitude at or before the pair (inputs are taken up to its time), if not stale.
  if (have_att_ && f.stamp.sample_ns - att_ns_ <= static_cast<std::int64_t>(cfg_.attitude_stale_s * 1e9)) {
    in.has_attitude = true;
    in.world_R_body = att_R_;
  }
  // The DVL (or wheel odometry on the DVL's interface) as the translation prior: the dead-reckoned
  // displacement since the previous pair (level, 20 % + 2 cm).
  const bool odo = dr_.has_velocity() && dr_.velocity_age_s(f.stamp.sample_ns) <= cfg_.dvl_stale_s;
  const Pose2 dr_now = dr_.pose_at(f.stamp.sample_ns);
  if (odo && vo_prev_dr_valid_) {
    in.has_body_displacement = true;
    in.body_displacement_world_m = Vec3d(dr_now.x_m - vo_prev_dr_.x_m, dr_now.y_m - vo_prev_dr_.y_m, 0.0);
    in.displacement_sigma_m = 0.02 + 0.2 * in.body_displacement_world_m.norm();
  }
  vo_prev_dr_ = dr_now;
  vo_prev_dr_valid_ = odo;
  Result<vo::VoStep> step = vo_.step(in);
  if (!step) {
    ++vo_no_attitude_;  // 3D-VME needs the attitude: the pair is not processed (FaultAttitudeLost says why)
  } else {
    r.processed = true;
    r.flags = step->flags;
    r.visual = step->visual;
    r.inliers = static_cast<std::uint32_t>(step->visual ? step->matches : 0);
    if (vo_chain_started_) {
      publish_vo_increment(r.inliers);
    } else {
      // The chain's first pair fixes the body's attitude: increments are measured from here.
      vo_anchor_ = vo_last_set_ = vo_.body_pose();
      vo_chain_started_ = true;
    }
  }
  r.world_T_body = vo_.body_pose();
  stage_time(Stage::kVo, t0);
  r.latency_ms = static_cast<double>(cpu_clock_.now_ns() - t0) * 1e-6;
  if (log_ && cfg_.log == LogFormat::kJson) {
    const Vec3d& p = r.world_T_body.t;
    const Vec3d tp = r.has_truth ? r.truth_world_T_body.t : Vec3d::Zero();
    std::fprintf(log_,
                 "{\"event\":\"vo\",\"seq\":%u,\"t_s\":%.1f,\"processed\":%s,\"visual\":%s,\"flags\":%u,\"inliers\":%u,"
                 "\"north_m\":%.4f,\"east_m\":%.4f,\"down_m\":%.4f,\"truth_north_m\":%.4f,\"truth_east_m\":%.4f,\"truth_path_m\":%.3f,"
                 "\"latency_ms\":%.2f}\n",
                 r.seq, static_cast<double>(nav_now_ns_ - start_ns_) * 1e-9, r.processed ? "true" : "false", r.visual ? "true" : "false",
                 r.flags, r.inliers, p.x(), p.y(), p.z(), tp.x(), tp.y(), r.truth_path_m, r.latency_ms);
  } else if (log_ && cfg_.log == LogFormat::kKeyValue) {
    std::fprintf(log_, "vo seq=%u processed=%d visual=%d inliers=%u north_m=%.3f east_m=%.3f\n", r.seq, r.processed ? 1 : 0,
                 r.visual ? 1 : 0, r.inliers, r.world_T_body.t.x(), r.world_T_body.t.y());
  }
  if (frame_observer_) frame_observer_(frame_ctx_, r);
}

const std::uint8_t* NavWorker::frame_slot(std::uint32_t slot) const noexcept {
  const std::size_t bytes = q_.frame_slot_bytes != 0
                                ? q_.frame_slot_bytes
                                : 2 * static_cast<std::size_t>(cfg_.vo.max_width) * static_cast<std::size_t>(cfg_.vo.max_height);
  return q_.frame_pool + static_cast<std::size_t>(slot) * bytes;
}

// Mode = Map: a new map (the mapper re-initialised in its arena: no heap), written to
// route_dir/map_<id>.qmap from its first node on; the file of an earlier map with this id stays whole
// until then (save_map: temporary file + fsync + rename).
ModeReject NavWorker::enter_map(std::uint16_t id) noexcept {
  map_arena_->reset();
  if (!mapper_.init(map_mapper_config(cfg_), *map_arena_)) return ModeReject::kUnsupportedMode;  // cannot happen: init sized it
  std::snprintf(map_path_, sizeof map_path_, "%s/map_%u.qmap", cfg_.route_dir.c_str(), static_cast<unsigned>(id));
  map_open_ = true;
  map_node_ = topo::kNoNode;
  map_mode_start_ns_ = nav_now_ns_;
  return ModeReject::kNone;
}

void NavWorker::save_map() noexcept {
  const Status s = drivers::map_store::save_map(store_, map_path_, mapper_.map(), mapper_.metric());
  ++map_saves_;
  if (!s) {
    ++map_save_errors_;
    ++writer_errors_;
    if (log_) std::fprintf(log_, "{\"event\":\"error\",\"what\":\"map: %s not saved: %s\"}\n", map_path_, s.message());
  }
}

// One downward frame through the shared mapper (pipeline::TopoMapper, as `qnav map` runs it). A frame
// the chain refuses leaves the pose and the map as they were (counted, logged with its reason).
void NavWorker::handle_downward(const FrameMsg& f, std::int64_t t0) noexcept {
  if (mode_ != qc::Mode::kMap || !map_ready_) return;
  if (!QNAVD_CHECK(f.width == cfg_.map_width && f.height == cfg_.map_height, "downward frame of another size than map.width x map.height"))
    return;
  ++map_frames_;
  const ConstImageViewU8 img = ConstImageViewU8::make(frame_slot(f.slot), cfg_.map_width, cfg_.map_height).value();
  pipeline::MapperStep& st = map_step_;
  const Status s = mapper_.step(img, cfg_.map_altitude_m > 0.0 ? cfg_.map_altitude_m : -1.0, st);
  if (!s) ++step_errors_;
  if (st.chain.status != topo::StepStatus::kOk) ++map_bad_frames_;
  if (st.observed && st.place.kind == topo::ObserveKind::kCreated) save_map();  // durable as it grows
  publish_map_frame(f, st);
  stage_time(Stage::kMap, t0);
  log_map_frame(f, st, static_cast<double>(cpu_clock_.now_ns() - t0) * 1e-6);
}

// QNAV_MAP_POSE + QNAV_MAP_STATUS for this frame (sent once, at this step's publish()).
void NavWorker::publish_map_frame(const FrameMsg& f, const pipeline::MapperStep& st) noexcept {
  const topo::ChainStep& c = st.chain;
  if (st.observed && st.place.node != topo::kNoNode) map_node_ = st.place.node;
  qc::MapPose p;
  const Vec2d& pos = c.pose.metric ? c.pose.position_m : c.pose.position_px;
  p.x = qc::clamp_to_signal(qc::kIdMapPose, "X", pos.x());
  p.y = qc::clamp_to_signal(qc::kIdMapPose, "Y", pos.y());
  p.heading_rad = qc::clamp_to_signal(qc::kIdMapPose, "Heading", std::remainder(c.pose.heading_rad, 2.0 * kPi));
  qc::MapStatus m;
  static_assert(topo::kNoNode == qc::kMapNoNode, "no node: the same value in the map and on the wire");
  m.node_id = map_node_;  // map.max_nodes <= 65534: a node id is below 65535
  m.node_count = static_cast<std::uint16_t>(std::min<std::size_t>(mapper_.map().node_count(), 65535));
  m.frame_seq = static_cast<std::uint16_t>(f.sequence & 0xFFFFu);
  m.registered = c.status == topo::StepStatus::kOk;
  const bool bad = c.status == topo::StepStatus::kBadInput;
  m.black = bad && (c.bad_input & topo::kFrameDark) != 0;
  m.saturated = bad && (c.bad_input & topo::kFrameSaturated) != 0;
  m.textureless = bad && (c.bad_input & topo::kFrameTextureless) != 0;
  m.lost = !m.registered && !bad;
  m.metric = c.pose.metric;
  m.new_node = st.observed && st.place.kind == topo::ObserveKind::kCreated;
  m.revisit = st.observed && st.place.revisit;
  publisher_->set(p);
  publisher_->set(m);
}

void NavWorker::log_map_frame(const FrameMsg& f, const pipeline::MapperStep& st, double latency_ms) noexcept {
  const topo::ChainStep& c = st.chain;
  if (log_ && cfg_.log == LogFormat::kJson) {
    std::fprintf(log_,
                 "{\"event\":\"map\",\"seq\":%u,\"t_s\":%.3f,\"status\":\"%s\",\"bad_input\":%u,\"keyframe\":%u,\"new_keyframe\":%s,"
                 "\"keypoints\":%u,\"inliers\":%u,\"x_px\":%.4f,\"y_px\":%.4f,\"heading_deg\":%.5f,\"metric\":%s,\"x_m\":%.5f,"
                 "\"y_m\":%.5f,\"node\":%d,\"kind\":\"%s\",\"revisit\":%s,\"nodes\":%zu,\"edges\":%zu,\"latency_ms\":%.2f}\n",
                 f.sequence, static_cast<double>(nav_now_ns_ - start_ns_) * 1e-9, topo::to_string(c.status), c.bad_input, c.keyframe_index,
                 c.new_keyframe ? "true" : "false", c.keypoints, c.inliers, c.pose.position_px.x(), c.pose.position_px.y(),
                 rad_to_deg(c.pose.heading_rad), c.pose.metric ? "true" : "false", c.pose.position_m.x(), c.pose.position_m.y(),
                 st.observed && st.place.node != topo::kNoNode ? static_cast<int>(st.place.node) : -1,
                 st.observed ? topo::to_string(st.place.kind) : "none", st.observed && st.place.revisit ? "true" : "false",
                 mapper_.map().node_count(), mapper_.map().edge_count(), latency_ms);
  } else if (log_ && cfg_.log == LogFormat::kKeyValue) {
    std::fprintf(log_, "map seq=%u status=%s x_px=%.2f y_px=%.2f heading_deg=%.2f nodes=%zu\n", f.sequence, topo::to_string(c.status),
                 c.pose.position_px.x(), c.pose.position_px.y(), rad_to_deg(c.pose.heading_rad), mapper_.map().node_count());
  }
}

// QNAV_VO_STEP carries the motion since the last one sent: while the publisher still holds the last
// value, this step is added to it (the increment grows from the same anchor); once it went out, a
// new increment starts where that one ended.
void NavWorker::publish_vo_increment(std::uint32_t inliers) noexcept {
  if (!publisher_->vo_pending()) {
    vo_anchor_ = vo_last_set_;
    vo_interval_inliers_ = inliers;
  } else {
    vo_interval_inliers_ = std::min(vo_interval_inliers_, inliers);
  }
  vo_last_set_ = vo_.body_pose();
  const pipeline::PlanarIncrement inc = pipeline::planar_increment(vo_anchor_, vo_last_set_);
  qc::VoStep m;
  m.dx_m = qc::clamp_to_signal(qc::kIdVoStep, "Dx", inc.forward_m);
  m.dy_m = qc::clamp_to_signal(qc::kIdVoStep, "Dy", inc.right_m);
  m.dyaw_rad = qc::clamp_to_signal(qc::kIdVoStep, "Dyaw", inc.yaw_rad);
  m.inliers = static_cast<std::uint8_t>(std::min<std::uint32_t>(vo_interval_inliers_, 255));
  publisher_->set(m);
}

bool NavWorker::on_tile(const pipeline::RouteTile& t) noexcept {
  TileReport& r = report_;
  r = TileReport{};
  r.seq = tile_seq_++;
  r.mode = mode_;
  r.reverse = reverse_;
  r.route_id = route_id_;
  r.nav_step_m = t.nav_step_m;
  r.truth_along_m = t.truth_along_m;
  r.truth_lateral_m = t.truth_lateral_m;
  r.stamp_ns = static_cast<std::int64_t>(t.node.meta.stamp_ns);
  if (mode_ == qc::Mode::kTeach && teach_open_ && !teach_stopped_) {
    r.node_written = writer_.node_count();
    const Status s = writer_.append(t.node);
    if (!s) {
      // A node that could not be made durable (a full disk, a failing medium) ends this route at the
      // last durable node: appending later nodes would leave a gap the repeat pass cannot tell from
      // the place. The daemon keeps navigating; the route is committed as it is when teaching ends.
      ++writer_errors_;
      teach_stopped_ = true;
      if (log_)
        std::fprintf(log_, "{\"event\":\"teach_stopped\",\"route_id\":%u,\"nodes_durable\":%u,\"why\":\"%s\"}\n", route_id_,
                     writer_.node_count(), s.message());
    }
  } else if (mode_ == qc::Mode::kRepeat) {
    const bool first = t.tile_index == 0;
    // Judged at the tile's last ping (sample time), not at "now": the same data gives the same answer.
    const bool dvl_lost = !dr_.has_velocity() || dr_.velocity_age_s(last_ping_ns_) > cfg_.dvl_stale_s;
    if (dvl_lost != eq5_) {
      eq5_ = dvl_lost;
      repeater_.set_motion(reverse_ ? route::RouteDirection::kReverse : route::RouteDirection::kForward,
                           eq5_ ? route::MotionModel::kPaperEq5 : route::MotionModel::kOdometry);
    }
    r.eq5_motion = eq5_;
    const Status s = repeater_.step(t.node, first ? 0.0 : t.nav_step_m, r.step);
    if (!s) {
      ++step_errors_;
      r.step = route::LocaliserStep{};
      r.step.guidance.status = route::GuidanceStatus::kHoldCourse;
      r.step.guidance.side = route::RouteSide::kUnknown;
    }
    const route::GuidanceOutput& g = r.step.guidance;
    // The next node in the direction of travel is one spacing ahead of the node the offsets refer to
    // (the taught nodes' own spacing, as the localiser's motion model uses it); values in the DBC ranges.
    pipeline::route_can_messages(r.step, repeater_.localiser().node_spacing_m(), r.seq, guidance_, route_status_);
    publisher_->set(guidance_);
    publisher_->set(route_status_);
    if (mav_) route_fix(t, g, r.step.confident);
  }
  r.latency_ms = static_cast<double>(cpu_clock_.now_ns() - ping_rx_cpu_ns_) * 1e-6;
  if (log_ && cfg_.log == LogFormat::kJson) {
    const route::LocaliserStep& st = r.step;
    std::fprintf(log_,
                 "{\"event\":\"tile\",\"seq\":%u,\"t_s\":%.1f,\"mode\":\"%s\",\"route_id\":%u,\"node_written\":%d,\"estimate\":%u,\"p\":%.3f,"
                 "\"entropy\":%.3f,\"inliers\":%u,\"status\":\"%s\",\"side\":\"%s\",\"cross_track_m\":%.2f,\"sigma_m\":%.2f,\"eq5\":%s,"
                 "\"reverse\":%s,\"truth_along_m\":%.1f,\"truth_lateral_m\":%.2f,\"latency_ms\":%.2f}\n",
                 r.seq, static_cast<double>(nav_now_ns_ - start_ns_) * 1e-9, qc::mode_name(r.mode), r.route_id,
                 r.mode == qc::Mode::kTeach ? static_cast<int>(r.node_written) : -1, st.estimate, static_cast<double>(st.probability), st.entropy,
                 st.best_inliers, r.mode == qc::Mode::kRepeat ? route::to_string(st.guidance.status) : "-",
                 r.mode == qc::Mode::kRepeat ? route::to_string(st.guidance.side) : "-", st.guidance.cross_track_m, st.guidance.cross_track_sigma_m,
                 r.eq5_motion ? "true" : "false", r.reverse ? "true" : "false", r.truth_along_m, r.truth_lateral_m, r.latency_ms);
  } else if (log_ && cfg_.log == LogFormat::kKeyValue) {
    std::fprintf(log_, "tile seq=%u mode=%s estimate=%u status=%s side=%s cross_track_m=%.2f sigma_m=%.2f\n", r.seq, qc::mode_name(r.mode),
                 r.step.estimate, route::to_string(r.step.guidance.status), route::to_string(r.step.guidance.side), r.step.guidance.cross_track_m,
                 r.step.guidance.cross_track_sigma_m);
  }
  if (observer_) observer_(observer_ctx_, r);
  return true;
}

void NavWorker::update_faults() noexcept {
  std::uint16_t f = faults_ & qc::fault::kRouteDamaged;
  // The sonar is not used in Mode = Vo or Mode = Map, the cameras only there: each is lost only where
  // it is used (a camera-only survey with the sonar off raises no sonar fault).
  const bool sonar_lost = mode_ != qc::Mode::kVo && mode_ != qc::Mode::kMap &&
                          (last_ping_ns_ < 0 ? (nav_now_ns_ - start_ns_) > static_cast<std::int64_t>(cfg_.sonar_stale_s * kNsPerS)
                                             : (nav_now_ns_ - last_ping_ns_) > static_cast<std::int64_t>(cfg_.sonar_stale_s * kNsPerS));
  const std::int64_t last_pair_ns = std::max(last_frame_ns_, vo_mode_start_ns_);
  const bool camera_lost = (mode_ == qc::Mode::kVo && (nav_now_ns_ - last_pair_ns > static_cast<std::int64_t>(cfg_.vo_stale_s * kNsPerS) ||
                                                       q_.io->camera_device_down.load(std::memory_order_relaxed))) ||
                           (mode_ == qc::Mode::kMap &&
                            (nav_now_ns_ - std::max(last_downward_ns_, map_mode_start_ns_) > static_cast<std::int64_t>(cfg_.map_stale_s * kNsPerS) ||
                             q_.io->downward_device_down.load(std::memory_order_relaxed)));
  const bool att_lost = dr_.heading_age_s(nav_now_ns_) > cfg_.attitude_stale_s;
  const bool dvl_lost = cfg_.dvl_enabled && dr_.velocity_age_s(nav_now_ns_) > cfg_.dvl_stale_s;
  if (sonar_lost) f |= qc::fault::kSonarLost;
  if (att_lost) f |= qc::fault::kAttitudeLost;
  if (dvl_lost) f |= qc::fault::kDvlLost;
  if (camera_lost) f |= qc::fault::kCameraLost;
  if (sonar_lost || att_lost || dvl_lost || camera_lost) f |= qc::fault::kSensorTimeout;
  if (bus_off_ || q_.io->can_device_down.load(std::memory_order_relaxed)) f |= qc::fault::kBusOff;
  if (deadline_misses_ > 0) f |= qc::fault::kDeadlineMiss;
  if (SoftwareFaults::count() > 0) f |= qc::fault::kSoftware;
  // The leak detector is latched by the io thread (drivers/camera LeakMonitor); a configured detector
  // whose line cannot be read is a sensor that does not report.
  const bool leak = q_.io->leak.load(std::memory_order_relaxed);
  if (leak) f |= qc::fault::kLeak;
  if (q_.io->leak_device_down.load(std::memory_order_relaxed)) f |= qc::fault::kSensorTimeout;
  if (leak && !leak_logged_ && log_ && cfg_.log != LogFormat::kOff) {
    std::fprintf(log_, "{\"event\":\"leak\",\"t_s\":%.3f,\"edges\":%u}\n", static_cast<double>(nav_now_ns_ - start_ns_) * 1e-9,
                 q_.io->leak_events.load(std::memory_order_relaxed));
    leak_logged_ = true;
  }
  faults_ = f;
  // Degraded repeat: without sonar or heading there is no fix; the autopilot is told to hold course.
  if (mode_ == qc::Mode::kRepeat && (sonar_lost || att_lost)) {
    route_status_.status = qc::GuidanceState::kHoldCourse;
    route_status_.side = qc::SideOfRoute::kUnknown;
    route_status_.cross_track_sigma_m = qc::kCrossTrackSigmaMaxM;
    publisher_->set(route_status_);
  }
  if (mode_ != qc::Mode::kRepeat) {
    route_status_ = qc::RouteStatus{};
    route_status_.tile_seq = static_cast<std::uint16_t>(tile_seq_ & 0xFFFF);
    publisher_->set(route_status_);
  }
}

void NavWorker::publish() noexcept {
  qc::NavStatus ns;
  ns.state = mode_;
  const bool fix_possible = mode_ == qc::Mode::kRepeat && !(faults_ & (qc::fault::kSonarLost | qc::fault::kAttitudeLost));
  ns.localised = fix_possible && report_.step.confident;
  ns.confidence_pct = fix_possible ? qc::clamp_to_signal(qc::kIdNavStatus, "Confidence", 100.0 * static_cast<double>(report_.step.probability)) : 0.0;
  ns.node_index = static_cast<std::uint16_t>(std::min<std::uint32_t>(mode_ == qc::Mode::kTeach ? writer_.node_count() : report_.step.estimate, 65535));
  ns.fault_flags = faults_;
  ns.mode_reject = static_cast<std::uint8_t>(last_reject_);
  publisher_->set(ns);
  qc::Health h;
  h.fault_flags = faults_;
  std::uint64_t rejected = 0;
  // Input qnav should have understood and refused; frames for other nodes (unknown_id, other_node)
  // are not rejections.
  for (std::size_t i = 0; i < static_cast<std::size_t>(qc::RxCounter::kCount); ++i)
    if (static_cast<qc::RxCounter>(i) != qc::RxCounter::kUnknownId) rejected += receiver_.counters().get(static_cast<qc::RxCounter>(i));
  rejected += ahrs_.counters().total() - ahrs_.counters().get(drivers::dronecan::AhrsCounter::kOtherNode);
  rejected += q_.io->dvl_rejected.load(std::memory_order_relaxed) + q_.io->sonar_rejected.load(std::memory_order_relaxed) + dr_rejected_;
  rejected += q_.io->can_rx_overflow.load(std::memory_order_relaxed) + q_.io->ping_overflow.load(std::memory_order_relaxed);
  rejected += q_.io->can_rx_dropped.load(std::memory_order_relaxed);
  rejected += pings_rejected() + pings_out_of_order_;
  rejected += q_.io->frame_overflow.load(std::memory_order_relaxed) + q_.io->camera_rejected.load(std::memory_order_relaxed) + frames_out_of_order_;
  if (mav_) rejected += mav_->rejected() + q_.io->mav_rx_overflow.load(std::memory_order_relaxed);
  h.rejected_inputs = static_cast<std::uint16_t>(std::min<std::uint64_t>(rejected, 65535));
  h.deadline_misses = static_cast<std::uint16_t>(std::min<std::uint32_t>(deadline_misses_, 65535));
  h.cpu_load_pct = qc::clamp_to_signal(qc::kIdHealth, "CpuLoad", cpu_load_pct_);
  h.bus_off = bus_off_ || q_.io->can_device_down.load(std::memory_order_relaxed);
  h.leak = (faults_ & qc::fault::kLeak) != 0;
  publisher_->set(h);
  qc::Heartbeat hb;
  hb.uptime_s = static_cast<std::uint32_t>(std::max<std::int64_t>(0, nav_now_ns_ - start_ns_) / kNsPerS);
  hb.state = mode_;
  hb.sw_major = 0;
  hb.sw_minor = 1;
  publisher_->set(hb);
  publisher_->poll(nav_now_ns_);
  if (mav_) mavlink_publish();
}

// ---- MAVLink (mavlink_endpoint.hpp) ----

void NavWorker::mavlink_inputs() noexcept {
  // At most a few commands per loop (each may open a route file); the rest waits for the next loop.
  for (int i = 0; i < 4; ++i) {
    const MavInputs in = mav_->drain(*q_.mav_rx);
    if (in.attitude) {  // the autopilot's ATTITUDE: an attitude source like the CAN AHRS
      double yaw = in.yaw_rad;
      if (yaw < 0.0) yaw += 2.0 * 3.14159265358979323846;
      if (!dr_.on_heading(in.attitude_ns, yaw)) ++dr_rejected_;
      att_R_ = rotation_from_rpy(in.roll_rad, in.pitch_rad, yaw);
      att_ns_ = in.attitude_ns;
      have_att_ = true;
      nav_now_ns_ = std::max(nav_now_ns_, in.attitude_ns);
    }
    if (!in.mode_cmd) break;
    handle_mode(in.cmd);
    mav_->ack(last_reject_ == ModeReject::kNone, to_string(last_reject_), *q_.mav_tx);
  }
}

// A route fix: the taught node's position (route frame) plus the registered along- and cross-track
// offsets is where the tile's centre was; the vehicle has dead-reckoned on from there since.
void NavWorker::route_fix(const pipeline::RouteTile& t, const route::GuidanceOutput& g, bool confident) noexcept {
  guidance_valid_ = g.status != route::GuidanceStatus::kHoldCourse && g.offsets != route::OffsetSource::kNone;
  waypoint_ne_ = g.waypoint_ne;
  if (!confident || g.offsets != route::OffsetSource::kRegistration || g.node >= meta_.size()) return;
  const Vec2d at_tile = pipeline::NavEstimate::route_fix_position(meta_[g.node], reverse_, g.along_track_m, g.cross_track_m);
  const Pose2 dr_now = dr_.pose_at(nav_now_ns_);
  const Pose2& dr_tile = t.node.meta.pose;
  est_.apply_fix(at_tile.x() + (dr_now.x_m - dr_tile.x_m), at_tile.y() + (dr_now.y_m - dr_tile.y_m));
  est_.rebase();  // tracked from this instant on
  est_.track(dr_now);
  route_fix_ = true;
}

void NavWorker::mavlink_publish() noexcept {
  const bool on_vo = mode_ == qc::Mode::kVo;
  if (on_vo != est_on_vo_) {
    est_.rebase();
    est_on_vo_ = on_vo;
  }
  if (on_vo) {
    if (vo_chain_started_) {
      const Vec3d p = vo_.body_pose().t;
      est_.track(Pose2{p.x(), p.y(), 0.0});
    }
  } else {
    est_.track(dr_.pose_at(nav_now_ns_));
  }
  qc::Stamped<qc::DepthIn> depth;  // z: the vehicle's depth sensor (QNAV_DEPTH_IN), absolute
  if (receiver_.latest_depth(nav_now_ns_, static_cast<std::int64_t>(cfg_.depth_stale_s * 1e9), depth) && depth.value.depth_valid)
    est_.set_down(depth.value.depth_m);
  MavSnapshot s;
  s.now_ns = nav_now_ns_;
  s.mode = mode_;
  s.faults = faults_;
  s.loss = (faults_ & (qc::fault::kDvlLost | qc::fault::kAttitudeLost)) != 0 || (on_vo && (faults_ & qc::fault::kCameraLost) != 0);
  s.have_attitude = have_att_ && !(faults_ & qc::fault::kAttitudeLost);
  s.world_R_body = att_R_;
  s.have_velocity = dr_.has_velocity() && !(faults_ & qc::fault::kDvlLost);
  s.vx_mps = dr_.forward_mps();
  s.vy_mps = dr_.starboard_mps();
  s.altitude_m = (faults_ & qc::fault::kDvlLost) ? -1.0 : dvl_altitude_m_;
  const bool fix_possible = mode_ == qc::Mode::kRepeat && !(faults_ & (qc::fault::kSonarLost | qc::fault::kAttitudeLost));
  s.localised = fix_possible && report_.step.confident;
  s.confidence_pct = fix_possible ? 100.0 * static_cast<double>(report_.step.probability) : 0.0;
  s.estimate = &est_;
  s.in_repeat = mode_ == qc::Mode::kRepeat;
  s.route_fix = route_fix_;
  s.guidance_valid = guidance_valid_ && fix_possible;
  s.cross_track_m = report_.step.guidance.cross_track_m;
  s.cross_track_sigma_m = report_.step.guidance.cross_track_sigma_m;
  s.side = static_cast<int>(report_.step.guidance.side);
  s.node = report_.step.guidance.node;
  s.waypoint_ne = waypoint_ne_;
  mav_->publish(s, *q_.mav_tx);
}

void NavWorker::log_health() noexcept {
  const std::int64_t now_cpu = cpu_clock_.now_ns();
  const std::int64_t window = now_cpu - busy_window_start_ns_;
  if (window > 0) cpu_load_pct_ = 100.0 * static_cast<double>(busy_ns_) / static_cast<double>(window);
  busy_ns_ = 0;
  busy_window_start_ns_ = now_cpu;
  if (!log_ || cfg_.log == LogFormat::kOff) return;
  const IoCounters& io = *q_.io;
  std::fprintf(log_,
               "{\"event\":\"health\",\"t_s\":%.1f,\"mode\":\"%s\",\"faults\":%u,\"pings\":%u,\"tiles\":%u,\"deadline_misses\":%u,"
               "\"ping_max_us\":%" PRId64 ",\"tile_max_us\":%" PRId64 ",\"cpu_load_pct\":%.1f,\"can_rx_overflow\":%u,\"can_rx_dropped\":%u,\"can_tx_overflow\":%u,"
               "\"ping_overflow\":%u,\"dvl_rejected\":%u,\"sonar_rejected\":%u,\"device_errors\":%u,\"can_rejected\":%u,\"dr_rejected\":%u,"
               "\"mode_refused\":%u,\"step_errors\":%u,\"writer_errors\":%u,\"software_faults\":%u,\"dvl_overflow\":%u,\"can_tx_errors\":%u,"
               "\"teach_no_odometry\":%u,\"nav_resets\":%u,\"pings_rejected\":%u,\"pings_out_of_order\":%u,\"bus_off\":%s,"
               "\"frames\":%u,\"vo_frames\":%u,\"vo_visual\":%u,\"vo_no_attitude\":%u,\"frames_out_of_order\":%u,\"frame_overflow\":%u,"
               "\"camera_rejected\":%u,\"vo_max_us\":%" PRId64 ",\"map_frames\":%u,\"map_bad_frames\":%u,\"map_saves\":%u,"
               "\"map_save_errors\":%u,\"map_max_us\":%" PRId64 ","
               "\"misses\":{\"inputs\":%u,\"modes\":%u,\"ping\":%u,\"tile\":%u,\"vo\":%u,\"map\":%u,\"outputs\":%u}}\n",
               static_cast<double>(nav_now_ns_ - start_ns_) * 1e-9, qc::mode_name(mode_), faults_, pings_, tile_seq_, deadline_misses_,
               stage_max_ns_[static_cast<int>(Stage::kPing)] / 1000, stage_max_ns_[static_cast<int>(Stage::kTile)] / 1000, cpu_load_pct_,
               io.can_rx_overflow.load(), io.can_rx_dropped.load(), publisher_->counters().get(qc::TxCounter::kTxBusy), io.ping_overflow.load(), io.dvl_rejected.load(), io.sonar_rejected.load(),
               io.device_errors.load(), static_cast<unsigned>(receiver_.counters().total()), dr_rejected_, mode_refused_, step_errors_, writer_errors_,
               SoftwareFaults::count(), io.dvl_overflow.load(), io.can_tx_errors.load(), teach_no_odometry_, nav_resets_, pings_rejected(), pings_out_of_order_, bus_off_ ? "true" : "false",
               frames_, vo_.frames(), vo_.visual_steps(), vo_no_attitude_, frames_out_of_order_, io.frame_overflow.load(), io.camera_rejected.load(),
               stage_max_ns_[static_cast<int>(Stage::kVo)] / 1000, map_frames_, map_bad_frames_, map_saves_, map_save_errors_,
               stage_max_ns_[static_cast<int>(Stage::kMap)] / 1000, stage_misses_[static_cast<int>(Stage::kInputs)],
               stage_misses_[static_cast<int>(Stage::kModes)], stage_misses_[static_cast<int>(Stage::kPing)],
               stage_misses_[static_cast<int>(Stage::kTile)], stage_misses_[static_cast<int>(Stage::kVo)],
               stage_misses_[static_cast<int>(Stage::kMap)], stage_misses_[static_cast<int>(Stage::kOutputs)]);
  if (mav_) {
    const auto& mc = mav_->counters();
    std::fprintf(log_,
                 "{\"event\":\"mavlink\",\"t_s\":%.1f,\"frames_rx\":%u,\"odometry_sent\":%u,\"commands_accepted\":%u,\"targets_sent\":%u,"
                 "\"reset_counter\":%u,\"fixes\":%u,\"parser_rejects\":%u,\"rx_overflow\":%u,\"tx_errors\":%u,\"device_errors\":%u,"
                 "\"foreign_system\":%u,\"unused_message\":%u,\"cmd_wrong_sender\":%u,\"cmd_not_for_us\":%u,\"cmd_unsupported\":%u,"
                 "\"cmd_bad_param\":%u,\"bad_attitude\":%u,\"tx_queue_full\":%u}\n",
                 static_cast<double>(nav_now_ns_ - start_ns_) * 1e-9, mav_->frames_rx(), mav_->odometry_sent(), mav_->commands_accepted(),
                 mav_->targets_sent(), est_.reset_counter(), est_.fixes(), mav_->parser_rejects(), io.mav_rx_overflow.load(), io.mav_tx_errors.load(),
                 io.mav_device_errors.load(), mc.get(MavCounter::kForeignSystem), mc.get(MavCounter::kUnusedMessage),
                 mc.get(MavCounter::kCmdWrongSender), mc.get(MavCounter::kCmdNotForUs), mc.get(MavCounter::kCmdUnsupported),
                 mc.get(MavCounter::kCmdBadParam), mc.get(MavCounter::kBadAttitude), mc.get(MavCounter::kTxQueueFull));
  }
  const std::uint32_t sw = SoftwareFaults::count();
  if (sw != software_faults_logged_) {
    const SoftwareFaultRecord r = SoftwareFaults::last();
    std::fprintf(log_, "{\"event\":\"software_fault\",\"count\":%u,\"last\":\"%s\",\"at\":\"%s:%d\"}\n", sw, r.what ? r.what : "?",
                 r.file ? r.file : "?", r.line);
    software_faults_logged_ = sw;
  }
  std::fflush(log_);
}

void NavWorker::shutdown() noexcept {
  if (shut_) return;
  leave_mode();
  log_health();  // the final counters
  mode_ = qc::Mode::kIdle;
  shut_ = true;
}

}  // namespace qnav::daemon
