// RouteTilePipeline: the per-ping wiring of route teach and repeat, shared by qnavd and the qnav tool:
// side-scan ping (at its causal nav pose) -> ScanlineCorrector -> TileBuilder (north-up tiles on the
// nav pose) -> TileFeatureExtractor -> a route node (keypoints in the tile frame, tile pose in the
// pass's dead-reckoned frame), plus the ground truth when the pass is simulated.
// Memory: one arena sized by init() from the config (corrector + builder + features) and a ring of
// per-ping records (2 x scanlines_per_tile, the most pings a tile holds, rounded up to a power of
// two); nothing grows with the
// length of a pass, and push_ping() allocates nothing (run_sim_pass() allocates its simulator).
// Time: one ping is O(samples); a finished tile adds one feature extraction (docs/budgets.md).
// Sinks are called synchronously; a sink that is a std::function built once allocates nothing.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "firmware/pipeline/route_defaults.hpp"

#include "drivers/sidescan/sim_seabed.hpp"
#include "drivers/sidescan/sim_sidescan.hpp"
#include "drivers/sidescan/sim_trajectory.hpp"
#include "nav/core/arena.hpp"
#include "nav/core/status.hpp"
#include "nav/route/route_localiser.hpp"
#include "nav/route/route_types.hpp"
#include "nav/route/tile_features.hpp"
#include "nav/sonar/scanline_corrector.hpp"
#include "nav/sonar/tile_builder.hpp"

namespace qnav::pipeline {

struct RouteTile {
  route::RouteNode node;           // keypoints + meta (pose = nav pose of the tile, along_m = nav distance)
  double nav_step_m = 0.0;         // nav distance travelled since the previous tile of the pass
  double truth_along_m = -1.0;     // simulated passes: along-route distance of the tile centre
  double truth_lateral_m = 0.0;    // simulated passes: offset right of the route's forward direction
  Pose2 truth_pose{};              // simulated passes: true pose at the tile's pose ping (keypoint
                                   // truth position ~ truth_pose.apply(keypoint), dead-reckoning drift aside)
  bool has_truth_pose = false;
  float coverage_fraction = 0.0f;
  std::uint32_t tile_index = 0;
  std::uint32_t ping_first = 0;    // the pings (SonarPing::ping_number) the tile was built from, first ...
  std::uint32_t ping_last = 0;     // ... and last
};

using RouteTileSink = std::function<bool(const RouteTile&)>;  // return false to stop the pass

// Simulator truth travelling with a ping (simulated passes only).
struct PingTruth {
  double along_m = -1.0;  // along-route distance of the ping from the route's first waypoint
  Pose2 pose{};
  double lateral_m = 0.0;
};

// Framing a repeat pass on the taught nodes: the distance to frame the next tile with
// (RouteTilePipeline::set_next_stride_m) so that its centre falls on the next node in the direction of
// travel, from the localiser's along-track offset to its estimated node (the tile centre is
// along_track_m past node n, node n+1 lies |along_m(n+1) - along_m(n)| further: the next tile ends
// that gap minus along_track_m later). A reverse pass started anywhere, which would otherwise be framed
// up to half a stride out of step with the taught tiles, is brought into step at its first registered
// tile. 0 (keep the configured stride) unless guidance took its offsets from a registration (tracking,
// or a strong one before the filter is confident); clamped to [0.75, 1.25] x stride_m (wider, one bad
// offset moves a tile too far: `qnav route eval`, docs/route.md). O(1).
double route_aligned_stride_m(const route::LocaliserStep& step, Span<const route::NodeMeta> meta, route::RouteDirection direction,
                              double stride_m) noexcept;

class RouteTilePipeline {
 public:
  // The arena the stages take from (corrector + tile builder + feature extractor, with alignment slack).
  static std::size_t arena_bytes(const RouteTileConfig& config) noexcept;
  // Allocates its own arena of arena_bytes(config).
  Status init(const RouteTileConfig& config);
  // Takes the stages' buffers from the caller's arena (qnavd: its static block); the arena outlives this.
  Status init(const RouteTileConfig& config, Arena& arena);
  // Flies a simulated pass over the seabed; calls sink for every tile.
  Status run_sim_pass(const sidescan::Seabed& seabed, const sidescan::SideScanSimConfig& sonar,
                      const sidescan::TrajectoryConfig& trajectory, const RouteTileSink& sink);
  // One simulated ping: rendered by sim from truth.pose (ping number `index`, at altitude_m) and pushed
  // at the nav pose. run_sim_pass (prescribed passes) and the closed-loop vehicle (closed_loop.hpp)
  // both feed the pipeline through this.
  Status push_sim_ping(sidescan::SideScanSimulator& sim, std::uint32_t index, std::uint64_t stamp_ns, float altitude_m, const Pose2& nav,
                       const PingTruth& truth, const RouteTileSink& sink, bool* stop);
  // Feeds one raw ping at its nav pose (XTF replay); emits finished tiles to sink.
  Status push_ping(const sonar::SonarPing& ping, const Pose2& nav_pose, const RouteTileSink& sink, bool* stop);
  // The same with the simulator's truth for this ping (ping.ping_number indexes the pass).
  Status push_ping(const sonar::SonarPing& ping, const Pose2& nav_pose, const PingTruth& truth, const RouteTileSink& sink, bool* stop);
  // Ends the pass: the tile in progress is emitted if it holds enough scanlines (by distance: 2; by
  // ping count: half a tile).
  Status flush(const RouteTileSink& sink);
  // The same with the least number of scanlines a last tile needs (`qnav sonar tiles`: 2).
  Status flush(const RouteTileSink& sink, int min_scanlines);
  void reset_pass();
  // Tiles by distance: the next tile ends stride_m of travel after the last one (see
  // TileBuilder::set_next_stride_m); call from the sink to frame the next tile on the route.
  void set_next_stride_m(double stride_m) noexcept { builder_->set_next_stride_m(stride_m); }
  const RouteTileConfig& config() const noexcept { return cfg_; }
  const sonar::TileBuilder& builder() const noexcept { return *builder_; }
  // Pings the corrector refused (its counters: damaged range, samples, altitude; no bottom found).
  const sonar::ScanlineCorrector& corrector() const noexcept { return *corrector_; }
  const route::TileFeatureExtractor& features() const noexcept { return *features_; }
  // Pings skipped since init: refused by the corrector or the tile builder (each also counts why).
  std::uint32_t rejected_pings() const noexcept { return rejected_pings_; }
  // The last tile's raster (for debug images).
  const sonar::SonarTile& last_tile() const noexcept { return builder_->tile(); }

