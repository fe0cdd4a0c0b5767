#include "firmware/qnavd/sim_vehicle.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "drivers/dronecan/ahrs.hpp"
#include "drivers/dronecan/transfer.hpp"
#include "drivers/dvl/wl_parser.hpp"
#include "firmware/pipeline/dead_reckoner.hpp"
#include "firmware/qnavd/sim_closed_loop.hpp"
#include "firmware/tools/image_reader.hpp"
#include "firmware/tools/sonar_file.hpp"
#include "hal/core/candump.hpp"
#include "nav/core/geometry.hpp"

namespace qnav::daemon {

namespace qc = drivers::qnavcan;

namespace {
constexpr std::int64_t kIdleTickNs = 100000000;      // the AHRS streams between passes (10 Hz)
constexpr std::int64_t kStateTimeoutNs = 5000000000;  // 5 s of mission time for NAV_STATUS to confirm
constexpr double kTwoPi = 6.283185307179586;
}  // namespace

SimVehicle::SimVehicle(const DaemonConfig& config, SimClock& clock, hal::Clock& wall) noexcept
    : cfg_(config), clock_(clock), pacer_(wall, config.sim_speed) {}

SimVehicle::~SimVehicle() {
  if (candump_) std::fclose(candump_);
}

bool SimVehicle::stalled(const char* sensor, std::int64_t t_ns) const noexcept {
  if (cfg_.sim_stall != sensor || static_cast<int>(pass_) != cfg_.sim_stall_pass) return false;
  const double since_s = static_cast<double>(t_ns - pass_start_ns_) * 1e-9;
  return since_s >= cfg_.sim_stall_start_s && since_s < cfg_.sim_stall_start_s + cfg_.sim_stall_s;
}

bool SimVehicle::faulty(const char* kind, std::int64_t t_ns) const noexcept {
  if (cfg_.sim_fault != kind || static_cast<int>(pass_) != cfg_.sim_fault_pass || phase_ != Phase::kFly) return false;
  const double since_s = static_cast<double>(t_ns - pass_start_ns_) * 1e-9;
  return since_s >= cfg_.sim_fault_start_s && since_s < cfg_.sim_fault_start_s + cfg_.sim_fault_s;
}

// Once per ping instant: error frames on the bus, bus-off and its restart, the disk filling up.
void SimVehicle::inject_bus_faults(std::int64_t t) noexcept {
  const std::uint8_t data[8] = {};
  if (net_ != nullptr && faulty("can_error_frames", t)) {
    net_->inject_error(hal::can_error::kProtocol | hal::can_error::kBusError, data);
    io_->faults_injected.fetch_add(1, std::memory_order_relaxed);
  }
  if (net_ != nullptr && cfg_.sim_fault == "can_bus_off") {
    const bool off = faulty("can_bus_off", t);
    if (off && !bus_off_) {
      net_->inject_error(hal::can_error::kBusOff, data);
      io_->faults_injected.fetch_add(1, std::memory_order_relaxed);
    } else if (!off && bus_off_) {
      net_->inject_error(hal::can_error::kRestarted, data);
    }
    bus_off_ = off;
  }
  if (leak_line_ != nullptr && cfg_.sim_fault == "leak") {  // water at the detector for the window
    const bool wet = faulty("leak", t);
    if (wet != wet_) {
      leak_line_->inject_level(wet, t);
      if (wet) io_->faults_injected.fetch_add(1, std::memory_order_relaxed);
      wet_ = wet;
    }
  }
  if (store_ != nullptr && cfg_.sim_fault == "disk_full") {
    const bool full = faulty("disk_full", t);
    if (full && !store_->full()) io_->faults_injected.fetch_add(1, std::memory_order_relaxed);
    store_->set_full(full);
  }
}

void SimVehicle::record(const hal::CanFrame& f, std::int64_t t_ns) noexcept {
  if (!candump_) return;
  hal::CanLogRecord r;
  r.frame = f;
  r.has_time = true;
  r.time_us = t_ns / 1000;
  // The interface the frames are on (sim.can_interface; names are at most 15 characters), else vcan0.
  const char* name = cfg_.sim_can_interface.empty() ? "vcan0" : cfg_.sim_can_interface.c_str();
  std::strncpy(r.interface, name, sizeof r.interface - 1);
  char line[hal::kMaxCanLogLine];
  if (hal::format_can_log_line(r, line, sizeof line) > 0) std::fprintf(candump_, "%s\n", line);
}

Status SimVehicle::init(hal::CanBus& autopilot, hal::SerialPort& dvl_out) {
  if (cfg_.mavlink_enabled && cfg_.mavlink_odometry_hz > 0.0) ahrs_tick_ns_ = static_cast<std::int64_t>(1e9 / cfg_.mavlink_odometry_hz);
  if (!cfg_.sim_candump.empty()) {
    candump_ = std::fopen(cfg_.sim_candump.c_str(), "w");
    if (!candump_) {
      std::fprintf(stderr, "qnavd: sim.candump %s: %s\n", cfg_.sim_candump.c_str(), std::strerror(errno));
      return Status(StatusCode::kIoError, "sim: cannot write sim.candump (see the line above)");
    }
  }
  bus_ = &autopilot;
  dvl_ = &dvl_out;
  survey_ = std::make_unique<pipeline::SimSurvey>();
  QNAV_RETURN_IF_ERROR(survey_->init(cfg_.sim_length_m, cfg_.sim_seed));
  sonar_ = std::make_unique<sidescan::SideScanSimulator>();
  QNAV_RETURN_IF_ERROR(sonar_->init(survey_->sonar, &survey_->seabed));  // sized here; each pass re-seeds it without allocating
  if (cfg_.sim_mission.size() == 0) return Status(StatusCode::kInvalidArgument, "sim: the mission has no [[sim.pass]]");
  recordings_.clear();
  sensors_.clear();
  map_files_.clear();
  map_synthetic_.clear();
  for (const SimPass& p : cfg_.sim_mission) {
    QNAV_RETURN_IF_ERROR(load_map_frames(p));
    QNAV_RETURN_IF_ERROR(load_sensors(p, sensors_.size()));
    // A stereo sequence replayed without its CAN log is a rig without an attitude sensor: the
    // simulated AHRS stays silent for the whole mission (the VO runs as `qnav vo --kitti` does).
    if (p.mode == qc::Mode::kVo && !p.images.empty() && p.candump.empty()) no_ahrs_ = true;
    // A recorded DVL stamps its sentences with its own clock: the simulated one (mission time) stays
    // silent between passes, or its sentences would step that clock back.
    if (!p.dvl_log.empty()) no_sim_dvl_ = true;
    if (p.mode == qc::Mode::kVo && p.images.empty() && !rover_) {
      if (frames_.frames == nullptr) return Status(StatusCode::kInvalidArgument, "sim: a vo pass needs vo.enabled (the frame pool)");
      if (frames_.width != SimRover().bench().width() || frames_.height != SimRover().bench().height())
        return Status(StatusCode::kInvalidArgument, "sim: the simulated stereo bench is 320 x 256: vo.width and vo.height must match");
      rover_ = std::make_unique<SimRover>();
    }
    std::unique_ptr<Recording> r;
    if (!p.file.empty()) {
      r = std::make_unique<Recording>();
      if (tools::load_sonar_file(p.file.c_str(), r->data) != 0 || r->data.pings.empty())
        return Status(StatusCode::kInvalidArgument, "sim: a [[sim.pass]] file cannot be read as XTF or JSF (see the message above)");
      r->track = tools::build_track(r->data, cfg_.sim_replay_nav == "dr", 0.0);
      tools::report_track("qnavd sim", p.file.c_str(), r->track);
    }
    recordings_.push_back(std::move(r));
  }
  for (const SimPass& p : cfg_.sim_mission) {
    if (!p.closed_loop || cl_) continue;
    cl_ = std::make_unique<ClosedLoopPass>();
    const std::size_t n = static_cast<std::size_t>(2.0 * cfg_.sim_length_m / ClosedLoopPass::kLogStepM) + 64;
    cl_->log.reserve(n);
    cl_->log_dist_m.reserve(n);
    if (!cfg_.sim_closed_loop_csv.empty()) {  // opened here: a bad path is a start-up error, not a skipped pass
      cl_->csv = std::fopen(cfg_.sim_closed_loop_csv.c_str(), "w");
      if (cl_->csv == nullptr) {
        std::fprintf(stderr, "qnavd: sim.closed_loop_csv %s: %s\n", cfg_.sim_closed_loop_csv.c_str(), std::strerror(errno));
        return Status(StatusCode::kIoError, "sim: cannot write sim.closed_loop_csv (see the line above)");
      }
      std::fprintf(cl_->csv, "seed,track,t_s,north_m,east_m,cross_track_m,along_m,travelled_m,mode,dvl_lost\n");
    }
  }
  phase_ = Phase::kCommand;
  next_idle_att_ns_ = clock_.now_ns();
  return Status::ok();
}

// A map pass's downward frames: the folder's file names (read one by one as the pass flies); the first
// must be map.width x map.height.
Status SimVehicle::load_map_frames(const SimPass& p) {
  map_files_.emplace_back();
  map_synthetic_.push_back(0);
  if (p.mode != qc::Mode::kMap) return Status::ok();
  if (frames_.frames == nullptr || frames_.map_width <= 0)
    return Status(StatusCode::kInvalidArgument, "sim: a map pass needs map.enabled (the frame pool)");
  if (p.images.empty()) {  // the synthetic seabed loop, rendered into the frame pool as the pass flies
    const sim::downward::Camera cam;
    if (frames_.map_width != cam.width || frames_.map_height != cam.height)
      return Status(StatusCode::kInvalidArgument, "sim: the synthetic seabed camera is 320 x 240: map.width and map.height must match");
    if (!seabed_) seabed_ = std::make_unique<sim::downward::Seabed>();
    map_synthetic_.back() = p.max_frames > 0 ? static_cast<std::size_t>(p.max_frames) : 120;
    return Status::ok();
  }
  std::vector<std::string>& files = map_files_.back();
  std::string err;
  if (!tools::list_image_files(p.images.c_str(), files, err) || files.size() < 2) {
    std::fprintf(stderr, "qnavd sim: sim.pass.images %s: %s\n", p.images.c_str(), err.empty() ? "fewer than two frames" : err.c_str());
    return Status(StatusCode::kInvalidArgument, "sim: the map pass's frame folder cannot be read (see the line above)");
  }
  if (p.max_frames > 0 && files.size() > static_cast<std::size_t>(p.max_frames)) files.resize(static_cast<std::size_t>(p.max_frames));
  const Result<ImageU8> first = tools::read_image_gray8(files.front().c_str());
  if (!first || first->width() != frames_.map_width || first->height() != frames_.map_height) {
    std::fprintf(stderr, "qnavd sim: sim.pass.images %s: the first frame %s is %s, map.width x map.height is %d x %d\n", p.images.c_str(),
                 files.front().c_str(), first ? (std::to_string(first->width()) + " x " + std::to_string(first->height())).c_str() : first.status().message(),
                 frames_.map_width, frames_.map_height);
    return Status(StatusCode::kInvalidArgument, "sim: map.width and map.height must be the size of the replayed frames (see the line above)");
  }
  std::fprintf(stderr, "qnavd sim: pass %zu maps %zu downward frames of %s\n", map_files_.size() - 1, files.size(), p.images.c_str());
  return Status::ok();
}

// A pass's recorded sensors (sim_replay.hpp), loaded whole here; a stereo sequence must fit the frame pool.
Status SimVehicle::load_sensors(const SimPass& p, std::size_t index) {
  if (p.mode == qc::Mode::kMap || (p.candump.empty() && p.dvl_log.empty() && p.images.empty())) {
    sensors_.push_back(nullptr);
    return Status::ok();
  }
  auto rs = std::make_unique<RecordedSensors>();
  if (!p.candump.empty()) QNAV_RETURN_IF_ERROR(rs->load_candump(p.candump));
  if (!p.dvl_log.empty()) QNAV_RETURN_IF_ERROR(rs->load_dvl(p.dvl_log, cfg_.dvl_protocol == "pd6"));
  if (!p.images.empty()) {
    if (frames_.frames == nullptr) return Status(StatusCode::kInvalidArgument, "sim: a vo pass needs vo.enabled (the frame pool)");
    QNAV_RETURN_IF_ERROR(rs->load_images(p.images, static_cast<std::size_t>(p.max_frames)));
    const Result<ImageU8> first = tools::read_image_gray8(rs->pairs.front().left_path.c_str());
    if (!first) {
      std::fprintf(stderr, "qnavd sim: sim.pass.images: %s: %s\n", rs->pairs.front().left_path.c_str(), first.status().message());
      return Status(StatusCode::kInvalidArgument, "sim: the stereo sequence's first image cannot be read (see the line above)");
    }
    if (first->width() != frames_.width || first->height() != frames_.height) {
      std::fprintf(stderr, "qnavd sim: sim.pass.images %s: the images are %d x %d, vo.width x vo.height is %d x %d\n", p.images.c_str(),
                   first->width(), first->height(), frames_.width, frames_.height);
      return Status(StatusCode::kInvalidArgument, "sim: vo.width and vo.height must be the size of the replayed images (see the line above)");
    }
  }
  std::fprintf(stderr, "qnavd sim: pass %zu replays %s\n", index, rs->what.c_str());
  sensors_.push_back(std::move(rs));
  return Status::ok();
}

// Recorded time -> mission time for the pass starting now: the earliest absolute sample of the pass's
// sources (its side-scan file's first ping included) at kPassLeadNs after now; sources with relative
// times start there too.
void SimVehicle::align_sensors() noexcept {
  const std::int64_t base = clock_.now_ns() + kPassLeadNs;
  std::int64_t abs0 = INT64_MAX, rel0 = INT64_MAX;
  const auto take = [&](std::int64_t t) {
    std::int64_t& first = t >= kEpochFloorNs ? abs0 : rel0;
    first = std::min(first, t);
  };
  if (!rs_->can.empty()) take(rs_->can.front().t_ns);
  if (!rs_->dvl.empty()) take(rs_->dvl.front().t_ns);
  if (!rs_->pairs.empty()) take(rs_->pairs.front().stamp_ns);
  std::int64_t ping0 = 0;
  if (recording_ != nullptr && peek_recorded(ping0)) take(ping0);
  abs_offset_ns_ = abs0 == INT64_MAX ? 0 : base - abs0;
  rel_offset_ns_ = rel0 == INT64_MAX ? 0 : base - rel0;
  can_i_ = dvl_i_ = pair_i_ = 0;
}

void SimVehicle::drain_bus() noexcept {
  hal::CanRxFrame rx;
  while (bus_->receive(rx, 0)) {
    if (observer_) observer_(observer_ctx_, rx);
    record(rx.frame, rx.stamp.sample_ns);
    // A closed-loop pass: the autopilot steers on the guidance it hears (bad frames are counted by it).
    if (cl_ && cl_->active) cl_->ap.on_frame(rx.frame, clock_.now_ns()).ignore();
    if (rx.frame.id == qc::kIdNavStatus) {
      qc::NavStatus ns;
      if (qc::decode(rx.frame, ns)) {
        reported_state_ = ns.state;
        reported_reject_ = ns.mode_reject;
        status_seen_since_cmd_ = true;
      }
    }
  }
}

void SimVehicle::send_mode(qc::Mode m, bool reverse) noexcept {
  qc::ModeCmd cmd;
  cmd.mode = m;
  cmd.reverse = reverse;
  cmd.route_id = cfg_.route_id;
  cmd.counter = ++mode_counter_;
  hal::CanFrame f;
  if (qc::encode(cmd, f) && bus_->send(f)) record(f, clock_.now_ns());
  status_seen_since_cmd_ = false;
  phase_start_ns_ = clock_.now_ns();
}

void SimVehicle::send_attitude(double heading_rad, double roll_rad, double pitch_rad) noexcept {
  last_heading_ = heading_rad;
  if (no_ahrs_) return;
  const std::int64_t now = clock_.now_ns();
  if (stalled("attitude", now) || now == last_att_ns_) return;  // one AHRS sample per instant
  last_att_ns_ = now;
  double h = std::fmod(heading_rad, kTwoPi);
  if (h < 0) h += kTwoPi;
  if (cfg_.sim_ahrs == "dronecan") {
    // uavcan.equipment.ahrs.Solution from node 42: yaw about NED down as a quaternion.
    namespace dc = drivers::dronecan;
    dc::AhrsSolution sol;
    sol.timestamp_us = static_cast<std::uint64_t>(now / 1000);
    const Eigen::Quaterniond q(rotation_from_rpy(roll_rad, pitch_rad, h));
    sol.orientation_xyzw[0] = static_cast<float>(q.x());
    sol.orientation_xyzw[1] = static_cast<float>(q.y());
    sol.orientation_xyzw[2] = static_cast<float>(q.z());
    sol.orientation_xyzw[3] = static_cast<float>(q.w());
    sol.linear_accel_mps2[2] = -9.81f;
    std::uint8_t payload[dc::kSolutionMaxBytes];
    const std::size_t n = dc::encode_solution(sol, true, payload, sizeof payload);
    hal::CanFrame frames[16];
    const std::size_t k = dc::split_transfer(dc::kSolutionSignature, dc::make_message_id(16, dc::kSolutionId, 42), att_counter_++, payload, n,
                                             frames, 16);
    for (std::size_t j = 0; j < k; ++j)
      if (bus_->send(frames[j])) record(frames[j], now);
    return;
  }
  qc::AttitudeIn a;
  a.heading_rad = std::fmin(h, 6.2832);
  a.roll_rad = roll_rad;
  a.pitch_rad = pitch_rad;
  a.valid = true;
  a.counter = att_counter_++;
  hal::CanFrame f;
  if (!qc::encode(a, f)) return;
  if (faulty("attitude_out_of_range", now)) {
    f.data[4] = 0xFF;  // Heading (bits 32..47): 6.5535 rad, beyond the DBC's [0, 6.2832]
    f.data[5] = 0xFF;
    io_->faults_injected.fetch_add(1, std::memory_order_relaxed);
  }
  if (bus_->send(f)) record(f, clock_.now_ns());
  if (faulty("attitude_duplicate", now) && bus_->send(f)) {  // the same frame again (same counter)
    record(f, clock_.now_ns());
    io_->faults_injected.fetch_add(1, std::memory_order_relaxed);
  }
}

void SimVehicle::send_dvl(double fwd, double stbd, std::int64_t t_ns) noexcept {
  if (stalled("dvl", t_ns)) return;
  long long tov = t_ns / 1000;
  if (tov <= last_tov_us_) tov = last_tov_us_ + 1;
  last_tov_us_ = tov;
  const bool nan = faulty("dvl_nan", t_ns), back = faulty("dvl_time_back", t_ns);
  const long long stamp = back ? tov - 5000000 : tov;  // 5 s in the past
  char line[240];
  const std::size_t n = drivers::dvl::wl_velocity_report(nan ? std::nan("") : fwd, stbd, 0.0, pass_cfg_.altitude_m, stamp, stamp, line, sizeof line);
  if (faulty("dvl_line_noise", t_ns)) {
    // A burst of line noise ending in a line break: a line of its own, before the real sentence.
    std::uint8_t noise[24];
    for (std::uint8_t& b : noise) {
      noise_seed_ = noise_seed_ * 1103515245u + 12345u;
      b = static_cast<std::uint8_t>(0x20 + (noise_seed_ >> 16) % 0x5F);
    }
    noise[sizeof noise - 1] = '\n';
    static_cast<void>(dvl_->write(Span<const std::uint8_t>(noise, sizeof noise)));
    io_->faults_injected.fetch_add(1, std::memory_order_relaxed);
  }
  static_cast<void>(dvl_->write(Span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(line), n)));
  if (nan || back) io_->faults_injected.fetch_add(1, std::memory_order_relaxed);
  if (faulty("dvl_duplicate", t_ns)) {
    static_cast<void>(dvl_->write(Span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(line), n)));
    io_->faults_injected.fetch_add(1, std::memory_order_relaxed);
  }
}

