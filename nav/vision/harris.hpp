// HarrisDetector: Harris corners with the Mars paper's neighbourhood-normalised scores.
//
// Pipeline per frame: Sobel 3x3 gradients -> structure tensor summed over a (2*block_radius+1)^2 box
// -> response R = det(M) - k * trace(M)^2 -> threshold -> non-maximum suppression over a
// (2*nms_radius+1)^2 window -> optional neighbourhood normalisation of the score -> keep the best
// max_corners (min-heap) -> optional sub-pixel refinement (parabola through the 3x3 response) ->
// output sorted by decreasing score (ties: smaller y, then smaller x, so the order is deterministic).
//
// Neighbourhood normalisation (Mars paper, section 3: "Harris' scores are normalized in their close
// neighborhood"): score = R / (mean of max(R,0) over the (2*norm_cells+1)^2 cells of norm_cell_px
// pixels around the corner + norm_floor * mean of max(R,0) over the whole image). A corner in a
// low-contrast area then competes with corners in a high-contrast area, which spreads the kept corners
// over the image; the floor keeps flat, noisy areas from being boosted.
//
// Threshold: R > max(min_response, quality_level * max R in the ROI).
// Input: 8-bit grey or float images (float tiles from the sonar/route stages). Only pixels inside the
// region of interest (clipped to the image minus the border) are reported; the response is computed
// on the ROI grown by the filter support, so responses and NMS equal the full-image ones; the
// threshold's max R and the normalisation statistics are taken over the ROI (the prediction of the
// overlap is what the caller wants corners spread over).
//
// Memory (from the Arena in init(), see arena_bytes()): one float response plane
// max_width*max_height, a ring of 3*(2*block_radius+1) float rows plus 3 column-sum rows, the
// normalisation cell grid, max_corners Corner (top-K heap), 2*nms_radius+1 rows for the separable
// NMS max filter. No heap, no allocation in detect(). Worst case time: O(W*H*(block + nms)) for the
// ROI + O(K log K) for K kept corners; every loop is bounded by the configured image size and caps.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/arena.hpp"
#include "nav/core/fixed_vector.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/image.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/vision/corner.hpp"
#include "nav/vision/counters.hpp"

namespace qnav::vision {

struct HarrisConfig {
  int max_width = 1280;       // largest image detect() accepts (buffers are sized from this)
  int max_height = 1024;
  int max_corners = 500;      // cap on output corners (also bounded by out.capacity())
  int block_radius = 1;       // structure tensor window (2r+1)^2; 1 -> 3x3 (OpenCV blockSize 3)
  float k = 0.04f;            // Harris constant
  int nms_radius = 2;         // non-maximum suppression window (2r+1)^2
  int border_px = 4;          // no corner closer than this to the image edge (>= block_radius + 1)
  float min_response = 0.0f;  // absolute floor on R (units of the input intensity^4)
  float quality_level = 1e-5f;  // relative floor: R > quality_level * max R (low: normalisation spreads)
  bool normalise = true;      // Mars paper neighbourhood normalisation of the score
  int norm_cell_px = 16;      // normalisation cell side
  int norm_cells = 1;         // neighbourhood = (2*norm_cells+1)^2 cells around the corner's cell
  float norm_floor = 1e-3f;   // floor as a fraction of the global mean positive response
  bool subpixel = true;       // parabola refinement of x, y (|offset| <= 0.5 px)
};

// Whether detect() computes the structure tensor of 8-bit images with block_radius 1 from integer
// gradients (harris_response_u8_r1) instead of its float passes: on targets without SIMD (LEON3, armhf
// without NEON), where the float passes are not vectorised and each int -> float conversion counts;
// with SIMD the float passes are vectorised and cheaper. Both give the same response bit for bit
// (test HarrisIntegerTensor.*), so corners do not depend on the choice.
#if defined(__SSE2__) || defined(__ARM_NEON) || defined(__aarch64__)
inline constexpr bool kHarrisIntegerTensor = false;
#else
inline constexpr bool kHarrisIntegerTensor = true;
#endif

// The Harris response R = det(M) - k trace(M)^2, M the products of the Sobel gradients (scaled by 1/8)
// summed over 3 x 3 (block_radius 1), of an 8-bit image at the pixels of `area`, written to response
// at the same coordinates; ring is scratch of 9 rows of at least area.x + area.width floats. False (and
// nothing written) when area is not at least 2 px inside the image or ring or response is too small.
// What detect() runs when kHarrisIntegerTensor (public for the tests). Time O(area), no allocation.
bool harris_response_u8_r1(ConstImageViewU8 image, RectI area, float k, ImageViewF32 response, Span<float> ring) noexcept;

class HarrisDetector {
 public:
  HarrisDetector() noexcept : counters_(kVisionCounterNames) {}

  // Validates the configuration and carves every buffer from the arena (start-up only).
  // Errors: kInvalidArgument for an invalid configuration, kCapacityExceeded when the arena is short.
  Status init(const HarrisConfig& config, Arena& arena) noexcept;
  // Bytes init() takes from an arena for this configuration (for sizing the arena), alignment included.
  static std::size_t arena_bytes(const HarrisConfig& config) noexcept;