 private:
  Status emit(const RouteTileSink& sink, bool* stop);
  RouteTileConfig cfg_{};
  std::unique_ptr<ArenaStorage> arena_;
  std::unique_ptr<sonar::ScanlineCorrector> corrector_;
  std::unique_ptr<sonar::TileBuilder> builder_;
  std::unique_ptr<route::TileFeatureExtractor> features_;
  std::unique_ptr<RouteTile> tile_;
  // Per-ping records of the pings a tile can still span: a ring of ring_mask_ + 1 >= 2 x
  // scanlines_per_tile slots keyed by ping_number (fixed at init; no growth with pass length).
  struct PingRecord {
    std::uint32_t ping_number = 0;
    bool used = false;
    bool has_truth = false;
    double nav_dist_m = 0.0;
    double truth_along_m = -1.0;
    Pose2 truth_pose{};
  };
  const PingRecord* record(std::uint32_t ping_number) const noexcept;
  Status push(const sonar::SonarPing& ping, const Pose2& nav, const PingTruth* truth, const RouteTileSink& sink, bool* stop);
  std::vector<PingRecord> ring_;
  std::size_t ring_mask_ = 0;
  double truth_lateral_m_ = 0.0;
  double last_tile_nav_m_ = 0.0;
  bool have_prev_nav_ = false;
  Pose2 prev_nav_{};
  double nav_dist_m_ = 0.0;
  std::uint32_t rejected_pings_ = 0;
};

}  // namespace qnav::pipeline
