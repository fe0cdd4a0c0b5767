// TopoMapper: the per-frame wiring of downward-camera mapping (underwater paper), shared by
// `qnav map` (frame directories, `qnav map eval`) and qnavd's map mode:
//   frame -> [RemapTable undistortion, when a camera model is given]
//         -> nav/topo HomographyChain (keypoints, ratio matching against the keyframe, robust
//            homography, eq. 2 chaining, keyframes; metric scale from the altitude)
//         -> [PlaceEncoder signature of the frame's keypoints -> TopoMap::observe at the chain's pose]
// A frame the chain refuses (black / saturated / textureless / unregistered) is not observed: the
// pose, the keyframe and the map are left as they were; the step says why.
// The tuned settings are defined here once (mapper_defaults): the chain's defaults from nav/topo with
// the frame size and camera, the map's node spacing (0.2 m metric, 30 mosaic px otherwise), its gate
// (1.5 x spacing) and longest edge (3 x spacing).
// Saving the map is the caller's (firmware/tools/map_file over a hal::FileStore): after a step whose
// place.kind is kCreated (durable as it grows, see map_file.hpp) and at the end.
// Memory: init() takes every buffer from the caller's Arena (arena_bytes()): the chain, the
// undistortion table and its output frame, the map; the PlaceEncoder (32 KB) is a member. step() and
// its parts allocate nothing. Time: one HomographyChain::process (nav/topo/homography_chain.hpp) +
// O(W H) undistortion + O(max_nodes 64) for the map.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/arena.hpp"
#include "nav/core/image.hpp"
#include "nav/core/status.hpp"
#include "nav/topo/homography_chain.hpp"
#include "nav/topo/topo_map.hpp"
#include "nav/vision/rectify.hpp"

namespace qnav::pipeline {

struct TopoMapperConfig {
  topo::HomographyChainConfig chain{};  // max_width/height: the frame size; camera: fx for metres
  bool undistort = false;               // frames undistorted through `camera` (RemapTable) first
  vision::PinholeRadTan camera{};       // the raw camera (when undistort)
  bool mapping = true;                  // build the topological map beside the chain
  bool metric = false;                  // map positions in metres (an altitude is given) else mosaic px
  topo::TopoMapConfig map{};
};

// The tuned defaults, defined once.
double default_node_spacing(bool metric) noexcept;  // 0.2 m, or 30 mosaic px
// The map configuration for a node spacing: gate 1.5 x spacing, longest edge 3 x spacing.
topo::TopoMapConfig topo_map_config(double node_spacing, std::size_t max_nodes) noexcept;
// The chain for W x H frames; camera intrinsics when fx > 0 (metric scale with an altitude).
topo::HomographyChainConfig chain_config(int width, int height, const topo::CameraIntrinsics& camera) noexcept;
// Everything for W x H frames: the chain (with the raw camera's intrinsics when have_camera), the
// undistortion when have_camera && undistort, the map in metres when metric (node spacing NaN = the
// default for the units).
TopoMapperConfig topo_mapper_config(int width, int height, bool have_camera, const vision::PinholeRadTan& camera, bool undistort,
                                    bool mapping, bool metric, double node_spacing, std::size_t max_nodes) noexcept;

struct MapperStep {
  topo::ChainStep chain;          // the chain's answer (status, pose, keypoints, inliers, ...)
  bool observed = false;          // the map took the frame (place is its answer)
  topo::ObserveResult place;      // kBadInput when not observed
};

class TopoMapper {
 public:
  TopoMapper() noexcept = default;
  TopoMapper(const TopoMapper&) = delete;
  TopoMapper& operator=(const TopoMapper&) = delete;

  static std::size_t arena_bytes(const TopoMapperConfig& config) noexcept;
  Status init(const TopoMapperConfig& config, Arena& arena) noexcept;

  // One frame (altitude_m <= 0 or NaN: unknown): undistort + register + observe. Errors (Status)
  // only for misuse or an undistortion table that refuses the frame; the frame's fate is in out.
  Status step(ConstImageViewU8 frame, double altitude_m, MapperStep& out) noexcept;

  // The parts of step(), for a caller that times them separately (qnav map):
  // undistort(): the frame through the table into the mapper's buffer (the frame itself when the
  // mapper does not undistort); register_frame(): the chain; observe(): the map.
  Status undistort(ConstImageViewU8 frame, ConstImageViewU8& out) noexcept;
  Status register_frame(ConstImageViewU8 frame, double altitude_m, MapperStep& out) noexcept;
  void observe(MapperStep& out) noexcept;

  // A frame that could not be read at all: counted by the chain as bad input.
  Status unreadable_frame(MapperStep& out) noexcept;

  bool undistorts() const noexcept { return config_.undistort; }
  bool mapping() const noexcept { return config_.mapping; }
  bool metric() const noexcept { return config_.metric; }
  const TopoMapperConfig& config() const noexcept { return config_; }
  const topo::HomographyChain& chain() const noexcept { return chain_; }
  const topo::TopoMap& map() const noexcept { return map_; }
  topo::TopoMap& map() noexcept { return map_; }

 private:
  TopoMapperConfig config_{};
  bool ready_ = false;
  topo::HomographyChain chain_;
  vision::RemapTable remap_;
  ImageViewU8 rectified_{};
  topo::PlaceEncoder encoder_;
  topo::TopoMap map_;
};

}  // namespace qnav::pipeline