  // Detects corners in the whole image (minus the border). out is cleared first; at most
  // min(max_corners, out.capacity()) corners are written, best first.
  // Errors: kNotReady before init(), kInvalidArgument for an empty image or one larger than configured.
  Status detect(ConstImageViewU8 image, BoundedVector<Corner>& out) noexcept;
  Status detect(ConstImageViewF32 image, BoundedVector<Corner>& out) noexcept;
  // Same, only corners whose integer position is inside roi (e.g. the predicted overlap of two
  // frames). An empty roi is an error (kOutOfRange, counted as bad_roi): it is a prediction failure.
  Status detect(ConstImageViewU8 image, RectI roi, BoundedVector<Corner>& out) noexcept;
  Status detect(ConstImageViewF32 image, RectI roi, BoundedVector<Corner>& out) noexcept;
  // Mutable views (exact matches: ImageView<T>'s const conversion is a template, so without these a
  // mutable view would be ambiguous between the u8 and float overloads).
  Status detect(ImageViewU8 image, BoundedVector<Corner>& out) noexcept { return detect(ConstImageViewU8(image), out); }
  Status detect(ImageViewF32 image, BoundedVector<Corner>& out) noexcept { return detect(ConstImageViewF32(image), out); }
  Status detect(ImageViewU8 image, RectI roi, BoundedVector<Corner>& out) noexcept {
    return detect(ConstImageViewU8(image), roi, out);
  }
  Status detect(ImageViewF32 image, RectI roi, BoundedVector<Corner>& out) noexcept {
    return detect(ConstImageViewF32(image), roi, out);
  }

  // Response plane of the last detect() (valid inside the last ROI grown by nms_radius; 0 elsewhere
  // where not computed). For tests and debug images.
  ConstImageViewF32 response() const noexcept { return last_response_; }
  const HarrisConfig& config() const noexcept { return config_; }
  const VisionCounters& counters() const noexcept { return counters_; }
  // Which NMS detect() runs on 8-bit images: by blocks (suppress_blocks; the default without SIMD) or by
  // row maxima (with SIMD, and always on float images). The same corners either way (test
  // Harris.BlockNmsGivesTheSameCornersAsTheRowMaximumNms); a switch for that test.
  void use_block_nms(bool on) noexcept { block_nms_ = on; }
  // Whether the statistics and the row-maximum NMS use their 4-lane vector loops (the default where
  // kHarrisIntegerTensor is false, i.e. with SIMD) or the scalar loops (the default without SIMD). The
  // same floats and corners bit for bit either way (test Harris.VectorLoopsGiveTheSameCornersAsTheScalarLoops);
  // a switch for that test. Without SIMD the vector loops are compiled out and the switch does nothing.
  void use_vector_loops(bool on) noexcept { simd_ = on; }

 private:
  template <typename Pixel>
  Status detect_impl(ImageView<const Pixel> image, RectI roi, BoundedVector<Corner>& out) noexcept;
  // The steps of detect_impl, in order (harris.cpp says what each does).
  Status check_input(int width, int height, std::size_t out_capacity) noexcept;
  template <typename Pixel>
  void float_tensor_response(ImageView<const Pixel> image, RectI g, ImageViewF32 resp) noexcept;
  // Max response over det (returned) and the normalisation cell means (cells_).
  // finite: the response has no NaN (8-bit images): the scalar loops compare the bits as integers.
  float response_statistics(ConstImageViewF32 resp, RectI det, bool finite) noexcept;
  // NMS over det above thresh, the best cap kept in heap_ (returned: their count; dropped: some were not).
  // finite: the response has no NaN or inf (8-bit images), so a pixel equal to its window maximum needs
  // only the tie check (the vector loops use it).
  std::size_t suppress_and_keep(ConstImageViewF32 resp, RectI det, float thresh, std::size_t cap, bool finite,
                                bool& dropped) noexcept;
  // The same by blocks of (nms_radius + 1)^2 pixels (Neubeck and Van Gool's NMS): only each block's
  // maximum gets the window check, so each pixel is compared about once plus the checks of the block
  // maxima. The same corners as suppress_and_keep on a finite response (every pixel of a block is
  // within nms_radius of the block's maximum, earliest in raster order among equals, so only it can be
  // its window's maximum under the tie rule; the heap keeps the same best corners in any order). Used
  // without SIMD on 8-bit images, where the per-pixel row maxima cost most of the NMS.
  std::size_t suppress_blocks(ConstImageViewF32 resp, RectI det, float thresh, std::size_t cap, bool& dropped) noexcept;

  HarrisConfig config_{};
  bool ready_ = false;
  Span<float> response_;   // max_width * max_height
  Span<float> ring_;       // 3 * (2r+1) rows of max_width products (xx, yy, xy)
  Span<float> colsum_;     // 3 rows of max_width
  Span<float> grad_;       // 2 rows of max_width (gx, gy of one row)
  Span<float> cells_;      // normalisation cells: sums, pixel counts, neighbourhood means
  Span<Corner> heap_;      // max_corners: top-K heap
  Span<float> nms_ring_;   // (2 * nms_radius + 2) rows of max_width: row maxima ring + window max
  ConstImageViewF32 last_response_;
  bool block_nms_ = kHarrisIntegerTensor;
  bool simd_ = !kHarrisIntegerTensor;
  VisionCounters counters_;
};

}  // namespace qnav::vision