// Between two pings of a pass (mavlink.enabled): the AHRS sample at the next instant of the
// odometry grid (multiples of ahrs_tick_ns_ in mission time, the grid MavlinkEndpoint publishes on)
// before the held ping, its heading interpolated between the two pings' (the shorter way round). The
// dead reckoning is unchanged: each DVL sample still comes with the heading of its own instant.
bool SimVehicle::ahrs_tick() noexcept {
  if (ahrs_tick_ns_ <= 0 || !have_prev_ || replay_attitude_ || !has_held_) return false;
  const std::int64_t tick = (clock_.now_ns() / ahrs_tick_ns_ + 1) * ahrs_tick_ns_;
  if (tick <= last_sample_ns_ || tick >= held_.t_ns) return false;
  clock_.set(tick);
  inject_bus_faults(tick);
  const double f = static_cast<double>(tick - last_sample_ns_) / static_cast<double>(held_.t_ns - last_sample_ns_);
  const double dh = std::remainder(held_.nav.heading_rad - prev_nav_.heading_rad, kTwoPi);
  send_attitude(prev_nav_.heading_rad + f * dh);
  return true;
}

// Between passes the vehicle is alive: time passes and the AHRS streams.
void SimVehicle::idle_tick() noexcept {
  if (!worker_caught_up_) return;  // lockstep (set_worker_caught_up)
  const std::int64_t t = clock_.now_ns() + kIdleTickNs / 10;
  if (!pace(t, false)) return;  // the handshake's ticks keep their mission-time lengths (no following)
  clock_.set(t);
  if (t >= next_idle_att_ns_) {
    send_attitude(last_heading_);
    if (!no_sim_dvl_) send_dvl(0.0, 0.0, t);  // the DVL streams too (the vehicle waits between passes)
    next_idle_att_ns_ = t + kIdleTickNs;
  }
}

