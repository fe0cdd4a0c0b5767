// pipeline::TopoMapper (the downward-camera mapping wiring `qnav map` and qnavd share): the synthetic
// loop maps within the trajectory goal, the per-frame path allocates nothing after init, and a
// black or saturated frame is flagged with the pose and the map left as they were.
#include "firmware/pipeline/topo_mapper.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "drivers/downward_sim/seabed_scene.hpp"
#include "test/support/alloc_guard.hpp"

namespace qnav::pipeline {
namespace {

namespace dw = qnav::sim::downward;

constexpr int kPerLap = 90;
constexpr double kRadius = 0.8, kAltitude = 2.0;

const dw::Seabed& seabed() {
  static const dw::Seabed s;
  return s;
}

// The settings `qnav map eval` runs: the simulator's pinhole, metres, the default 0.2 m spacing.
TopoMapperConfig loop_config(bool undistort) {
  const dw::Camera cam;
  const vision::PinholeRadTan k = vision::ideal_pinhole(cam.f, cam.cx, cam.cy, cam.width, cam.height);
  return topo_mapper_config(cam.width, cam.height, true, k, undistort, true, true, std::nan(""), 256);
}

// The true camera position in frame 0's camera axes (the chain's metric frame).
Vec2d truth_m(int k) {
  const dw::CameraPose p0 = dw::loop_pose(0, kPerLap, kRadius, kAltitude), pk = dw::loop_pose(k, kPerLap, kRadius, kAltitude);
  const double c = std::cos(p0.yaw_rad), s = std::sin(p0.yaw_rad);
  const Vec2d d(pk.x_m - p0.x_m, pk.y_m - p0.y_m);
  return Vec2d(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
}

struct Rig {
  TopoMapperConfig config;
  ArenaStorage arena;
  TopoMapper mapper;
  ImageU8 frame;
  explicit Rig(const TopoMapperConfig& c)
      : config(c), arena(TopoMapper::arena_bytes(c)), frame(ImageU8::allocate(c.chain.max_width, c.chain.max_height).value()) {
    const Status s = mapper.init(config, arena);
    EXPECT_TRUE(s.is_ok()) << s.message();
  }
  MapperStep see(int k) {
    dw::render(seabed(), dw::Camera{}, dw::loop_pose(k, kPerLap, kRadius, kAltitude), frame.view());
    MapperStep out;
    EXPECT_TRUE(mapper.step(frame.view(), kAltitude, out).is_ok());
    return out;
  }
};

TEST(TopoMapper, DefaultsAreTheToolsTunedValues) {
  EXPECT_EQ(default_node_spacing(true), 0.2);
  EXPECT_EQ(default_node_spacing(false), 30.0);
  const topo::TopoMapConfig m = topo_map_config(0.2, 64);
  EXPECT_EQ(m.max_nodes, 64u);
  EXPECT_DOUBLE_EQ(m.gate, 0.3);
  EXPECT_DOUBLE_EQ(m.max_edge_length, 0.6);
  const TopoMapperConfig c = loop_config(false);
  EXPECT_EQ(c.chain.max_width, 320);
  EXPECT_EQ(c.chain.camera.fx, 300.0);
  EXPECT_FALSE(c.undistort);
  EXPECT_TRUE(c.metric);
  // No camera: pixels, no intrinsics, no undistortion even when asked.
  const TopoMapperConfig px = topo_mapper_config(320, 240, false, vision::PinholeRadTan{}, true, true, false, std::nan(""), 64);
  EXPECT_FALSE(px.undistort);
  EXPECT_EQ(px.chain.camera.fx, 0.0);
  EXPECT_EQ(px.map.node_spacing, 30.0);
}

// The goal (<= 2 % of path on the synthetic sequence) for the first lap, every frame
// registered and observed, the map growing about once per node spacing, no heap in any step.
TEST(TopoMapper, LoopTrajectoryWithinTwoPercentOfPathAndNoHeapPerFrame) {
  Rig rig(loop_config(false));
  constexpr int kFrames = kPerLap;
  double max_err = 0.0;
  int created = 0;
  for (int k = 0; k < kFrames; ++k) {
    dw::render(seabed(), dw::Camera{}, dw::loop_pose(k, kPerLap, kRadius, kAltitude), rig.frame.view());
    MapperStep out;
    QNAV_EXPECT_NO_ALLOC(EXPECT_TRUE(rig.mapper.step(rig.frame.view(), kAltitude, out).is_ok()));
    ASSERT_EQ(out.chain.status, topo::StepStatus::kOk) << "frame " << k;
    ASSERT_TRUE(out.observed) << "frame " << k;
    created += out.place.kind == topo::ObserveKind::kCreated ? 1 : 0;
    max_err = std::max(max_err, (out.chain.pose.position_m - truth_m(k)).norm());
  }
  const double path = 2.0 * 3.14159265358979323846 * kRadius * (kFrames - 1) / kPerLap;
  EXPECT_LT(max_err, 0.02 * path) << "max error " << max_err << " m over " << path << " m";
  // A 5 m loop at 0.2 m spacing: ~25 nodes (SOM adaptation moves them, so not exactly).
  EXPECT_GE(created, 15);
  EXPECT_LE(created, 35);
  EXPECT_EQ(rig.mapper.map().node_count(), static_cast<std::size_t>(created));
}

// With a camera model the frame goes through the undistortion table first (identity here: no
// distortion), in the mapper's own buffer, without heap; a frame of another size is not undistorted
// but refused by the chain (kFrameSize).
TEST(TopoMapper, UndistortsInItsOwnBufferAndRefusesOtherSizes) {
  Rig rig(loop_config(true));
  for (int k = 0; k < 4; ++k) {
    dw::render(seabed(), dw::Camera{}, dw::loop_pose(k, kPerLap, kRadius, kAltitude), rig.frame.view());
    MapperStep out;
    QNAV_EXPECT_NO_ALLOC(EXPECT_TRUE(rig.mapper.step(rig.frame.view(), kAltitude, out).is_ok()));
    ASSERT_EQ(out.chain.status, topo::StepStatus::kOk) << k;
    EXPECT_LT((out.chain.pose.position_m - truth_m(k)).norm(), 0.01);
  }
  ImageU8 small = ImageU8::allocate(160, 120).value();
  std::memset(small.data(), 128, 160 * 120);
  MapperStep out;
  ASSERT_TRUE(rig.mapper.step(small.view(), kAltitude, out).is_ok());
  EXPECT_EQ(out.chain.status, topo::StepStatus::kBadInput);
  EXPECT_EQ(out.chain.bad_input, topo::kFrameSize);
  EXPECT_FALSE(out.observed);
}

// A black and a saturated frame in the middle of the loop: flagged (kBadInput with the reason), not
// observed, the pose and every node untouched; the next good frame registers where it should.
TEST(TopoMapper, BlackOrSaturatedFrameIsFlaggedAndTheMapLeftIntact) {
  Rig rig(loop_config(false));
  for (int k = 0; k < 20; ++k) ASSERT_EQ(rig.see(k).chain.status, topo::StepStatus::kOk) << k;
  const topo::TopoMap& map = rig.mapper.map();
  const std::size_t nodes = map.node_count(), edges = map.edge_count();
  std::vector<Vec2d> positions;
  for (std::uint16_t i = 0; i < map.capacity(); ++i)
    if (map.active(i)) positions.push_back(map.node(i).position);
  const topo::ChainPose pose = rig.mapper.chain().pose();

  struct Bad {
    std::uint8_t grey;
    std::uint8_t reason;
  };
  for (const Bad bad : {Bad{0, topo::kFrameDark}, Bad{255, topo::kFrameSaturated}}) {
    std::memset(rig.frame.data(), bad.grey, static_cast<std::size_t>(rig.frame.width()) * rig.frame.height());
    MapperStep out;
    ASSERT_TRUE(rig.mapper.step(rig.frame.view(), kAltitude, out).is_ok());
    EXPECT_EQ(out.chain.status, topo::StepStatus::kBadInput);
    EXPECT_TRUE(out.chain.bad_input & bad.reason) << int(out.chain.bad_input);
    EXPECT_FALSE(out.observed);
    EXPECT_EQ(out.chain.pose.position_px, pose.position_px);
    EXPECT_EQ(rig.mapper.chain().pose().position_px, pose.position_px);
    EXPECT_EQ(rig.mapper.chain().pose().heading_rad, pose.heading_rad);
    EXPECT_EQ(map.node_count(), nodes);
    EXPECT_EQ(map.edge_count(), edges);
    std::size_t j = 0;
    for (std::uint16_t i = 0; i < map.capacity(); ++i) {
      if (map.active(i)) {
        EXPECT_EQ(map.node(i).position, positions[j++]);
      }
    }
  }
  const MapperStep next = rig.see(20);
  ASSERT_EQ(next.chain.status, topo::StepStatus::kOk);
  EXPECT_TRUE(next.observed);
  EXPECT_LT((next.chain.pose.position_m - truth_m(20)).norm(), 0.01);
}

TEST(TopoMapper, RefusesUseBeforeInitAndACameraOfAnotherSize) {
  TopoMapper mapper;
  MapperStep out;
  ImageU8 img = ImageU8::allocate(320, 240).value();
  EXPECT_EQ(mapper.step(img.view(), 2.0, out).code(), StatusCode::kNotReady);
  TopoMapperConfig c = loop_config(true);
  c.camera.width = 640;
  ArenaStorage arena(TopoMapper::arena_bytes(c));
  EXPECT_EQ(mapper.init(c, arena).code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace qnav::pipeline
