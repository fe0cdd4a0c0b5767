#include "firmware/pipeline/topo_mapper.hpp"

#include <cmath>

namespace qnav::pipeline {

double default_node_spacing(bool metric) noexcept { return metric ? 0.2 : 30.0; }

topo::TopoMapConfig topo_map_config(double node_spacing, std::size_t max_nodes) noexcept {
  topo::TopoMapConfig c;
  c.max_nodes = max_nodes;
  c.node_spacing = node_spacing;
  c.gate = 1.5 * node_spacing;
  c.max_edge_length = 3.0 * node_spacing;
  return c;
}

topo::HomographyChainConfig chain_config(int width, int height, const topo::CameraIntrinsics& camera) noexcept {
  topo::HomographyChainConfig c;
  c.max_width = width;
  c.max_height = height;
  if (camera.fx > 0.0) c.camera = camera;
  return c;
}

TopoMapperConfig topo_mapper_config(int width, int height, bool have_camera, const vision::PinholeRadTan& camera, bool undistort,
                                    bool mapping, bool metric, double node_spacing, std::size_t max_nodes) noexcept {
  TopoMapperConfig c;
  topo::CameraIntrinsics k;
  if (have_camera) {
    k.fx = camera.fx;
    k.fy = camera.fy;
    k.cx = camera.cx;
    k.cy = camera.cy;
  }
  c.chain = chain_config(width, height, k);
  c.undistort = have_camera && undistort;
  c.camera = camera;
  c.mapping = mapping;
  c.metric = metric;
  c.map = topo_map_config(std::isnan(node_spacing) ? default_node_spacing(metric) : node_spacing, max_nodes);
  return c;
}

namespace {
vision::RemapConfig remap_config(const TopoMapperConfig& c) noexcept {
  vision::RemapConfig rc;
  rc.max_width = c.chain.max_width;
  rc.max_height = c.chain.max_height;
  return rc;
}
constexpr std::size_t kImageAlign = 64;  // slack for the rectified frame's alignment in the arena
}  // namespace

std::size_t TopoMapper::arena_bytes(const TopoMapperConfig& c) noexcept {
  std::size_t n = topo::HomographyChain::arena_bytes(c.chain);
  if (c.undistort)
    n += vision::RemapTable::arena_bytes(remap_config(c)) +
         static_cast<std::size_t>(c.chain.max_width) * static_cast<std::size_t>(c.chain.max_height) + kImageAlign;
  if (c.mapping) n += topo::TopoMap::arena_bytes(c.map);
  return n;
}

Status TopoMapper::init(const TopoMapperConfig& config, Arena& arena) noexcept {
  ready_ = false;
  config_ = config;
  QNAV_RETURN_IF_ERROR(chain_.init(config_.chain, arena));
  if (config_.undistort) {
    if (config_.camera.width != config_.chain.max_width || config_.camera.height != config_.chain.max_height)
      return Status(StatusCode::kInvalidArgument, "topo mapper: the camera model's size is not the frame size");
    QNAV_RETURN_IF_ERROR(remap_.init(remap_config(config_), arena));
    QNAV_RETURN_IF_ERROR(remap_.build_undistort(config_.camera, vision::FlatPortRefraction{}));
    Result<ImageU8> img = ImageU8::allocate(arena, config_.chain.max_width, config_.chain.max_height);
    if (!img) return img.status();
    rectified_ = img->view();
  }
  if (config_.mapping) {
    encoder_.init();
    QNAV_RETURN_IF_ERROR(map_.init(config_.map, arena));
  }
  ready_ = true;
  return Status::ok();
}

Status TopoMapper::undistort(ConstImageViewU8 frame, ConstImageViewU8& out) noexcept {
  out = frame;
  if (!ready_) return Status(StatusCode::kNotReady, "topo mapper: used before init");
  // A frame of another size goes to the chain as it is: the chain refuses it (kBadInput, kFrameSize).
  if (!config_.undistort || frame.empty() || frame.width() != config_.camera.width || frame.height() != config_.camera.height)
    return Status::ok();
  QNAV_RETURN_IF_ERROR(remap_.apply(frame, rectified_));
  out = ConstImageViewU8(rectified_);
  return Status::ok();
}

Status TopoMapper::register_frame(ConstImageViewU8 frame, double altitude_m, MapperStep& out) noexcept {
  out.observed = false;
  out.place = topo::ObserveResult{};
  if (!ready_) return Status(StatusCode::kNotReady, "topo mapper: used before init");
  return chain_.process(frame, altitude_m, out.chain);
}

Status TopoMapper::unreadable_frame(MapperStep& out) noexcept { return register_frame(ConstImageViewU8(), -1.0, out); }

void TopoMapper::observe(MapperStep& out) noexcept {
  if (!ready_ || !config_.mapping || out.chain.status != topo::StepStatus::kOk) return;
  topo::PlaceSignature sig;
  encoder_.encode(chain_.current_keypoints(), sig);
  const Vec2d p = config_.metric ? out.chain.pose.position_m : out.chain.pose.position_px;
  if (map_.observe(sig, p, out.chain.pose.heading_rad, out.place)) out.observed = true;
}

Status TopoMapper::step(ConstImageViewU8 frame, double altitude_m, MapperStep& out) noexcept {
  ConstImageViewU8 in;
  QNAV_RETURN_IF_ERROR(undistort(frame, in));
  QNAV_RETURN_IF_ERROR(register_frame(in, altitude_m, out));
  observe(out);
  return Status::ok();
}

}  // namespace qnav::pipeline