Status SimVehicle::start_pass() {
  const SimPass& p = cfg_.sim_mission[pass_];
  recording_ = recordings_[pass_].get();
  rs_ = sensors_[pass_].get();
  replay_attitude_ = rs_ != nullptr && !rs_->can.empty();
  replay_dvl_ = rs_ != nullptr && !rs_->dvl.empty();
  have_prev_ = false;
  pass_start_ns_ = clock_.now_ns();
  if (cl_) {  // the autopilot logs its taught track in a simulated teach pass
    cl_->logging = p.mode == qc::Mode::kTeach && recording_ == nullptr && rs_ == nullptr;
    if (cl_->logging) cl_->have_log = false;
  }
  if (p.mode == qc::Mode::kMap) {
    map_next_ = 0;
    map_t_ns_ = clock_.now_ns() + kPassLeadNs;
    return Status::ok();
  }
  if (p.mode == qc::Mode::kVo && rs_ != nullptr && !rs_->pairs.empty()) {
    align_sensors();
    return Status::ok();
  }
  if (p.mode == qc::Mode::kVo) {
    // The rover's first pair one step after the last sample between passes.
    rover_->start(cfg_.sim_seed + pass_, p.length_m, clock_.now_ns() + kPassLeadNs);
    return Status::ok();
  }
  if (recording_ != nullptr) {
    rec_next_ = static_cast<std::size_t>(p.first_ping);
    rec_end_ = p.last_ping < 0 ? recording_->data.pings.size()
                               : std::min<std::size_t>(recording_->data.pings.size(), static_cast<std::size_t>(p.last_ping));
    if (rec_next_ >= rec_end_) return Status(StatusCode::kOutOfRange, "sim: the pass's ping range is outside its file");
    rec_prev_stamp_ = recording_->data.pings[rec_next_].ping.stamp_ns;
    rec_started_ = false;
    if (rs_ != nullptr) align_sensors();
    return Status::ok();
  }
  if (rs_ != nullptr) {  // recorded sensors without a side-scan file: no pings in this pass
    align_sensors();
    return Status::ok();
  }
  const std::uint64_t seed = pass_ == 0 ? pipeline::teach_pass_seed(cfg_.sim_seed) : pipeline::repeat_pass_seed(cfg_.sim_seed) + pass_;
  pass_cfg_ = survey_->pass(p.offset_pct / 100.0 * survey_->swath_m, p.reverse, seed);
  // The first ping one ping period after the last sample between passes (sample times strictly increase).
  pass_cfg_.start_stamp_ns = static_cast<std::uint64_t>(clock_.now_ns() + static_cast<std::int64_t>(1e9 / pass_cfg_.ping_rate_hz));
  QNAV_RETURN_IF_ERROR(traj_.init(pass_cfg_));
  QNAV_RETURN_IF_ERROR(sonar_->init(survey_->sonar_for(pass_cfg_.seed), &survey_->seabed));
  if (p.closed_loop) {
    const Status st = start_closed_loop_pass(seed);
    if (!st) std::fprintf(stderr, "sim autopilot: pass %u: %s; skipping the pass\n", pass_, st.message());
    return st;
  }
  return Status::ok();
}

