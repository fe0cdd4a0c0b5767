#include "firmware/qnavd/components/sonar_tiles.hpp"

namespace qnav::daemon {

namespace qc = drivers::qnavcan;

Status SonarTiles::init(StaticMemory* mem) {
  Result<Arena*> a = arena_.take(mem, "tile_pipeline", pipeline::RouteTilePipeline::arena_bytes(ctx_.cfg->tiles));
  if (!a) return a.status();
  return tiles_.init(ctx_.cfg->tiles, *a.value());
}

Status SonarTiles::push(const PingMsg& p, const float* pool, std::size_t pool_stride, const Pose2& nav, const pipeline::RouteTileSink& sink) noexcept {
  const std::size_t half = pool_stride / 2;
  const float* base = pool + static_cast<std::size_t>(p.slot) * pool_stride;
  sonar::SonarPing ping;
  ping.stamp_ns = static_cast<std::uint64_t>(p.stamp.sample_ns);
  ping.ping_number = pass_ping_++;
  ping.port = Span<const float>(base, p.port_samples);
  ping.stbd = Span<const float>(base + half, p.stbd_samples);
  ping.slant_range_m = p.slant_range_m;
  ping.altitude_m = p.altitude_m;
  return p.has_truth ? tiles_.push_ping(ping, nav, p.truth, sink, nullptr) : tiles_.push_ping(ping, nav, sink, nullptr);
}

void SonarTiles::log(const TileReport& r) const noexcept {
  const route::LocaliserStep& st = r.step;
  if (ctx_.json()) {
    const bool repeat = r.mode == qc::Mode::kRepeat;
    std::fprintf(ctx_.log,
                 "{\"event\":\"tile\",\"seq\":%u,\"t_s\":%.1f,\"mode\":\"%s\",\"route_id\":%u,\"node_written\":%d,\"estimate\":%u,\"p\":%.3f,"
                 "\"entropy\":%.3f,\"inliers\":%u,\"status\":\"%s\",\"side\":\"%s\",\"cross_track_m\":%.2f,\"sigma_m\":%.2f,\"eq5\":%s,"
                 "\"reverse\":%s,\"truth_along_m\":%.1f,\"truth_lateral_m\":%.2f,\"latency_ms\":%.2f}\n",
                 r.seq, ctx_.clock->t_s(), qc::mode_name(r.mode), r.route_id, r.mode == qc::Mode::kTeach ? static_cast<int>(r.node_written) : -1,
                 st.estimate, static_cast<double>(st.probability), st.entropy, st.best_inliers,
                 repeat ? route::to_string(st.guidance.status) : "-", repeat ? route::to_string(st.guidance.side) : "-",
                 st.guidance.cross_track_m, st.guidance.cross_track_sigma_m, r.eq5_motion ? "true" : "false", r.reverse ? "true" : "false",
                 r.truth_along_m, r.truth_lateral_m, r.latency_ms);
  } else if (ctx_.key_value()) {
    std::fprintf(ctx_.log, "tile seq=%u mode=%s estimate=%u status=%s side=%s cross_track_m=%.2f sigma_m=%.2f\n", r.seq, qc::mode_name(r.mode),
                 st.estimate, route::to_string(st.guidance.status), route::to_string(st.guidance.side), st.guidance.cross_track_m,
                 st.guidance.cross_track_sigma_m);
  }
}

}  // namespace qnav::daemon
