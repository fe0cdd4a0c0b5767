#include "firmware/qnavd/components/nav_source.hpp"

#include <cmath>
#include <limits>
#include <new>

namespace qnav::daemon {

namespace qc = drivers::qnavcan;

Status NavSource::init(SpscRing<MavBytes>* rx, SpscRing<MavBytes>* tx, StaticMemory* mem) {
  if (!ctx_.cfg->mavlink_enabled) return Status::ok();
  if (!rx || !tx) return Status(StatusCode::kInvalidArgument, "nav worker: mavlink queues missing");
  rx_ = rx;
  tx_ = tx;
  mav_ = std::make_unique<MavlinkEndpoint>(*ctx_.cfg, ctx_.log);
  if (map_runs(*ctx_.cfg)) {
    const std::size_t n = ctx_.cfg->map_max_nodes;
    if (mem != nullptr) {
      Result<Span<KeptPosition>> r = mem->take_array<KeptPosition>("map_fixes", n);
      if (!r) return r.status();
      map_fixes_ = r.value();
    } else {
      own_map_fixes_.reset(new (std::nothrow) KeptPosition[n]);
      if (!own_map_fixes_) return Status(StatusCode::kCapacityExceeded, "nav worker: cannot allocate the map fixes");
      map_fixes_ = Span<KeptPosition>(own_map_fixes_.get(), n);
    }
    map_start();
  }
  return Status::ok();
}

void NavSource::map_start() noexcept {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (KeptPosition& p : map_fixes_) p = KeptPosition{nan, nan};
}

void NavSource::map_step(const topo::ObserveResult& place, const pipeline::DeadReckoner& dr) noexcept {
  if (place.node == topo::kNoNode || place.node >= map_fixes_.size()) return;
  KeptPosition& kept = map_fixes_[place.node];
  const Pose2 dr_now = dr.pose_at(ctx_.clock->now_ns);
  est_.track(dr_now);  // the estimate up to this frame's instant
  if (place.kind == topo::ObserveKind::kCreated) {
    kept = KeptPosition{est_.north_m(), est_.east_m()};
    return;
  }
  if (place.kind != topo::ObserveKind::kMatched || !place.revisit || !std::isfinite(kept.north_m) || !std::isfinite(kept.east_m)) return;
  est_.apply_fix(kept.north_m, kept.east_m);
  est_.rebase();
  est_.track(dr_now);
}

void NavSource::route_fix(const pipeline::RouteTile& t, const route::LocaliserStep& step, const route::NodeMeta* node, bool reverse,
                          const pipeline::DeadReckoner& dr) noexcept {
  const route::GuidanceOutput& g = step.guidance;
  guidance_valid_ = g.status != route::GuidanceStatus::kHoldCourse && g.offsets != route::OffsetSource::kNone;
  waypoint_ne_ = g.waypoint_ne;
  if (!step.confident || g.offsets != route::OffsetSource::kRegistration || node == nullptr) return;
  const Vec2d at_tile = pipeline::NavEstimate::route_fix_position(*node, reverse, g.along_track_m, g.cross_track_m);
  const Pose2 dr_now = dr.pose_at(ctx_.clock->now_ns);
  const Pose2& dr_tile = t.node.meta.pose;
  est_.apply_fix(at_tile.x() + (dr_now.x_m - dr_tile.x_m), at_tile.y() + (dr_now.y_m - dr_tile.y_m));
  est_.rebase();  // tracked from this instant on
  est_.track(dr_now);
  route_fix_ = true;
}

void NavSource::publish(qc::Mode mode, std::uint16_t faults, const NavInputs& in, const VoComponent& vo,
                        const route::LocaliserStep& step) noexcept {
  const std::int64_t now_ns = ctx_.clock->now_ns;
  const pipeline::DeadReckoner& dr = in.dr();
  const bool on_vo = mode == qc::Mode::kVo;
  if (on_vo != on_vo_) {
    est_.rebase();
    on_vo_ = on_vo;
  }
  if (on_vo) {
    if (vo.chain_started()) {
      const Vec3d p = vo.body_pose().t;
      est_.track(Pose2{p.x(), p.y(), 0.0});
    }
  } else {
    est_.track(dr.pose_at(now_ns));
  }
  double depth_m = 0.0;  // z: the vehicle's depth sensor (QNAV_DEPTH_IN), absolute
  if (in.depth_m(now_ns, &depth_m)) est_.set_down(depth_m);
  MavSnapshot s;
  s.now_ns = now_ns;
  s.mode = mode;
  s.faults = faults;
  s.loss = (faults & (qc::fault::kDvlLost | qc::fault::kAttitudeLost)) != 0 || (on_vo && (faults & qc::fault::kCameraLost) != 0);
  s.have_attitude = in.has_attitude() && !(faults & qc::fault::kAttitudeLost);
  s.world_R_body = in.attitude();
  s.have_velocity = dr.has_velocity() && !(faults & qc::fault::kDvlLost);
  s.vx_mps = dr.forward_mps();
  s.vy_mps = dr.starboard_mps();
  s.altitude_m = (faults & qc::fault::kDvlLost) ? -1.0 : in.dvl_altitude_m();
  const bool fix_possible = mode == qc::Mode::kRepeat && !(faults & (qc::fault::kSonarLost | qc::fault::kAttitudeLost));
  s.localised = fix_possible && step.confident;
  s.confidence_pct = fix_possible ? 100.0 * static_cast<double>(step.probability) : 0.0;
  s.estimate = &est_;
  s.in_repeat = mode == qc::Mode::kRepeat;
  s.route_fix = route_fix_;
  s.guidance_valid = guidance_valid_ && fix_possible;
  s.cross_track_m = step.guidance.cross_track_m;
  s.cross_track_sigma_m = step.guidance.cross_track_sigma_m;
  s.side = static_cast<int>(step.guidance.side);
  s.node = step.guidance.node;
  s.waypoint_ne = waypoint_ne_;
  mav_->publish(s, *tx_);
}

void NavSource::log_counters(const IoCounters& io) const noexcept {
  if (!mav_ || !ctx_.events()) return;
  const auto& mc = mav_->counters();
  std::fprintf(ctx_.log,
               "{\"event\":\"mavlink\",\"t_s\":%.1f,\"frames_rx\":%u,\"odometry_sent\":%u,\"commands_accepted\":%u,\"targets_sent\":%u,"
               "\"reset_counter\":%u,\"fixes\":%u,\"parser_rejects\":%u,\"rx_overflow\":%u,\"tx_errors\":%u,\"device_errors\":%u,"
               "\"foreign_system\":%u,\"unused_message\":%u,\"cmd_wrong_sender\":%u,\"cmd_not_for_us\":%u,\"cmd_unsupported\":%u,"
               "\"cmd_bad_param\":%u,\"bad_attitude\":%u,\"tx_queue_full\":%u,\"cmd_unsigned\":%u,\"signing_rejects\":%u}\n",
               ctx_.clock->t_s(), mav_->frames_rx(), mav_->odometry_sent(), mav_->commands_accepted(), mav_->targets_sent(), est_.reset_counter(),
               est_.fixes(), mav_->parser_rejects(), io.mav_rx_overflow.load(), io.mav_tx_errors.load(), io.mav_device_errors.load(),
               mc.get(MavCounter::kForeignSystem), mc.get(MavCounter::kUnusedMessage), mc.get(MavCounter::kCmdWrongSender),
               mc.get(MavCounter::kCmdNotForUs), mc.get(MavCounter::kCmdUnsupported), mc.get(MavCounter::kCmdBadParam),
               mc.get(MavCounter::kBadAttitude), mc.get(MavCounter::kTxQueueFull), mc.get(MavCounter::kCmdUnsigned), mav_->signing_rejects());
}

}  // namespace qnav::daemon