// Pacing (sim.speed, SimPacer): the step at mission time t goes when it is due. While it waits and
// `follow` is set (a pass's next sample), mission time follows the wall up to just before t, in steps
// of the pacer's poll slice, so the daemon's periodic outputs (NAV_STATUS every 100 ms) keep their
// periods in wall time too; the samples' own times do not change. Between passes (follow = false)
// the clock moves only by the handshake's ticks, whose mission-time lengths the lockstep fixes.
bool SimVehicle::pace(std::int64_t t, bool follow) noexcept {
  if (pacer_.due(t)) {
    if (io_ != nullptr) {
      io_->sim_late_steps.store(pacer_.late_steps(), std::memory_order_relaxed);
      io_->sim_max_late_us.store(static_cast<std::uint32_t>(std::min<std::int64_t>(pacer_.max_late_ns() / 1000, UINT32_MAX)),
                                 std::memory_order_relaxed);
    }
    return true;
  }
  if (follow) {
    const std::int64_t step_ns = static_cast<std::int64_t>(static_cast<double>(SimPacer::kPollSliceNs) * pacer_.speed());
    const std::int64_t m = std::min(pacer_.mission_now_ns(), t - 1);
    if (m >= clock_.now_ns() + step_ns) clock_.set(m);
  }
  return false;
}

