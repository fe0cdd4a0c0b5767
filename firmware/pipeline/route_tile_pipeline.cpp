#include "firmware/pipeline/route_tile_pipeline.hpp"

#include <algorithm>

namespace qnav::pipeline {

double route_aligned_stride_m(const route::LocaliserStep& st, Span<const route::NodeMeta> meta, route::RouteDirection direction,
                              double stride_m) noexcept {
  const route::GuidanceOutput& g = st.guidance;
  // Offsets from a registration guidance trusts: tracking, or (not yet confident) a strong one.
  if (!(stride_m > 0.0) || g.offsets != route::OffsetSource::kRegistration) return 0.0;
  const std::size_t n = g.node;
  const bool fwd = direction == route::RouteDirection::kForward;
  if (n >= meta.size() || (fwd && n + 1 >= meta.size()) || (!fwd && n == 0)) return 0.0;
  const std::size_t next = fwd ? n + 1 : n - 1;
  const double gap = std::abs(meta[next].along_m - meta[n].along_m);
  const double want = gap - g.along_track_m;
  if (!std::isfinite(want)) return 0.0;
  return std::min(1.25 * stride_m, std::max(0.75 * stride_m, want));
}

std::size_t RouteTilePipeline::arena_bytes(const RouteTileConfig& config) noexcept {
  return sonar::ScanlineCorrector::arena_bytes(config.corrector) + sonar::TileBuilder::arena_bytes(config.tiles) +
         (config.extract_features ? route::TileFeatureExtractor::arena_bytes(config.features) : 0) + 4096;
}

Status RouteTilePipeline::init(const RouteTileConfig& config) {
  arena_ = std::make_unique<ArenaStorage>(arena_bytes(config));
  if (!arena_->valid()) return Status(StatusCode::kCapacityExceeded, "route tiles: cannot allocate arena");
  return init(config, *arena_);
}

Status RouteTilePipeline::init(const RouteTileConfig& config, Arena& arena) {
  cfg_ = config;
  corrector_ = std::make_unique<sonar::ScanlineCorrector>();
  builder_ = std::make_unique<sonar::TileBuilder>();
  features_ = std::make_unique<route::TileFeatureExtractor>();
  tile_ = std::make_unique<RouteTile>();
  QNAV_RETURN_IF_ERROR(corrector_->init(config.corrector, arena));
  QNAV_RETURN_IF_ERROR(builder_->init(config.tiles, arena));
  if (config.extract_features) QNAV_RETURN_IF_ERROR(features_->init(config.features, arena));
  std::size_t ring = 1;
  while (ring < 2 * static_cast<std::size_t>(std::max(1, config.tiles.scanlines_per_tile))) ring <<= 1;
  ring_.assign(ring, PingRecord{});
  ring_mask_ = ring - 1;
  reset_pass();
  return Status::ok();
}

void RouteTilePipeline::reset_pass() {
  if (builder_) builder_->reset();
  for (PingRecord& r : ring_) r = PingRecord{};
  last_tile_nav_m_ = 0.0;
  have_prev_nav_ = false;
  nav_dist_m_ = 0.0;
  truth_lateral_m_ = 0.0;
}

Status RouteTilePipeline::emit(const RouteTileSink& sink, bool* stop) {
  const sonar::SonarTile& t = builder_->tile();
  RouteTile& out = *tile_;
  route::TileGeometry g;
  g.resolution_m = t.resolution_m;
  g.origin_north_m = t.origin_north_m;
  g.origin_east_m = t.origin_east_m;
  g.pose = t.pose;
  if (cfg_.extract_features) {
    const Status s = features_->extract(t.intensity, t.coverage, g, out.node);
    if (!s && s.code() != StatusCode::kEmpty) return s;
  } else {
    out.node.keypoints.clear();
    out.node.meta.pose = t.pose;
    out.node.meta.keypoint_count = 0;
  }
  const std::uint32_t mid = (t.first_ping + t.last_ping) / 2;
  out.node.meta.stamp_ns = (t.first_stamp_ns + t.last_stamp_ns) / 2;
  const PingRecord* mid_rec = record(mid);
  out.node.meta.along_m = mid_rec ? mid_rec->nav_dist_m : nav_dist_m_;
  out.nav_step_m = out.node.meta.along_m - last_tile_nav_m_;
  last_tile_nav_m_ = out.node.meta.along_m;
  out.truth_along_m = mid_rec && mid_rec->has_truth ? mid_rec->truth_along_m : -1.0;
  out.truth_lateral_m = truth_lateral_m_;
  const std::uint32_t pose_ping = t.first_ping + (t.last_ping - t.first_ping + 1) / 2;  // the builder's pose slot
  const PingRecord* pose_rec = record(pose_ping);
  out.has_truth_pose = pose_rec != nullptr && pose_rec->has_truth;
  out.truth_pose = out.has_truth_pose ? pose_rec->truth_pose : Pose2{};
  out.coverage_fraction = t.coverage_fraction;
  out.tile_index = t.index;
  out.ping_first = t.first_ping;
  out.ping_last = t.last_ping;
  if (!sink(out) && stop != nullptr) *stop = true;
  return Status::ok();
}

const RouteTilePipeline::PingRecord* RouteTilePipeline::record(std::uint32_t ping_number) const noexcept {
  const PingRecord& r = ring_[ping_number & ring_mask_];
  return r.used && r.ping_number == ping_number ? &r : nullptr;
}

Status RouteTilePipeline::push_ping(const sonar::SonarPing& ping, const Pose2& nav, const RouteTileSink& sink, bool* stop) {
  return push(ping, nav, nullptr, sink, stop);
}

Status RouteTilePipeline::push_ping(const sonar::SonarPing& ping, const Pose2& nav, const PingTruth& truth, const RouteTileSink& sink,
                                    bool* stop) {
  return push(ping, nav, &truth, sink, stop);
}

Status RouteTilePipeline::push(const sonar::SonarPing& ping, const Pose2& nav, const PingTruth* truth, const RouteTileSink& sink, bool* stop) {
  if (have_prev_nav_) nav_dist_m_ += std::hypot(nav.x_m - prev_nav_.x_m, nav.y_m - prev_nav_.y_m);
  prev_nav_ = nav;
  have_prev_nav_ = true;
  PingRecord& rec = ring_[ping.ping_number & ring_mask_];
  rec.ping_number = ping.ping_number;
  rec.used = true;
  rec.nav_dist_m = nav_dist_m_;
  rec.has_truth = truth != nullptr;
  rec.truth_along_m = truth ? truth->along_m : -1.0;
  rec.truth_pose = truth ? truth->pose : Pose2{};
  if (truth) truth_lateral_m_ = truth->lateral_m;
  sonar::CorrectedScanline line;
  const Status cs = corrector_->correct(ping, line);
  if (!cs) {
    ++rejected_pings_;  // counted by the corrector; the ping is skipped
    return Status::ok();
  }
  Result<bool> built = builder_->push(line, nav);
  if (!built) {
    ++rejected_pings_;  // counted by the builder
    return Status::ok();
  }
  if (*built) return emit(sink, stop);
  return Status::ok();
}

Status RouteTilePipeline::flush(const RouteTileSink& sink) {
  return flush(sink, builder_->by_distance() ? 2 : builder_->config().scanlines_per_tile / 2);
}

Status RouteTilePipeline::flush(const RouteTileSink& sink, int min_scanlines) {
  Result<bool> built = builder_->flush(min_scanlines);
  if (built && *built) return emit(sink, nullptr);
  return Status::ok();
}

}  // namespace qnav::pipeline
