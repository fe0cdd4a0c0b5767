#include "firmware/qnavd/components/nav_health.hpp"

#include <algorithm>
#include <cinttypes>

#include "firmware/qnavd/software_fault.hpp"

namespace qnav::daemon {

namespace qc = drivers::qnavcan;

namespace {
constexpr std::int64_t kNsPerS = 1000000000;
}  // namespace

void NavHealth::init(const NavParts& parts, qc::QnavCanPublisher& publisher, std::int64_t cpu_now_ns) noexcept {
  p_ = parts;
  publisher_ = &publisher;
  const Deployment d = make_deployment(*ctx_.cfg);
  for (int i = 0; i < static_cast<int>(Stage::kCount); ++i) budgets_us_[i] = d.stages[i].budget_us;
  start_window(cpu_now_ns);
}

void NavHealth::stage_time(Stage s, std::int64_t t0_ns, std::int64_t now_ns) noexcept {
  const std::int64_t dt = now_ns - t0_ns;
  const int i = static_cast<int>(s);
  stage_max_ns_[i] = std::max(stage_max_ns_[i], dt);
  busy_ns_ += dt;
  if (budgets_us_[i] > 0 && dt > static_cast<std::int64_t>(budgets_us_[i]) * 1000) {
    ++stage_misses_[i];
    ++deadline_misses_;
  }
}

std::uint32_t NavHealth::pings_rejected() const noexcept {
  const auto& c = p_.tiles->corrector().counters();
  return c.get(sonar::CorrectorCounter::kBadSampleCount) + c.get(sonar::CorrectorCounter::kBadRange) +
         c.get(sonar::CorrectorCounter::kNonFiniteSample) + c.get(sonar::CorrectorCounter::kBadAltitude);
}

std::uint16_t NavHealth::update(RouteRepeat& repeat) noexcept {
  const DaemonConfig& cfg = *ctx_.cfg;
  const std::int64_t now = ctx_.clock->now_ns;
  const qc::Mode mode = p_.state->mode;
  const IoCounters& io = *p_.io;
  const pipeline::DeadReckoner& dr = p_.inputs->dr();
  std::uint16_t f = repeat.route_damaged() ? qc::fault::kRouteDamaged : 0;
  // The sonar is not used in Mode = Vo or Mode = Map, the cameras only there: each is lost only where
  // it is used (a camera-only survey with the sonar off raises no sonar fault).
  const std::int64_t last_ping_ns = p_.state->last_ping_ns;
  const bool sonar_lost = mode != qc::Mode::kVo && mode != qc::Mode::kMap &&
                          (now - (last_ping_ns < 0 ? ctx_.clock->start_ns : last_ping_ns)) > static_cast<std::int64_t>(cfg.sonar_stale_s * kNsPerS);
  const bool camera_lost = (mode == qc::Mode::kVo && (p_.vo->camera_lost(now) || io.camera_device_down.load(std::memory_order_relaxed))) ||
                           (mode == qc::Mode::kMap && (p_.map->camera_lost(now) || io.downward_device_down.load(std::memory_order_relaxed)));
  const bool att_lost = dr.heading_age_s(now) > cfg.attitude_stale_s;
  const bool dvl_lost = cfg.dvl_enabled && dr.velocity_age_s(now) > cfg.dvl_stale_s;
  if (sonar_lost) f |= qc::fault::kSonarLost;
  if (att_lost) f |= qc::fault::kAttitudeLost;
  if (dvl_lost) f |= qc::fault::kDvlLost;
  if (camera_lost) f |= qc::fault::kCameraLost;
  if (sonar_lost || att_lost || dvl_lost || camera_lost) f |= qc::fault::kSensorTimeout;
  if (p_.inputs->bus_off() || io.can_device_down.load(std::memory_order_relaxed)) f |= qc::fault::kBusOff;
  if (deadline_misses_ > 0) f |= qc::fault::kDeadlineMiss;
  if (SoftwareFaults::count() > 0) f |= qc::fault::kSoftware;
  // The leak detector is latched by the io thread (drivers/camera LeakMonitor); a configured detector
  // whose line cannot be read is a sensor that does not report.
  const bool leak = io.leak.load(std::memory_order_relaxed);
  if (leak) f |= qc::fault::kLeak;
  if (io.leak_device_down.load(std::memory_order_relaxed)) f |= qc::fault::kSensorTimeout;
  if (leak && !leak_logged_ && ctx_.events()) {
    std::fprintf(ctx_.log, "{\"event\":\"leak\",\"t_s\":%.3f,\"edges\":%u}\n", ctx_.clock->t_s(), io.leak_events.load(std::memory_order_relaxed));
    leak_logged_ = true;
  }
  faults_ = f;
  // Degraded repeat: without sonar or heading there is no fix; the autopilot is told to hold course.
  repeat.hold(mode == qc::Mode::kRepeat, sonar_lost || att_lost, p_.counters->tiles);
  return f;
}

void NavHealth::publish() noexcept {
  const qc::Mode mode = p_.state->mode;
  const route::LocaliserStep& step = p_.state->step;
  const IoCounters& io = *p_.io;
  const NavCounters& n = *p_.counters;
  qc::NavStatus ns;
  ns.state = mode;
  const bool fix_possible = mode == qc::Mode::kRepeat && !(faults_ & (qc::fault::kSonarLost | qc::fault::kAttitudeLost));
  ns.localised = fix_possible && step.confident;
  ns.confidence_pct = fix_possible ? qc::clamp_to_signal(qc::kIdNavStatus, "Confidence", 100.0 * static_cast<double>(step.probability)) : 0.0;
  ns.node_index = static_cast<std::uint16_t>(std::min<std::uint32_t>(mode == qc::Mode::kTeach ? p_.teach->node_count() : step.estimate, 65535));
  ns.fault_flags = faults_;
  ns.mode_reject = static_cast<std::uint8_t>(p_.state->last_reject);
  publisher_->set(ns);
  qc::Health h;
  h.fault_flags = faults_;
  // Input qnav should have understood and refused; frames for other nodes are not rejections.
  std::uint64_t rejected = p_.inputs->rejected();
  rejected += io.dvl_rejected.load(std::memory_order_relaxed) + io.sonar_rejected.load(std::memory_order_relaxed);
  rejected += io.can_rx_overflow.load(std::memory_order_relaxed) + io.ping_overflow.load(std::memory_order_relaxed);
  rejected += io.can_rx_dropped.load(std::memory_order_relaxed);
  rejected += pings_rejected() + n.pings_out_of_order;
  rejected += io.frame_overflow.load(std::memory_order_relaxed) + io.camera_rejected.load(std::memory_order_relaxed) + n.frames_out_of_order;
  if (p_.source->enabled()) rejected += p_.source->rejected() + io.mav_rx_overflow.load(std::memory_order_relaxed);
  h.rejected_inputs = static_cast<std::uint16_t>(std::min<std::uint64_t>(rejected, 65535));
  h.deadline_misses = static_cast<std::uint16_t>(std::min<std::uint32_t>(deadline_misses_, 65535));
  h.cpu_load_pct = qc::clamp_to_signal(qc::kIdHealth, "CpuLoad", cpu_load_pct_);
  h.bus_off = p_.inputs->bus_off() || io.can_device_down.load(std::memory_order_relaxed);
  h.leak = (faults_ & qc::fault::kLeak) != 0;
  publisher_->set(h);
  qc::Heartbeat hb;
  hb.uptime_s = static_cast<std::uint32_t>(std::max<std::int64_t>(0, ctx_.clock->now_ns - ctx_.clock->start_ns) / kNsPerS);
  hb.state = mode;
  hb.sw_major = 0;
  hb.sw_minor = 1;
  publisher_->set(hb);
  publisher_->poll(ctx_.clock->now_ns);
}

void NavHealth::log(std::int64_t cpu_now_ns) noexcept {
  const std::int64_t window = cpu_now_ns - busy_window_start_ns_;
  if (window > 0) cpu_load_pct_ = 100.0 * static_cast<double>(busy_ns_) / static_cast<double>(window);
  start_window(cpu_now_ns);
  if (!ctx_.events()) return;
  const IoCounters& io = *p_.io;
  const NavCounters& n = *p_.counters;
  const NavInputs& in = *p_.inputs;
  const VoComponent& vo = *p_.vo;
  const MapComponent& map = *p_.map;
  auto max_us = [this](Stage s) { return stage_max_ns_[static_cast<int>(s)] / 1000; };
  auto misses = [this](Stage s) { return stage_misses_[static_cast<int>(s)]; };
  std::fprintf(ctx_.log,
               "{\"event\":\"health\",\"t_s\":%.1f,\"mode\":\"%s\",\"faults\":%u,\"pings\":%u,\"tiles\":%u,\"deadline_misses\":%u,"
               "\"ping_max_us\":%" PRId64 ",\"tile_max_us\":%" PRId64 ",\"cpu_load_pct\":%.1f,\"can_rx_overflow\":%u,\"can_rx_dropped\":%u,\"can_tx_overflow\":%u,"
               "\"ping_overflow\":%u,\"dvl_rejected\":%u,\"sonar_rejected\":%u,\"device_errors\":%u,\"can_rejected\":%u,\"dr_rejected\":%u,"
               "\"mode_refused\":%u,\"step_errors\":%u,\"registrations_rejected\":%u,\"writer_errors\":%u,\"software_faults\":%u,\"dvl_overflow\":%u,\"can_tx_errors\":%u,"
               "\"teach_no_odometry\":%u,\"nav_resets\":%u,\"pings_rejected\":%u,\"pings_out_of_order\":%u,\"bus_off\":%s,"
               "\"frames\":%u,\"vo_frames\":%u,\"vo_visual\":%u,\"vo_no_attitude\":%u,\"frames_out_of_order\":%u,\"frame_overflow\":%u,"
               "\"camera_rejected\":%u,\"vo_max_us\":%" PRId64 ",\"map_frames\":%u,\"map_bad_frames\":%u,\"map_saves\":%u,"
               "\"map_save_errors\":%u,\"map_max_us\":%" PRId64 ","
               "\"misses\":{\"inputs\":%u,\"modes\":%u,\"ping\":%u,\"tile\":%u,\"vo\":%u,\"map\":%u,\"outputs\":%u}}\n",
               ctx_.clock->t_s(), qc::mode_name(p_.state->mode), faults_, n.pings, n.tiles, deadline_misses_, max_us(Stage::kPing),
               max_us(Stage::kTile), cpu_load_pct_, io.can_rx_overflow.load(), io.can_rx_dropped.load(),
               publisher_->counters().get(qc::TxCounter::kTxBusy), io.ping_overflow.load(), io.dvl_rejected.load(), io.sonar_rejected.load(),
               io.device_errors.load(), static_cast<unsigned>(in.receiver().counters().total()), in.dr_rejected(), n.mode_refused,
               p_.repeat->step_errors() + map.step_errors(), p_.repeat->registrations_rejected(), p_.teach->errors() + map.save_errors(), SoftwareFaults::count(),
               io.dvl_overflow.load(), io.can_tx_errors.load(), n.teach_no_odometry, n.nav_resets, pings_rejected(), n.pings_out_of_order,
               in.bus_off() ? "true" : "false", n.frames, vo.frames(), vo.visual_steps(), vo.no_attitude(), n.frames_out_of_order,
               io.frame_overflow.load(), io.camera_rejected.load(), max_us(Stage::kVo), map.frames(), map.bad_frames(), map.saves(),
               map.save_errors(), max_us(Stage::kMap), misses(Stage::kInputs), misses(Stage::kModes), misses(Stage::kPing),
               misses(Stage::kTile), misses(Stage::kVo), misses(Stage::kMap), misses(Stage::kOutputs));
  p_.source->log_counters(io);
  const std::uint32_t sw = SoftwareFaults::count();
  if (sw != software_faults_logged_) {
    const SoftwareFaultRecord r = SoftwareFaults::last();
    std::fprintf(ctx_.log, "{\"event\":\"software_fault\",\"count\":%u,\"last\":\"%s\",\"at\":\"%s:%d\"}\n", sw, r.what ? r.what : "?",
                 r.file ? r.file : "?", r.line);
    software_faults_logged_ = sw;
  }
  std::fflush(ctx_.log);
}

}  // namespace qnav::daemon
