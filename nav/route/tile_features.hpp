// TileFeatureExtractor: what a route node keeps of a tile. Finds Harris corners (nav/vision, with
// the Mars paper's neighbourhood-normalised scores) on a block-averaged (downsample x downsample;
// a coarse pixel is covered when at least half its pixels are) and box-blurred copy of a north-up
// tile in which pixels without coverage are replaced by the mean covered intensity (so the swath
// edge does not produce corners), keeps the max_keypoints strongest corners whose descriptor footprint lies
// fully inside covered pixels, and stores for each: its position in the tile frame (metres; x along
// the tile heading, y to starboard; origin at the tile pose) and an 8x8 int8 descriptor sampled on
// the north-up grid (descriptor_step_px apart), so descriptors of the same seabed spot compare
// directly whatever the vehicle heading (forward or reverse passes). Steps and radii below are in
// coarse pixels.
// Raster convention (same as nav/sonar's SonarTile): row 0 is the north edge, columns grow east;
// pixel (c, r) centre is north = origin_north_m - (r + 0.5) res, east = origin_east_m + (c + 0.5) res.
// Pose2 of a tile: x_m north, y_m east, heading_rad compass (clockwise from north).
// Memory: two float planes and a coverage plane of (max_width / downsample) x (max_height / downsample)
// (the downsampled tile the keypoints are found on) + the Harris buffers for that size, all from the
// Arena in init().
// Cost: O(W H) copy/blur + Harris (see nav/vision/harris.hpp) + O(K) descriptors. No heap.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/arena.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/image.hpp"
#include "nav/core/status.hpp"
#include "nav/route/route_types.hpp"
#include "nav/vision/harris.hpp"

namespace qnav::route {

struct TileFeatureConfig {
  int max_width = 1024;
  int max_height = 1024;
  std::size_t max_keypoints = 64;     // <= kMaxKeypointsPerNode
  int descriptor_step_px = 2;         // spacing of the 8x8 descriptor samples
  int downsample = 1;                 // block-average factor before detection (speckle, sand ripples)
  int blur_radius_px = 1;             // box blur (coarse pixels) before Harris; 0 = none
  int harris_block_radius = 2;
  int harris_nms_radius = 6;
  int harris_norm_cell_px = 32;
};

struct TileGeometry {
  double resolution_m = 0.1;
  double origin_north_m = 0.0;
  double origin_east_m = 0.0;
  Pose2 pose;  // tile frame in the route frame (north, east, compass heading)
};

enum class FeatureCounter : std::uint8_t { kBadTile, kEmptyTile, kFootprintUncovered, kCount };
inline constexpr const char* kFeatureCounterNames[] = {"bad_tile", "empty_tile", "footprint_uncovered"};

class TileFeatureExtractor {
 public:
  TileFeatureExtractor() noexcept : counters_(kFeatureCounterNames) {}
  static std::size_t arena_bytes(const TileFeatureConfig& c) noexcept;
  Status init(const TileFeatureConfig& config, Arena& arena) noexcept;
  // Fills out.keypoints (cleared first) and out.meta.pose. coverage may be empty (all covered);
  // otherwise same size as intensity, 0 = no data. A tile with no covered pixel is kEmpty.
  Status extract(ConstImageViewF32 intensity, ConstImageViewU8 coverage, const TileGeometry& geometry,
                 RouteNode& out) noexcept;
  const CounterSet<FeatureCounter>& counters() const noexcept { return counters_; }
  const vision::HarrisDetector& harris() const noexcept { return harris_; }
  // The plane the last extract found its corners on: the block-averaged tile, uncovered coarse pixels
  // set to the covered mean, box-blurred (width / downsample x height / downsample). Valid until the
  // next extract; empty before the first, or when that one failed before the blur.
  ConstImageViewF32 plane() const noexcept {
    return plane_w_ > 0 ? ConstImageViewF32::unchecked(work_.data(), plane_w_, plane_h_, plane_w_) : ConstImageViewF32{};
  }

 private:
  void block_average(ConstImageViewF32 in, ConstImageViewU8 cov, ImageViewF32 wk, ImageView<std::uint8_t> cv,
                     double& sum, std::size_t& n) const noexcept;
  void box_blur(ImageViewF32 wk, ImageViewF32 tp) const noexcept;  // blur_radius_px; none at 0

  TileFeatureConfig config_{};
  bool ready_ = false;
  vision::HarrisDetector harris_;
  Span<float> work_;
  Span<float> tmp_;
  Span<std::uint8_t> cov_;
  Span<vision::Corner> corners_;
  int plane_w_ = 0, plane_h_ = 0;  // plane(): set once the last extract has blurred its plane
  CounterSet<FeatureCounter> counters_;
};

}  // namespace qnav::route