void SimVehicle::release_ping(SpscRing<PingMsg>& pings, IoCounters& io) noexcept {
  if (!has_pending_) return;
  if (!pings.try_push(pending_)) {
    io.ping_overflow.fetch_add(1, std::memory_order_relaxed);
    spare_slot_ = pending_.slot;  // the slot stays ours (the end of a pass waits for every slot)
  }
  has_pending_ = false;
}

bool SimVehicle::next_simulated(Sample& out) noexcept {
  sidescan::TrajectorySample s;
  if (!traj_.next(s)) return false;
  if (cl_) log_teach_pose(s.nav);
  out.t_ns = static_cast<std::int64_t>(s.stamp_ns);
  out.nav = s.nav;
  out.ping_number = s.index;
  out.device_stamp_ns = s.stamp_ns;
  out.altitude_m = s.altitude_m;
  out.has_truth = true;
  out.truth.along_m = s.along_route_m;
  out.truth.pose = s.truth;
  out.truth.lateral_m = pass_cfg_.lateral_offset_m;
  out.recorded = nullptr;
  traj_sample_ = s;
  return true;
}

bool SimVehicle::next_recorded(Sample& out) noexcept {
  const Recording& r = *recording_;
  while (rec_next_ < rec_end_ && !r.track.ok[rec_next_]) ++rec_next_;  // pings without navigation are not flown
  if (rec_next_ >= rec_end_) return false;
  const std::size_t k = rec_next_++;
  const tools::PingRec& pr = r.data.pings[k];
  // Recorded timing, carried on the mission clock (strictly increasing even where the file's is not).
  // A file's clock that steps back or jumps ahead is not followed: each step is kept within 0 < dt <= 2 s.
  const std::int64_t file_dt = static_cast<std::int64_t>(pr.ping.stamp_ns) - static_cast<std::int64_t>(rec_prev_stamp_);
  rec_prev_stamp_ = pr.ping.stamp_ns;
  std::int64_t t = pass_start_ns_ + kPassLeadNs;
  if (rec_started_) t = last_sample_ns_ + std::min<std::int64_t>(std::max<std::int64_t>(file_dt, 1000000), 2000000000);
  rec_started_ = true;
  out.t_ns = t;
  out.nav = r.track.pose[k];
  out.ping_number = static_cast<std::uint32_t>(k);
  out.device_stamp_ns = pr.ping.stamp_ns;
  out.altitude_m = -1.0f;  // bottom detection, as `qnav route train|repeat --sonar`
  out.has_truth = false;
  out.recorded = &pr;
  return true;
}

SimVehicle::StepResult SimVehicle::emit(const Sample& smp, SpscRing<std::uint32_t>& free_slots, float* pool, std::size_t stride,
                                        IoCounters& io) noexcept {
  const std::int64_t t = smp.t_ns;
  clock_.set(t);
  inject_bus_faults(t);
  // AHRS: the compass heading (with the DVL + compass errors of the pass) at the ping time, unless
  // the pass replays the recorded one (sim.pass.candump), or the DVL (sim.pass.dvl_log).
  if (!replay_attitude_) send_attitude(smp.nav.heading_rad);
  // DVL: the dead-reckoned displacement since the previous ping, in the body frame of that heading.
  // The pass's first sample sends zero: nothing travelled since the last sample between passes
  // (whose time depends on how fast the daemon answered the mode command), so every pass is flown
  // the same.
  double fwd_mps = 0.0, stbd_mps = 0.0;
  if (have_prev_ && t > last_sample_ns_)
    pipeline::body_velocity_between(prev_nav_, smp.nav, static_cast<double>(t - last_sample_ns_) * 1e-9, fwd_mps, stbd_mps);
  if (!replay_dvl_) send_dvl(fwd_mps, stbd_mps, t);
  prev_nav_ = smp.nav;
  have_prev_ = true;
  last_sample_ns_ = t;
  // Side-scan: render (or copy the recorded ping) into a free slot of the pool.
  if (stalled("sonar", t)) return StepResult::kProduced;
  io.pings_in.fetch_add(1, std::memory_order_relaxed);
  std::uint32_t slot = 0;
  if (spare_slot_ >= 0) {
    slot = static_cast<std::uint32_t>(spare_slot_);
    spare_slot_ = -1;
  } else if (!free_slots.try_pop(slot)) {
    io.ping_overflow.fetch_add(1, std::memory_order_relaxed);
    return StepResult::kProduced;
  }
  float* port = pool + static_cast<std::size_t>(slot) * stride;
  float* stbd = port + stride / 2;
  PingMsg m;
  m.slot = slot;
  bool ok = false;
  if (smp.recorded != nullptr) {
    const tools::PingRec& pr = *smp.recorded;
    ok = pr.port.size() <= stride / 2 && pr.stbd.size() <= stride / 2;
    if (ok) {
      std::memcpy(port, pr.port.data(), pr.port.size() * sizeof(float));
      std::memcpy(stbd, pr.stbd.data(), pr.stbd.size() * sizeof(float));
      m.port_samples = static_cast<std::uint32_t>(pr.port.size());
      m.stbd_samples = static_cast<std::uint32_t>(pr.stbd.size());
      m.slant_range_m = pr.ping.slant_range_m;
    }
  } else {
    const std::size_t n = static_cast<std::size_t>(survey_->sonar.samples_per_side);
    ok = n <= stride / 2 &&
         sonar_->ping(traj_sample_.truth, traj_sample_.altitude_m, traj_sample_.index, Span<float>(port, n), Span<float>(stbd, n)).is_ok();
    m.port_samples = m.stbd_samples = static_cast<std::uint32_t>(n);
    m.slant_range_m = survey_->sonar.slant_range_m;
  }
  if (!ok) {
    io.sonar_rejected.fetch_add(1, std::memory_order_relaxed);
    spare_slot_ = slot;  // kept for the next ping (the nav worker is the only producer of free_slots)
    return StepResult::kProduced;
  }
  m.ping_number = smp.ping_number;
  m.altitude_m = smp.altitude_m;
  m.device_stamp_ns = smp.device_stamp_ns;
  m.stamp.sample_ns = m.stamp.arrival_ns = t;
  if (faulty("sonar_nan", t)) {
    port[m.port_samples / 3] = std::nanf("");
    io.faults_injected.fetch_add(1, std::memory_order_relaxed);
  }
  if (faulty("sonar_bad_range", t)) {
    m.slant_range_m = 8.8e-38f;  // one flipped exponent bit of 30 m
    io.faults_injected.fetch_add(1, std::memory_order_relaxed);
  }
  if (faulty("ping_time_back", t)) {
    m.stamp.sample_ns = m.stamp.arrival_ns = t - 3000000000;  // stamped 3 s in the past
    io.faults_injected.fetch_add(1, std::memory_order_relaxed);
  }
  m.has_truth = smp.has_truth;
  m.truth = smp.truth;
  // Held until the I/O thread has queued this instant's attitude frame and DVL sentence
  // (release_ping), as a real sonar's ping arrives with the navigation of its time.
  pending_ = m;
  has_pending_ = true;
  return StepResult::kProduced;
}

