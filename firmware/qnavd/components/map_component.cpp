#include "firmware/qnavd/components/map_component.hpp"

#include "firmware/qnavd/software_fault.hpp"

#include <algorithm>
#include <cmath>

#include "drivers/map_store/map_file.hpp"
#include "drivers/qnavcan/messages.hpp"
#include "nav/core/geometry.hpp"

namespace qnav::daemon {

namespace qc = drivers::qnavcan;

Status MapComponent::init(StaticMemory* mem, qc::QnavCanPublisher& publisher) {
  publisher_ = &publisher;
  if (!map_runs(*ctx_.cfg)) return Status::ok();
  const pipeline::TopoMapperConfig mc = map_mapper_config(*ctx_.cfg);
  Result<Arena*> a = arena_.take(mem, "map", pipeline::TopoMapper::arena_bytes(mc));
  if (!a) return a.status();
  map_arena_ = a.value();
  QNAV_RETURN_IF_ERROR(mapper_.init(mc, *map_arena_));
  ready_ = true;
  return Status::ok();
}

// A new map (the mapper re-initialised in its arena: no heap), written to route_dir/map_<id>.qmap
// from its first node on; the file of an earlier map with this id stays whole until then.
ModeReject MapComponent::enter(std::uint16_t map_id) noexcept {
  map_arena_->reset();
  if (!mapper_.init(map_mapper_config(*ctx_.cfg), *map_arena_)) return ModeReject::kUnsupportedMode;  // cannot happen: init sized it
  std::snprintf(path_, sizeof path_, "%s/map_%u.qmap", ctx_.cfg->route_dir.c_str(), static_cast<unsigned>(map_id));
  open_ = true;
  node_ = topo::kNoNode;
  mode_start_ns_ = ctx_.clock->now_ns;
  return ModeReject::kNone;
}

void MapComponent::leave(std::uint16_t map_id) noexcept {
  if (!open_) return;
  save();
  if (ctx_.log)
    std::fprintf(ctx_.log, "{\"event\":\"map_closed\",\"route_id\":%u,\"nodes\":%zu,\"edges\":%zu,\"frames\":%u,\"bad_frames\":%u,"  // frames: since start
                           "\"file\":\"%s\",\"saves\":%u,\"save_errors\":%u}\n",
                 map_id, mapper_.map().node_count(), mapper_.map().edge_count(), frames_, bad_frames_, path_, saves_, save_errors_);
  open_ = false;
}

void MapComponent::save() noexcept {
  const Status s = drivers::map_store::save_map(store_, path_, mapper_.map(), mapper_.metric());
  ++saves_;
  if (!s) {
    ++save_errors_;
    if (ctx_.log) std::fprintf(ctx_.log, "{\"event\":\"error\",\"what\":\"map: %s not saved: %s\"}\n", path_, s.message());
  }
}

bool MapComponent::camera_lost(std::int64_t now_ns) const noexcept {
  return now_ns - std::max(order_.last_ns, mode_start_ns_) > static_cast<std::int64_t>(ctx_.cfg->map_stale_s * 1e9);
}

bool MapComponent::on_frame(const FrameMsg& f, const std::uint8_t* image) noexcept {
  if (!QNAVD_CHECK(f.width == ctx_.cfg->map_width && f.height == ctx_.cfg->map_height, "downward frame of another size than map.width x map.height"))
    return false;
  ++frames_;
  const ConstImageViewU8 img = ConstImageViewU8::make(image, ctx_.cfg->map_width, ctx_.cfg->map_height).value();
  const Status s = mapper_.step(img, ctx_.cfg->map_altitude_m > 0.0 ? ctx_.cfg->map_altitude_m : -1.0, step_);
  if (!s) ++step_errors_;
  if (step_.chain.status != topo::StepStatus::kOk) ++bad_frames_;
  if (step_.observed && step_.place.kind == topo::ObserveKind::kCreated) save();  // durable as it grows
  publish(f);
  return true;
}

// QNAV_MAP_POSE + QNAV_MAP_STATUS for this frame (sent once, at this loop's outputs).
void MapComponent::publish(const FrameMsg& f) noexcept {
  const pipeline::MapperStep& st = step_;
  const topo::ChainStep& c = st.chain;
  if (st.observed && st.place.node != topo::kNoNode) node_ = st.place.node;
  qc::MapPose p;
  const Vec2d& pos = c.pose.metric ? c.pose.position_m : c.pose.position_px;
  p.x = qc::clamp_to_signal(qc::kIdMapPose, "X", pos.x());
  p.y = qc::clamp_to_signal(qc::kIdMapPose, "Y", pos.y());
  p.heading_rad = qc::clamp_to_signal(qc::kIdMapPose, "Heading", std::remainder(c.pose.heading_rad, 2.0 * kPi));
  qc::MapStatus m;
  static_assert(topo::kNoNode == qc::kMapNoNode, "no node: the same value in the map and on the wire");
  m.node_id = node_;  // map.max_nodes <= 65534: a node id is below 65535
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

void MapComponent::log_frame(const FrameMsg& f, double latency_ms) const noexcept {
  const pipeline::MapperStep& st = step_;
  const topo::ChainStep& c = st.chain;
  if (ctx_.json()) {
    std::fprintf(ctx_.log,
                 "{\"event\":\"map\",\"seq\":%u,\"t_s\":%.3f,\"status\":\"%s\",\"bad_input\":%u,\"keyframe\":%u,\"new_keyframe\":%s,"
                 "\"keypoints\":%u,\"inliers\":%u,\"x_px\":%.4f,\"y_px\":%.4f,\"heading_deg\":%.5f,\"metric\":%s,\"x_m\":%.5f,"
                 "\"y_m\":%.5f,\"node\":%d,\"kind\":\"%s\",\"revisit\":%s,\"nodes\":%zu,\"edges\":%zu,\"latency_ms\":%.2f}\n",
                 f.sequence, ctx_.clock->t_s(), topo::to_string(c.status), c.bad_input, c.keyframe_index, c.new_keyframe ? "true" : "false",
                 c.keypoints, c.inliers, c.pose.position_px.x(), c.pose.position_px.y(), rad_to_deg(c.pose.heading_rad),
                 c.pose.metric ? "true" : "false", c.pose.position_m.x(), c.pose.position_m.y(),
                 st.observed && st.place.node != topo::kNoNode ? static_cast<int>(st.place.node) : -1,
                 st.observed ? topo::to_string(st.place.kind) : "none", st.observed && st.place.revisit ? "true" : "false",
                 mapper_.map().node_count(), mapper_.map().edge_count(), latency_ms);
  } else if (ctx_.key_value()) {
    std::fprintf(ctx_.log, "map seq=%u status=%s x_px=%.2f y_px=%.2f heading_deg=%.2f nodes=%zu\n", f.sequence, topo::to_string(c.status),
                 c.pose.position_px.x(), c.pose.position_px.y(), rad_to_deg(c.pose.heading_rad), mapper_.map().node_count());
  }
}

}  // namespace qnav::daemon
