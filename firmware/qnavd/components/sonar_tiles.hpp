// SonarTiles: the side-scan tile stage of Mode = Teach and Mode = Repeat. Each ping from the ping pool,
// with the dead-reckoned pose at its time, goes into the tile pipeline (pipeline::RouteTilePipeline:
// slant-range correction, the tile raster, keypoints); a finished tile goes to the worker's sink, which
// hands it to RouteTeach or RouteRepeat, and is reported (TileReport, the "tile" log line).
// Consumes: push(ping message, its pool slot, dead-reckoned pose) per ping while teaching or repeating;
//   flush() when a teach ends (the node in progress); reset_pass() when a mode is left;
//   set_next_stride_m() from the repeat (the next tile framed on the taught nodes).
// Produces: RouteTile to the sink; the tile pipeline's counters (NavHealth reads the corrector's).
// Pings are numbered from 0 in each pass (the repeat CSV's ping_first / ping_last).
// Memory: the tile pipeline's arena, the deployment table's "tile_pipeline" buffer. Time: a ping is
// the ping budget; the ping that completes a tile runs the whole tile stage (the tile budget).
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivers/qnavcan/messages.hpp"
#include "firmware/pipeline/route_tile_pipeline.hpp"
#include "firmware/qnavd/components/component.hpp"
#include "firmware/qnavd/messages.hpp"
#include "nav/core/geometry.hpp"
#include "nav/route/route_localiser.hpp"

namespace qnav::daemon {

// One sensed tile as the nav worker reported it (log line, tests).
struct TileReport {
  std::uint32_t seq = 0;
  drivers::qnavcan::Mode mode = drivers::qnavcan::Mode::kIdle;
  bool reverse = false;
  std::uint16_t route_id = 0;
  std::uint32_t node_written = 0;         // teach: index of the node appended
  route::LocaliserStep step;              // repeat
  double nav_step_m = 0.0;
  bool eq5_motion = false;                // DVL lost: the paper's motion model
  double truth_along_m = -1.0;            // sim backend only
  double truth_lateral_m = 0.0;
  std::int64_t stamp_ns = 0;
  double latency_ms = 0.0;                // last ping of the tile received -> outputs queued
};

class SonarTiles {
 public:
  explicit SonarTiles(const NavContext& ctx) noexcept : ctx_(ctx) {}
  Status init(StaticMemory* mem);
  // The ping in pool slot p.slot (port samples at its start, starboard at half its stride) at the
  // dead-reckoned pose nav. Returns the tile pipeline's status (its rejections are counted, not returned).
  Status push(const PingMsg& p, const float* pool, std::size_t pool_stride, const Pose2& nav, const pipeline::RouteTileSink& sink) noexcept;
  Status flush(const pipeline::RouteTileSink& sink) noexcept { return tiles_.flush(sink); }
  void reset_pass() noexcept {
    tiles_.reset_pass();
    pass_ping_ = 0;
  }
  void set_next_stride_m(double stride_m) noexcept { tiles_.set_next_stride_m(stride_m); }
  const pipeline::RouteTilePipeline& pipeline() const noexcept { return tiles_; }
  // The tile's log line (log.format json: every field; kv: the guidance; off: none).
  void log(const TileReport& r) const noexcept;

 private:
  const NavContext& ctx_;  // the worker's: its log is set in NavWorker::init
  pipeline::RouteTilePipeline tiles_;
  StageArena arena_;
  std::uint32_t pass_ping_ = 0;
};

}  // namespace qnav::daemon
