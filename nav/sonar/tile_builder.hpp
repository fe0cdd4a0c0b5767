// TileBuilder: corrected scanlines + dead-reckoned poses -> north-up metric side-scan tiles
// (the route-following paper's on-board tile: N scanlines, 500 in the paper, per tile).
// Raster: row 0 is the NORTH edge, columns grow EAST; pixel (c, r) covers north in
// (origin_north_m - (r+1)*res, origin_north_m - r*res], east in [origin_east_m + c*res, origin_east_m + (c+1)*res).
// The origin is snapped to a multiple of the resolution, so tiles from any pass share one world grid.
// Framing, two modes:
//  - by distance (tile_length_m > 0, what every route default uses): a tile holds the scanlines of the
//    last tile_length_m of along-track travel (the dead-reckoned distance between the scanlines'
//    poses), the first when tile_length_m has been travelled, then one every tile_stride_m (or the
//    distance set_next_stride_m() gives for the next one). scanlines_per_tile is then the ring's
//    capacity, the most pings a tile can hold (size it for the highest ping rate and lowest speed
//    allowed); when a faster ping rate or a slower vehicle would need more, the oldest pings of the
//    tile are dropped (the tile is shorter than tile_length_m) and counted once per tile as
//    tile_overflow. A nav pose that (all but) stops from one ping to the next, a step under 5 % of
//    the mean step (dead reckoning without odometry: a DVL loss freezes it; a vehicle that stops dead
//    looks the same) is framed at the mean step of the pings that moved (counted as frozen_pose), so
//    tiles keep coming at the last ping spacing, as they did by ping count; a vehicle that never
//    moved emits no tile.
//  - by ping count (tile_length_m = 0): when scanlines_per_tile scanlines are buffered, then every
//    scanline_stride.
// How a tile is made:
//  - the tile is centred on the bounding box of the buffered swath (valid bins only) and clipped to
//    the configured raster size (clipped splats are counted);
//  - between consecutive scanlines, poses and bin values are interpolated in sub-steps of at most
//    one pixel (max_substeps cap; no interpolation across a pose jump > max_gap_m), and each
//    (sub-)sample is splatted bilinearly: overlapping writes accumulate as a weighted average;
//  - an empty pixel with measured pixels within hole_fill_radius_px on both sides along its row or
//    its column (and in at least hole_fill_min_neighbours of the 4 directions) is filled by
//    inverse-distance interpolation of those nearest measured pixels (coverage 2). No cascading.
// Memory: every buffer is carved from the Arena in init() (see arena_bytes()); push() copies the
// scanline into a fixed ring (no allocation); building a tile touches the raster only. The float
// intensity raster lives in the first half of the accumulator (8 bytes per pixel): normalise()
// empties the accumulator row by row as it writes the intensity, so the raster costs 10 bytes per
// pixel (9 without the u8 raster) plus one row, not 14.
// Cost: push O(bins); tile build O(scanlines * bins * substeps + touched pixels * 4r): see
// BM_TileBuild500 in bench_sonar (docs/sonar.md). Only the box of pixels touched by this tile and
// the previous one is cleared and normalised. NaN/inf poses or wrong-size scanlines are rejected
// and counted.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/arena.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/image.hpp"
#include "nav/core/status.hpp"
#include "nav/sonar/hole_fill.hpp"
#include "nav/sonar/sonar_types.hpp"