// A slot of the frame pool for the next pair: the one kept from a failed pair, else a free one; none
// free is an overflow (counted).
bool SimVehicle::take_frame_slot(std::uint32_t& slot, IoCounters& io) noexcept {
  if (spare_frame_ >= 0) {
    slot = static_cast<std::uint32_t>(spare_frame_);
    spare_frame_ = -1;
    return true;
  }
  if (frames_.free->try_pop(slot)) return true;
  io.frame_overflow.fetch_add(1, std::memory_order_relaxed);
  return false;
}

SimVehicle::StepResult SimVehicle::fly_rover(IoCounters& io) noexcept {
  if (frames_.frames->size() >= 1) return StepResult::kWaiting;  // the consumer sets the pace
  if (spare_frame_ < 0 && frames_.free->front() == nullptr) return StepResult::kWaiting;
  if (!has_held_rover_) {
    if (!rover_->next(held_rover_)) {
      phase_ = Phase::kEndPass;
      return StepResult::kWaiting;
    }
    has_held_rover_ = true;
  }
  if (!pace(held_rover_.t_ns, true)) return StepResult::kWaiting;
  has_held_rover_ = false;
  const RoverSample& s = held_rover_;
  clock_.set(s.t_ns);
  inject_bus_faults(s.t_ns);
  send_attitude(s.heading_rad, s.roll_rad, s.pitch_rad);
  // The rover's wheel odometry over the last step, as the DVL's body velocities.
  send_dvl(s.dt_s > 0.0 ? s.odo_forward_m / s.dt_s : 0.0, s.dt_s > 0.0 ? s.odo_right_m / s.dt_s : 0.0, s.t_ns);
  if (stalled("camera", s.t_ns)) return StepResult::kProduced;
  io.frames_in.fetch_add(1, std::memory_order_relaxed);
  std::uint32_t slot = 0;
  if (!take_frame_slot(slot, io)) return StepResult::kProduced;
  const std::size_t n = static_cast<std::size_t>(frames_.width) * static_cast<std::size_t>(frames_.height);
  std::uint8_t* left = frames_.slot(slot);
  const Status r = rover_->render(ImageViewU8::make(left, frames_.width, frames_.height).value(),
                                  ImageViewU8::make(left + n, frames_.width, frames_.height).value());
  if (!r) {
    io.camera_rejected.fetch_add(1, std::memory_order_relaxed);
    spare_frame_ = slot;  // kept for the next pair (the nav worker is the only producer of free frames)
    return StepResult::kProduced;
  }
  FrameMsg m;
  m.slot = slot;
  m.sequence = s.index;
  m.width = static_cast<std::uint16_t>(frames_.width);
  m.height = static_cast<std::uint16_t>(frames_.height);
  m.stamp.sample_ns = m.stamp.arrival_ns = s.t_ns;
  m.has_truth = true;
  m.truth_world_T_body = s.truth_world_T_body;
  m.truth_path_m = s.path_m;
  pending_pair_ = m;
  has_pending_pair_ = true;
  return StepResult::kProduced;
}

bool SimVehicle::peek_recorded(std::int64_t& stamp_ns) noexcept {
  const Recording& r = *recording_;
  while (rec_next_ < rec_end_ && !r.track.ok[rec_next_]) ++rec_next_;
  if (rec_next_ >= rec_end_) return false;
  stamp_ns = static_cast<std::int64_t>(r.data.pings[rec_next_].ping.stamp_ns);
  return true;
}

