// MapComponent: Mode = Map. Each downward frame through pipeline::TopoMapper (the `qnav map` wiring:
// homography chain, topological map); the map written durably to daemon.route_dir/map_<id>.qmap
// (drivers/map_store over the FileStore: temporary file + fsync + rename) after every new node and
// when the mode is left; a new map each time the mode is entered (re-initialised in its arena).
// Consumes: enter(map id) when Mode = Map is entered; on_frame(frame, image) per downward frame;
//   leave() when the mode is left.
// Produces: QNAV_MAP_POSE + QNAV_MAP_STATUS per frame on the publisher (pose, node, node count, the
//   frame's flags); the map file; a log line per frame; camera_lost() for FaultCameraLost.
// A refused frame (black, saturated, textureless, unregistered) is counted and logged, the pose and
// the map left as they were.
// Memory: the mapper's arena (the table's "map" buffer), reused by each new map; the PlaceEncoder's
// 32 KB inside the mapper. Time: one mapper step per frame (the map budget) plus a file rewrite on a
// new node.
#pragma once

#include <cstdint>

#include "drivers/qnavcan/publisher.hpp"
#include "firmware/pipeline/topo_mapper.hpp"
#include "firmware/qnavd/components/component.hpp"
#include "firmware/qnavd/messages.hpp"
#include "hal/core/file_store.hpp"

namespace qnav::daemon {

class MapComponent {
 public:
  MapComponent(const NavContext& ctx, hal::FileStore& store) noexcept : ctx_(ctx), store_(store) {}
  Status init(StaticMemory* mem, drivers::qnavcan::QnavCanPublisher& publisher);
  bool ready() const noexcept { return ready_; }
  ModeReject enter(std::uint16_t map_id) noexcept;
  // Saves the map as it ends (adapted since its last new node) and logs map_closed.
  void leave(std::uint16_t map_id) noexcept;
  // False when the frame is older than the previous downward frame (counted out of order by the worker).
  bool in_order(std::int64_t sample_ns) noexcept { return order_.advance(sample_ns); }
  // One downward frame (map.width x map.height); a step error is counted (step_errors).
  // False: a frame of another size than map.width x map.height (a software fault, counted).
  bool on_frame(const FrameMsg& f, const std::uint8_t* image) noexcept;
  void log_frame(const FrameMsg& f, double latency_ms) const noexcept;
  // Mode = Map: no downward frame for map.stale_s since the last one (or the mode's start).
  bool camera_lost(std::int64_t now_ns) const noexcept;

  const pipeline::TopoMapper& mapper() const noexcept { return mapper_; }
  const pipeline::MapperStep& step() const noexcept { return step_; }  // the last frame's
  std::uint32_t frames() const noexcept { return frames_; }
  std::uint32_t bad_frames() const noexcept { return bad_frames_; }
  std::uint32_t saves() const noexcept { return saves_; }
  std::uint32_t save_errors() const noexcept { return save_errors_; }
  std::uint32_t step_errors() const noexcept { return step_errors_; }

 private:
  void save() noexcept;
  void publish(const FrameMsg& f) noexcept;

  const NavContext& ctx_;  // the worker's: its log is set in NavWorker::init
  hal::FileStore& store_;
  pipeline::TopoMapper mapper_;
  StageArena arena_;
  Arena* map_arena_ = nullptr;
  drivers::qnavcan::QnavCanPublisher* publisher_ = nullptr;
  pipeline::MapperStep step_{};
  bool ready_ = false, open_ = false;
  char path_[1024] = {};
  SampleOrder order_;                // the last downward frame's sample time
  std::int64_t mode_start_ns_ = 0;    // when Mode = Map was entered (map.stale_s counts from it)
  std::uint16_t node_ = topo::kNoNode;  // the node the last observed frame was placed at
  std::uint32_t frames_ = 0, bad_frames_ = 0, saves_ = 0, save_errors_ = 0, step_errors_ = 0;
};

}  // namespace qnav::daemon