namespace qnav::sonar {

struct TileBuilderConfig {
  double resolution_m = 0.1;        // pixel size
  int tile_width_px = 1024;         // raster size (east)
  int tile_height_px = 1024;        // raster size (north)
  int scanlines_per_tile = 500;     // N scanlines in a tile (by distance: the most a tile can hold)
  int scanline_stride = 500;        // by ping count: a tile every stride scanlines once N are buffered (<= N)
  double tile_length_m = 0.0;       // > 0: tiles by along-track distance, this long (0: by ping count)
  double tile_stride_m = 0.0;       // by distance: a tile every this much travel (> 0 when tile_length_m > 0)
  int max_bins_per_side = 512;      // largest CorrectedScanline accepted
  int max_substeps = 16;            // cap on interpolation sub-steps between two scanlines
  double max_gap_m = 5.0;           // no interpolation between poses farther apart (nav jump, gap)
  int hole_fill_radius_px = 2;      // 0 = no hole filling
  int hole_fill_min_neighbours = 2; // of the 4 axis directions, how many must reach measured data (2..4)
  float display_max = 2.5f;         // intensity mapped to 255 in the u8 raster
  bool u8_raster = true;            // false: no u8 raster (SonarTile::intensity_u8 empty; qnavd, which only
                                    // extracts features, saves its W x H bytes and the pass that fills it)
};

// One finished tile. Views point into the builder's buffers; valid until the next tile is built.
struct SonarTile {
  std::uint32_t index = 0;            // 0, 1, 2 ... in emission order
  ConstImageViewF32 intensity;        // normalised intensity (about 1 = mean seabed); 0 where no data
  ConstImageViewU8 intensity_u8;      // intensity * 255 / display_max, clamped (empty without u8_raster)
  ConstImageViewU8 coverage;          // 0 no data, 1 measured, 2 filled by hole interpolation
  double resolution_m = 0.0;
  double origin_north_m = 0.0;        // north of the top edge of row 0
  double origin_east_m = 0.0;         // east of the left edge of column 0
  Pose2 pose;                         // nav pose at the middle scanline (x_m north, y_m east, compass heading)
  Pose2 first_pose, last_pose;
  std::uint64_t first_stamp_ns = 0, last_stamp_ns = 0;
  std::uint32_t first_ping = 0, last_ping = 0;
  std::uint32_t scanlines = 0;
  Vec2d footprint_ne[4];              // swath corners (north, east): first-port, first-stbd, last-stbd, last-port
  float coverage_fraction = 0.0f;     // measured + filled pixels / all pixels
  std::uint32_t clipped_splats = 0;   // samples that fell outside the raster

  // Continuous pixel coordinates (col, row) of a north/east point (pixel centres at +0.5).
  Vec2d ne_to_pixel(double north_m, double east_m) const noexcept {
    return Vec2d((east_m - origin_east_m) / resolution_m, (origin_north_m - north_m) / resolution_m);
  }
  // North/east of continuous pixel coordinates.
  Vec2d pixel_to_ne(double col, double row) const noexcept {
    return Vec2d(origin_north_m - row * resolution_m, origin_east_m + col * resolution_m);
  }
};

enum class TileCounter : std::uint8_t {
  kBadPose,
  kBadScanline,
  kClippedSplat,
  kNavJump,
  kTileOverflow,  // by distance: a tile needed more pings than scanlines_per_tile (it was cut short)
  kFrozenPose,    // by distance: a ping whose nav pose had not moved, framed at the mean ping step
  kCount
};
inline constexpr const char* kTileCounterNames[] = {"bad_pose", "bad_scanline", "clipped_splat", "nav_jump", "tile_overflow", "frozen_pose"};

class TileBuilder {
 public:
  TileBuilder() noexcept = default;
  TileBuilder(const TileBuilder&) = delete;
  TileBuilder& operator=(const TileBuilder&) = delete;

  static std::size_t arena_bytes(const TileBuilderConfig& config) noexcept;
  Status init(const TileBuilderConfig& config, Arena& arena) noexcept;

  // Adds one scanline at its nav pose. Returns true in the Result when a new tile was built by this
  // call (then tile() holds it). Rejected inputs return an error and are counted.
  Result<bool> push(const CorrectedScanline& line, const Pose2& pose) noexcept;
  // Builds a tile from the scanlines buffered since the last tile (end of a line or file); returns
  // false when fewer than min_scanlines are pending.
  Result<bool> flush(int min_scanlines = 2) noexcept;
  // Drops buffered scanlines (new survey line); the tile index keeps counting.
  void reset() noexcept;
  // By distance: the next tile ends stride_m of travel after the last one ended (instead of
  // tile_stride_m), e.g. to put its centre on a taught node. Ignored before the first tile, by ping
  // count, and unless 0 < stride_m <= 4 x tile_stride_m. O(1).
  void set_next_stride_m(double stride_m) noexcept;
  // Along-track distance the framing counts since the pass began (sum of the pose steps; a frozen
  // pose adds the mean step), metres.
  double travelled_m() const noexcept { return dist_m_; }
  bool by_distance() const noexcept { return cfg_.tile_length_m > 0.0; }

  const SonarTile& tile() const noexcept { return tile_; }
  std::uint32_t tiles_built() const noexcept { return tiles_built_; }
  int buffered() const noexcept { return count_; }
  const CounterSet<TileCounter>& counters() const noexcept { return counters_; }
  const TileBuilderConfig& config() const noexcept { return cfg_; }

