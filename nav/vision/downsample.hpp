// Downsampling by an integer factor (the Mars paper works at 1/4: 1280x1024 -> 320x256) and an image
// pyramid of factor-2 levels (for multi-scale detection and the gradient-histogram descriptor).
//
// downsample(): each output pixel is the rounded mean of a factor x factor block of the input
// (box filter = area averaging, what a sensor binning mode does). Output size = floor(input / factor);
// the last columns/rows that do not fill a block are dropped. O(W*H), no allocation.
#pragma once

#include <cstddef>

#include "nav/core/arena.hpp"
#include "nav/core/image.hpp"
#include "nav/core/status.hpp"

namespace qnav::vision {

// dst must be exactly (src.width/factor) x (src.height/factor); factor in 1..16.
// Errors: kInvalidArgument (empty view, factor out of range, wrong dst size, src smaller than factor).
Status downsample(ConstImageViewU8 src, int factor, ImageViewU8 dst) noexcept;
Status downsample(ConstImageViewF32 src, int factor, ImageViewF32 dst) noexcept;

struct PyramidConfig {
  int max_width = 1280;   // largest level-0 image build() accepts
  int max_height = 1024;
  int levels = 4;         // level 0 = the input itself (copied), level i = 2x2 box of level i-1; 1..8
};

// ImagePyramid: owns levels 0..levels-1 (from an Arena in init()); build() fills them from a frame.
// Level i has size floor(W / 2^i) x floor(H / 2^i); levels that would be smaller than 8x8 are not
// built (levels_built() tells how many were). Memory ~ 4/3 * max_width * max_height bytes.
class ImagePyramid {
 public:
  static constexpr int kMaxLevels = 8;
  Status init(const PyramidConfig& config, Arena& arena) noexcept;
  // Errors: kNotReady before init(), kInvalidArgument for an empty or too large image.
  Status build(ConstImageViewU8 image) noexcept;
  int levels_built() const noexcept { return built_; }
  // Level i of the last build(); an empty view for i outside [0, levels_built()).
  ConstImageViewU8 level(int i) const noexcept;
  // Scale of level i relative to level 0 (2^i): x0 = (xi + 0.5) * scale - 0.5.
  static float scale(int i) noexcept { return static_cast<float>(1 << i); }

 private:
  PyramidConfig config_{};
  bool ready_ = false;
  int built_ = 0;
  Span<std::uint8_t> storage_[kMaxLevels];
  ImageViewU8 views_[kMaxLevels];
};

}  // namespace qnav::vision