// A pass with recorded sensors: the next sample of any source, in time order, on the mission clock
// (never backwards: a source whose clock steps back plays at the current time).
SimVehicle::StepResult SimVehicle::fly_replay(SpscRing<std::uint32_t>& free_slots, SpscRing<PingMsg>& pings, float* pool,
                                              std::size_t stride, IoCounters& io) noexcept {
  enum Source { kNone, kPing, kCan, kDvl, kPair };
  Source which = kNone;
  std::int64_t best = INT64_MAX, stamp = 0;
  const auto consider = [&](Source s, std::int64_t t) {
    if (replay_time(t) < best) best = replay_time(t), which = s;
  };
  // At equal times the navigation goes first: a ping or pair arrives with the navigation of its instant.
  if (can_i_ < rs_->can.size()) consider(kCan, rs_->can[can_i_].t_ns);
  if (dvl_i_ < rs_->dvl.size()) consider(kDvl, rs_->dvl[dvl_i_].t_ns);
  if (recording_ != nullptr && peek_recorded(stamp)) consider(kPing, stamp);
  if (pair_i_ < rs_->pairs.size()) consider(kPair, rs_->pairs[pair_i_].stamp_ns);
  if (which == kNone) {
    phase_ = Phase::kEndPass;
    return StepResult::kWaiting;
  }
  const std::int64_t t = std::max(best, clock_.now_ns());
  if (which == kPair && (frames_.frames->size() >= 1 || (spare_frame_ < 0 && frames_.free->front() == nullptr)))
    return StepResult::kWaiting;  // the consumer sets the pace
  if (!pace(t, true)) return StepResult::kWaiting;
  switch (which) {
    case kPing: {
      Sample smp;
      if (!next_recorded(smp)) return StepResult::kWaiting;
      smp.t_ns = std::max(t, last_sample_ns_ + 1000);  // the recorded timing, aligned with the logs
      return emit(smp, free_slots, pool, stride, io);
    }
    case kCan: {
      clock_.set(t);
      inject_bus_faults(t);
      const hal::CanFrame& f = rs_->can[can_i_++].frame;
      if (f.error && net_ != nullptr) {
        std::uint8_t data[8] = {};
        std::memcpy(data, f.data, 8);
        net_->inject_error(f.id, data);
      } else if (!stalled("attitude", t) && bus_->send(f)) {
        record(f, t);
      }
      return StepResult::kProduced;
    }
    case kDvl: {
      clock_.set(t);
      const ReplayDvlReport& r = rs_->dvl[dvl_i_++];
      if (!stalled("dvl", t))
        static_cast<void>(dvl_->write(Span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(rs_->dvl_text.data()) + r.offset, r.length)));
      return StepResult::kProduced;
    }
    case kPair: return replay_pair(t, io);
    case kNone: break;
  }
  static_cast<void>(pings);
  return StepResult::kWaiting;
}

// The next recorded stereo pair into a free slot of the frame pool (decoded here, on the sim's io
// thread: replay only). A pair that cannot be read or has the wrong size is counted and skipped.
SimVehicle::StepResult SimVehicle::replay_pair(std::int64_t t, IoCounters& io) noexcept {
  clock_.set(t);
  inject_bus_faults(t);
  const tools::StereoFrame& pf = rs_->pairs[pair_i_];
  const std::uint32_t seq = static_cast<std::uint32_t>(pair_i_++);
  if (stalled("camera", t)) return StepResult::kProduced;
  io.frames_in.fetch_add(1, std::memory_order_relaxed);
  const Result<ImageU8> l = tools::read_image_gray8(pf.left_path.c_str());
  const Result<ImageU8> r = tools::read_image_gray8(pf.right_path.c_str());
  if (!l || !r || l->width() != frames_.width || l->height() != frames_.height || r->width() != frames_.width ||
      r->height() != frames_.height) {
    io.camera_rejected.fetch_add(1, std::memory_order_relaxed);
    return StepResult::kProduced;
  }
  std::uint32_t slot = 0;
  if (!take_frame_slot(slot, io)) return StepResult::kProduced;
  const std::size_t n = static_cast<std::size_t>(frames_.width) * static_cast<std::size_t>(frames_.height);
  std::uint8_t* left = frames_.slot(slot);
  for (int y = 0; y < frames_.height; ++y) {
    std::memcpy(left + static_cast<std::size_t>(y) * static_cast<std::size_t>(frames_.width), l->view().row(y), static_cast<std::size_t>(frames_.width));
    std::memcpy(left + n + static_cast<std::size_t>(y) * static_cast<std::size_t>(frames_.width), r->view().row(y),
                static_cast<std::size_t>(frames_.width));
  }
  FrameMsg m;
  m.slot = slot;
  m.sequence = seq;
  m.width = static_cast<std::uint16_t>(frames_.width);
  m.height = static_cast<std::uint16_t>(frames_.height);
  m.stamp.sample_ns = m.stamp.arrival_ns = t;
  pending_pair_ = m;
  has_pending_pair_ = true;
  return StepResult::kProduced;
}

SimVehicle::StepResult SimVehicle::fly_downward(IoCounters& io) noexcept {
  if (frames_.frames->size() >= 1) return StepResult::kWaiting;  // the consumer sets the pace
  if (spare_frame_ < 0 && frames_.free->front() == nullptr) return StepResult::kWaiting;
  const std::vector<std::string>& files = map_files_[pass_];
  const std::size_t synthetic = map_synthetic_[pass_];
  if (map_next_ >= (synthetic > 0 ? synthetic : files.size())) {
    phase_ = Phase::kEndPass;
    return StepResult::kWaiting;
  }
  if (!pace(map_t_ns_, true)) return StepResult::kWaiting;
  const std::int64_t t = map_t_ns_;
  map_t_ns_ += kMapFramePeriodNs;
  const std::size_t seq = map_next_++;
  clock_.set(t);
  inject_bus_faults(t);
  send_attitude(last_heading_);  // the vehicle's AHRS runs on (the mapper does not use it)
  if (stalled("camera", t)) return StepResult::kProduced;
  io.frames_in.fetch_add(1, std::memory_order_relaxed);
  std::uint32_t slot = 0;
  if (synthetic > 0) {  // rendered in place: no file, no heap
    if (!take_frame_slot(slot, io)) return StepResult::kProduced;
    const sim::downward::CameraPose pose = sim::downward::loop_pose(static_cast<int>(seq), kSeabedFramesPerLap);
    sim::downward::render(*seabed_, sim::downward::Camera{}, pose,
                          ImageViewU8::make(frames_.slot(slot), frames_.map_width, frames_.map_height).value());
  } else {
    const Result<ImageU8> img = tools::read_image_gray8(files[seq].c_str());
    if (!img || img->width() != frames_.map_width || img->height() != frames_.map_height) {
      io.camera_rejected.fetch_add(1, std::memory_order_relaxed);
      return StepResult::kProduced;
    }
    if (!take_frame_slot(slot, io)) return StepResult::kProduced;
    std::uint8_t* dst = frames_.slot(slot);
    const std::size_t w = static_cast<std::size_t>(frames_.map_width);
    for (int y = 0; y < frames_.map_height; ++y) std::memcpy(dst + static_cast<std::size_t>(y) * w, img->view().row(y), w);
  }
  FrameMsg m;
  m.slot = slot;
  m.sequence = static_cast<std::uint32_t>(seq);
  m.width = static_cast<std::uint16_t>(frames_.map_width);
  m.height = static_cast<std::uint16_t>(frames_.map_height);
  m.downward = true;
  m.stamp.sample_ns = m.stamp.arrival_ns = t;
  pending_pair_ = m;
  has_pending_pair_ = true;
  return StepResult::kProduced;
}

