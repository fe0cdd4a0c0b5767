#include "firmware/pipeline/route_repeat_session.hpp"

namespace qnav::pipeline {

Status RouteRepeatSession::init(const RepeatSessionConfig& config, Arena* arena) {
  if (!(config.entry_prior >= 0.0 && config.entry_prior < 1.0))
    return Status(StatusCode::kInvalidArgument, "repeat session: entry_prior must be in [0, 1)");
  config_ = config;
  QNAV_RETURN_IF_ERROR(arena != nullptr ? repeater_.init(config.localiser, *arena) : repeater_.init(config.localiser));
  if (config.experiences_per_node > 0)
    QNAV_RETURN_IF_ERROR(experiences_.init(config.max_nodes, config.experiences_per_node, config.learn,
                                           config.backfill ? &repeater_.config().registration : nullptr));
  return Status::ok();
}

Status RouteRepeatSession::start(const route::RouteParams& params, Span<const route::NodeMeta> meta, route::NodeSource& nodes, bool reverse) noexcept {
  end();
  reverse_ = reverse;
  eq5_ = false;
  tiles_ = 0;
  meta_ = meta;
  nodes_ = &nodes;
  params_ = params;
  repeater_.set_motion(direction(), route::MotionModel::kOdometry);
  QNAV_RETURN_IF_ERROR(repeater_.start(params, meta, nodes));
  return repeater_.apply_entry_prior(config_.entry_prior, kEntryPriorSigmaNodes);
}

ExperiencesOpened RouteRepeatSession::open_experiences(const char* route_path, bool learn) noexcept {
  ExperiencesOpened r;
  if (with_experiences_) end();
  if (config_.experiences_per_node == 0) return r;  // configured without experiences
  if (nodes_ == nullptr) {
    r.status = Status(StatusCode::kNotReady, "route repeat: open_experiences() before start()");
    return r;
  }
  r.status = experiences_.open(route_path, params_, *nodes_, learn, &r.report);
  if (!r.status) {
    (void)repeater_.attach_experiences(nullptr, nullptr);
    return r;
  }
  if (!experiences_.has_experiences()) return r;  // no companion, not learning
  r.status = experiences_.attach(repeater_, meta_, reverse_);
  if (!r.status) {
    r.at_attach = true;
    experiences_.detach(repeater_);
    return r;
  }
  with_experiences_ = true;
  return r;
}

RepeatTileResult RouteRepeatSession::step(const RouteTile& tile, bool dvl_lost, route::LocaliserStep& out) noexcept {
  RepeatTileResult r;
  if (dvl_lost != eq5_) {  // the paper's eq. 5 while the DVL is lost, odometry again when it returns
    eq5_ = dvl_lost;
    repeater_.set_motion(direction(), eq5_ ? route::MotionModel::kPaperEq5 : route::MotionModel::kOdometry);
  }
  r.eq5 = eq5_;
  const double distance_m = tiles_ == 0 ? 0.0 : tile.nav_step_m;  // the pass's first tile: no travel yet
  ++tiles_;
  r.step = repeater_.step(tile.node, distance_m, out);
  if (r.step && with_experiences_) r.learn = experiences_.on_step(tile.node, distance_m, out, &r.learned);
  if (!r.step) {
    out = route::LocaliserStep{};
    out.guidance.status = route::GuidanceStatus::kHoldCourse;
    out.guidance.side = route::RouteSide::kUnknown;
  }
  return r;
}

double RouteRepeatSession::next_stride_m(const route::LocaliserStep& step, double configured_stride_m) const noexcept {
  return route_aligned_stride_m(step, meta_, direction(), configured_stride_m);
}

std::uint32_t RouteRepeatSession::end() noexcept {
  if (!with_experiences_) {
    experiences_.end_pass();  // a learning pass the localiser never attached to: nothing to drop
    return 0;
  }
  const std::uint32_t pass_learned = experiences_.learned();  // this pass's (begin_pass counts from 0)
  experiences_.detach(repeater_);
  with_experiences_ = false;
  return pass_learned;
}

}  // namespace qnav::pipeline
