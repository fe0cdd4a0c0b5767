// The canned input of the timing stage "map" (canned.hpp: CannedMap): qnavd's map-mode step on the
// synthetic downward-camera loop. Kept out of canned.cpp so the freestanding LEON3 workload
// (test/timing/freestanding/sources.cmake) does not need firmware/pipeline/topo_mapper.
#include <cmath>
#include <vector>

#include "drivers/downward_sim/seabed_scene.hpp"
#include "firmware/pipeline/topo_mapper.hpp"
#include "nav/core/arena.hpp"
#include "test/timing/canned.hpp"

namespace qnav::timing {

namespace {
constexpr int kFramesPerLap = 90;       // qnav map eval's loop
constexpr double kRadiusM = 0.8, kAltitudeM = 2.0, kSpacingM = 0.2;
constexpr std::size_t kMaxNodes = 1024;  // qnavd's map.max_nodes default
}  // namespace

struct CannedMap::Impl {
  pipeline::TopoMapperConfig config;
  std::unique_ptr<ArenaStorage> arena;
  pipeline::TopoMapper mapper;
  ImageU8 frames[kSteps + 1];
  pipeline::MapperStep out;
};

CannedMap::CannedMap() : d_(new Impl) {}
CannedMap::~CannedMap() = default;

Status CannedMap::init() {
  Impl& d = *d_;
  const sim::downward::Camera cam;
  {
    const sim::downward::Seabed seabed;  // 1250 x 1250 floats, freed at the end of this block
    for (int k = 0; k <= kSteps; ++k) {
      Result<ImageU8> img = ImageU8::allocate(cam.width, cam.height);
      if (!img) return img.status();
      d.frames[k] = std::move(img.value());
      sim::downward::render(seabed, cam, sim::downward::loop_pose(k, kFramesPerLap, kRadiusM, kAltitudeM), d.frames[k].view());
    }
  }
  const vision::PinholeRadTan pinhole = vision::ideal_pinhole(cam.f, cam.cx, cam.cy, cam.width, cam.height);
  d.config = pipeline::topo_mapper_config(cam.width, cam.height, true, pinhole, false, true, true, kSpacingM, kMaxNodes);
  d.arena = std::make_unique<ArenaStorage>(pipeline::TopoMapper::arena_bytes(d.config));
  return d.mapper.init(d.config, *d.arena);
}

void CannedMap::restart() {
  Impl& d = *d_;
  d.arena->reset();
  (void)d.mapper.init(d.config, *d.arena);
  (void)d.mapper.step(ConstImageViewU8(d.frames[0].view()), kAltitudeM, d.out);
}

std::uint64_t CannedMap::step(int k) {
  Impl& d = *d_;
  Hash h;
  if (k < 0 || k >= kSteps) return 0;
  if (!d.mapper.step(ConstImageViewU8(d.frames[k + 1].view()), kAltitudeM, d.out).is_ok()) return 0;
  const topo::ChainStep& c = d.out.chain;
  if (c.status != topo::StepStatus::kOk) return 0;
  h.add(static_cast<std::uint64_t>(c.keypoints));
  h.add(static_cast<std::uint64_t>(c.matches));
  h.add(static_cast<std::uint64_t>(c.inliers));
  h.add(c.pose.position_m.x());
  h.add(c.pose.position_m.y());
  h.add(c.pose.heading_rad);
  h.add(static_cast<std::uint64_t>(d.out.observed ? 1 : 0));
  h.add(static_cast<std::uint64_t>(d.out.place.kind));
  h.add(static_cast<std::uint64_t>(d.out.place.node));
  h.add(static_cast<std::uint64_t>(d.mapper.map().node_count()));
  return h.value();
}

}  // namespace qnav::timing