void SimVehicle::release_pair(IoCounters& io) noexcept {
  if (!has_pending_pair_) return;
  if (!frames_.frames->try_push(pending_pair_)) {
    io.frame_overflow.fetch_add(1, std::memory_order_relaxed);
    spare_frame_ = pending_pair_.slot;
  }
  has_pending_pair_ = false;
}

SimVehicle::StepResult SimVehicle::step(SpscRing<std::uint32_t>& free_slots, SpscRing<PingMsg>& pings, float* pool, std::size_t stride,
                                        IoCounters& io) noexcept {
  io_ = &io;
  if (!pacer_.started()) pacer_.start(clock_.now_ns());  // the pace's anchor: the mission's first step
  drain_bus();
  switch (phase_) {
    case Phase::kCommand: {
      if (pass_ >= cfg_.sim_mission.size()) {
        phase_ = Phase::kDone;
        return StepResult::kDone;
      }
      const SimPass& p = cfg_.sim_mission[pass_];
      send_attitude(last_heading_);  // the AHRS is up before the first command
      send_mode(p.mode, p.reverse);
      phase_ = Phase::kAwaitState;
      return StepResult::kWaiting;
    }
    case Phase::kAwaitState: {
      const SimPass& p = cfg_.sim_mission[pass_];
      if (status_seen_since_cmd_ && reported_state_ == p.mode && reported_reject_ == 0) {
        if (!start_pass()) {
          ++pass_;
          phase_ = Phase::kCommand;
          return StepResult::kWaiting;
        }
        phase_ = Phase::kFly;
        return StepResult::kWaiting;
      }
      if ((status_seen_since_cmd_ && reported_reject_ != 0) || clock_.now_ns() - phase_start_ns_ > kStateTimeoutNs) {
        std::fprintf(stderr, "sim autopilot: pass %u: qnavd did not enter the commanded mode (reject code %u); skipping the pass\n", pass_,
                     reported_reject_);
        ++pass_;
        send_mode(qc::Mode::kIdle, false);
        phase_ = Phase::kAwaitIdle;
        return StepResult::kWaiting;
      }
      idle_tick();
      return StepResult::kWaiting;
    }
    case Phase::kFly: {
      if (pings.size() >= 2) return StepResult::kWaiting;  // the consumer sets the pace (every speed: the lockstep)
      // A closed-loop pass flies its next instant only once the daemon has navigated the last one and
      // the frames it published reached the vehicle: the autopilot hears each tile's guidance at the
      // ping after the tile, as in `qnav route follow`, whatever the host's load (without this the
      // frames arrived 0-2 pings late, and one seed's p95 varied 4.3-5.1 m from run to run).
      if (cl_ && cl_->active && !worker_caught_up_) return StepResult::kWaiting;
      if (cfg_.sim_mission[pass_].mode == qc::Mode::kMap) return fly_downward(io);
      if (rs_ != nullptr) return fly_replay(free_slots, pings, pool, stride, io);
      if (cfg_.sim_mission[pass_].mode == qc::Mode::kVo) return fly_rover(io);
      if (!has_held_) {
        if (!(recording_ ? next_recorded(held_) : (cl_ && cl_->active) ? next_closed_loop(held_) : next_simulated(held_))) {
          phase_ = Phase::kEndPass;
          return StepResult::kWaiting;
        }
        has_held_ = true;
      }
      if (ahrs_tick_ns_ > 0 && have_prev_ && !replay_attitude_) {  // the AHRS between pings (mavlink.enabled)
        const std::int64_t tick = (clock_.now_ns() / ahrs_tick_ns_ + 1) * ahrs_tick_ns_;
        if (tick > last_sample_ns_ && tick < held_.t_ns) {
          if (!pace(tick, true)) return StepResult::kWaiting;
          if (ahrs_tick()) return StepResult::kProduced;
        }
      }
      if (!pace(held_.t_ns, true)) return StepResult::kWaiting;
      has_held_ = false;
      return emit(held_, free_slots, pool, stride, io);
    }
    case Phase::kEndPass:
      // Let the nav worker finish the pass: every slot back (the last ping processed, not only popped).
      if (free_slots.size() + (spare_slot_ >= 0 ? 1u : 0u) < free_slots.capacity()) return StepResult::kWaiting;
      if (frames_.free != nullptr && frames_.free->size() + (spare_frame_ >= 0 ? 1u : 0u) < frames_.free->capacity())
        return StepResult::kWaiting;
      // A fault window ends with its pass at the latest (the disk is free, the bus restarted):
      // out of kFly no window is open.
      phase_ = Phase::kAwaitIdle;
      inject_bus_faults(clock_.now_ns());
      send_mode(qc::Mode::kIdle, false);
      ++pass_;
      return StepResult::kWaiting;
    case Phase::kAwaitIdle:
      if (status_seen_since_cmd_ && reported_state_ == qc::Mode::kIdle) {
        phase_ = Phase::kCommand;
        return StepResult::kWaiting;
      }
      idle_tick();
      return StepResult::kWaiting;
    case Phase::kDone: return StepResult::kDone;
  }
  return StepResult::kDone;
}

}  // namespace qnav::daemon

namespace qnav::daemon {

bool SimVehicle::recorded_geometry(double& range_m, double& spacing_m) const {
  std::vector<float> ranges;
  double dist = 0.0;
  std::size_t steps = 0;
  for (std::size_t i = 0; i < recordings_.size(); ++i) {
    const Recording* r = recordings_[i].get();
    if (r == nullptr) continue;
    tools::collect_slant_ranges(r->data, ranges);
    for (std::size_t k = 1; k < r->data.pings.size(); ++k) {
      if (r->track.ok[k] && r->track.ok[k - 1]) {
        dist += std::hypot(r->track.pose[k].x_m - r->track.pose[k - 1].x_m, r->track.pose[k].y_m - r->track.pose[k - 1].y_m);
        ++steps;
      }
    }
  }
  if (steps == 0 || !tools::median_slant_range(ranges, range_m)) return false;
  spacing_m = cfg_.sim_replay_stride * dist / static_cast<double>(steps);
  return true;
}

}  // namespace qnav::daemon