 private:
  struct Slot {
    Pose2 pose;
    std::uint64_t stamp_ns;
    std::uint32_t ping;
    double dist_m;  // along-track distance travelled at this scanline
    float bin_m;
    int bins;
    int run_lo[2], run_hi[2];  // per side: bins [run_lo, run_hi) are all valid (the first valid bin's run)
  };
  Status build(int first, int count) noexcept;
  // Logical index i: 0 = oldest buffered scanline.
  std::size_t ring(int i) const noexcept { return static_cast<std::size_t>((head_ + i) % cfg_.scanlines_per_tile); }
  float* values(int i, int side) noexcept {
    return values_.data() + (ring(i) * 2 + static_cast<std::size_t>(side)) * static_cast<std::size_t>(cfg_.max_bins_per_side);
  }
  std::uint8_t* valid(int i, int side) noexcept {
    return valid_.data() + (ring(i) * 2 + static_cast<std::size_t>(side)) * static_cast<std::size_t>(cfg_.max_bins_per_side);
  }
  // build() in steps, in this order:
  void place_tile(int first, int count) noexcept;       // tile_ origin from the swath's bounding box
  void clear_previous_box() noexcept;                   // zero what the previous tile touched
  void splat_scanline(int i, int end) noexcept;         // scanline i and its sub-steps toward i + 1 (< end)
  // One side of one sub-step: pixel coordinates (c0, r0) of the sub-step's pose, sb its starboard unit.
  void splat_side(int i, int side, const Slot* next, float t, double c0, double r0, const Vec2d& sb, int across) noexcept;
  inline void splat(float col, float row, float v) noexcept;
  // Intensity, coverage 1 and the u8 raster in the touched box; returns the pixels with coverage 1.
  std::size_t normalise() noexcept;
  void finish_tile(int first, int count, std::size_t covered) noexcept;

  TileBuilderConfig cfg_{};
  bool ready_ = false;
  Span<Slot> slots_;
  Span<float> values_;          // ring of N x 2 x max_bins
  Span<std::uint8_t> valid_;    // same layout
  struct alignas(8) Acc {  // 8-aligned: one doubleword (SPARC's ldd / std in the splat)
    float sum;
    float weight;
  };
  // One side's line of bins on splat_side()'s fast path: values and masks of this and the next
  // scanline, the interpolation t, the raster position of bin 0 and the step per bin, the bins valid on
  // both lines [lo, hi), the accumulator and its width.
  struct BinRun {
    const float* va;
    const float* vb;
    const std::uint8_t* ka;
    const std::uint8_t* kb;
    float t, cx, cy, dcb, drb;
    int lo, hi, bins;
    Acc* base;
    int W;
  };
  void splat_run_plain(const BinRun& r) const noexcept;
  void splat_run_carry(const BinRun& r) const noexcept;
  Span<Acc> acc_;               // weighted sum and weight, interleaved (one cache line per splat row)
  float* intensity_ = nullptr;  // W x H floats over the first half of acc_'s bytes (see normalise())
  Span<float> row_;             // one row of intensity, computed before its accumulator row is emptied
  Span<std::uint8_t> coverage_, u8_;
  int head_ = 0;                // ring index of the oldest buffered scanline
  int count_ = 0;               // buffered scanlines
  int since_tile_ = 0;          // scanlines pushed since the last tile
  std::uint32_t tiles_built_ = 0;
  std::uint32_t clipped_ = 0;
  // Framing by distance.
  bool have_prev_pose_ = false;
  Pose2 prev_pose_{};
  double dist_m_ = 0.0;        // travelled since the pass began (framing distance)
  double mean_step_m_ = 0.0;   // mean pose step of the pings that moved (0: none yet)
  bool framing_started_ = false;
  double next_end_m_ = 0.0;    // the next tile ends at the first scanline at or past this distance
  double last_end_m_ = 0.0;    // where the last tile ended
  bool overflow_ = false;      // a ping the next tile needed was dropped
  int first_in_tile(double start_m) const noexcept;
  double inv_res_ = 0.0;        // 1 / resolution_m, set by build()
  float one_ = 1.0f;            // 1, read once per line by splat_side()'s plain loop and normalise() (see there)
  int bb_x0_ = 0, bb_y0_ = 0, bb_x1_ = -1, bb_y1_ = -1;        // pixels touched by the tile being built
  int prev_x0_ = 0, prev_y0_ = 0, prev_x1_ = -1, prev_y1_ = -1;  // ... by the previous tile (to clear)
  SonarTile tile_{};
  CounterSet<TileCounter> counters_{kTileCounterNames};
};

}  // namespace qnav::sonar
