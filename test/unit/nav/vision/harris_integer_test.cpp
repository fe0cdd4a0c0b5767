// harris_response_u8_r1 (the structure tensor from integer gradients that detect() runs for 8-bit
// images with block_radius 1 on targets without SIMD, kHarrisIntegerTensor) against the float passes
// (detect() on the same image as floats: the float path on every target): the same response bit for
// bit, on images with the largest gradients an 8-bit image has, and the same corners.
#include <gtest/gtest.h>

#include <cmath>

#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "nav/vision/harris.hpp"
#include "test_images.hpp"

namespace qnav::vision {
namespace {

std::uint32_t bits(float v) {
  std::uint32_t u = 0;
  std::memcpy(&u, &v, sizeof u);
  return u;
}

struct Images {
  static constexpr int kW = 96, kH = 80;
  std::vector<std::uint8_t> u8 = std::vector<std::uint8_t>(kW * kH);
  std::vector<float> f32 = std::vector<float>(kW * kH);
  void sync() {
    for (std::size_t i = 0; i < u8.size(); ++i) f32[i] = static_cast<float>(u8[i]);
  }
};

// 0: uniform noise; 1: binary 0/255 noise (Sobel sums up to +-1020 with both signs of the product);
// 2: a 255 square on 0 (step corners) plus a 0/255 checkerboard patch; 3: 2 x 2 tiles of 4 random levels
// (plateaus: many equal responses next to each other, the tie rule decides).
void make(Images& im, int kind) {
  std::uint32_t s = 12345u + static_cast<std::uint32_t>(kind);
  for (int y = 0; y < Images::kH; ++y)
    for (int x = 0; x < Images::kW; ++x) {
      s = s * 1664525u + 1013904223u;
      std::uint8_t v = 0;
      if (kind == 0) v = static_cast<std::uint8_t>(s >> 24);
      if (kind == 1) v = (s >> 31) != 0 ? 255 : 0;
      if (kind == 2) v = (x >= 20 && x < 60 && y >= 15 && y < 50) || (x >= 70 && y >= 55 && ((x + y) & 1)) ? 255 : 0;
      if (kind == 3) {
        std::uint32_t t = static_cast<std::uint32_t>((y / 2) * 977 + (x / 2)) * 2654435761u;
        t ^= t >> 13;
        v = static_cast<std::uint8_t>(85u * ((t * 2246822519u) >> 30));
      }
      im.u8[static_cast<std::size_t>(y * Images::kW + x)] = v;
    }
  im.sync();
}

TEST(HarrisIntegerTensor, SameResponseBitForBitAsTheFloatPasses) {
  HarrisConfig c;
  c.max_width = Images::kW;
  c.max_height = Images::kH;
  c.block_radius = 1;
  ArenaStorage arena(HarrisDetector::arena_bytes(c));
  HarrisDetector det;
  ASSERT_TRUE(det.init(c, arena).is_ok());
  std::vector<Corner> storage(500);
  BoundedVector<Corner> out(Span<Corner>(storage.data(), storage.size()));
  // Every pixel where the response is defined (an even number of rows), and an area with an odd number
  // of rows and columns (harris_response_u8_r1 takes two rows per pass, an odd last row alone).
  for (const RectI area : {RectI{2, 2, Images::kW - 4, Images::kH - 4}, RectI{3, 2, Images::kW - 6, Images::kH - 5}})
  for (int kind = 0; kind < 4; ++kind) {
    std::vector<float> resp(Images::kW * Images::kH, -1.0f), ring(9 * Images::kW);
    Images im;
    make(im, kind);
    ASSERT_TRUE(det.detect(ConstImageViewF32(ImageViewF32::make(im.f32.data(), Images::kW, Images::kH).value()), out).is_ok());
    const ConstImageViewF32 ref = det.response();
    ImageViewF32 got = ImageViewF32::make(resp.data(), Images::kW, Images::kH).value();
    ASSERT_TRUE(harris_response_u8_r1(ConstImageViewU8(ImageViewU8::make(im.u8.data(), Images::kW, Images::kH).value()), area, c.k, got,
                                      Span<float>(ring.data(), ring.size())));
    float rmax = 0.0f;
    for (int y = area.y; y < area.y + area.height; ++y)
      for (int x = area.x; x < area.x + area.width; ++x) rmax = std::max(rmax, std::abs(ref.row(y)[x]));
    // Where the detector runs the integer tensor (targets without SIMD: LEON3, armhf) it must give the
    // float path's response bit for bit. Elsewhere the float path is what runs, and the compiler may
    // contract its response into fused multiply-adds (aarch64), so the two agree to rounding only.
    // x86-64 without FMA has no contraction: bit for bit there too.
#if defined(__x86_64__) && !defined(__FMA__)
    const bool exact = true;
#else
    const bool exact = kHarrisIntegerTensor;
#endif
    const float tol = exact ? 0.0f : 1e-6f * rmax;
    int differ = 0;
    for (int y = area.y; y < area.y + area.height; ++y)
      for (int x = area.x; x < area.x + area.width; ++x)
        differ += (tol == 0.0f ? bits(got.row(y)[x]) != bits(ref.row(y)[x]) : std::abs(got.row(y)[x] - ref.row(y)[x]) > tol) ? 1 : 0;
    EXPECT_EQ(differ, 0) << "image " << kind << " area height " << area.height << (exact ? " (bit for bit)" : " (to 1e-6 of the largest response)");
    EXPECT_GT(rmax, 0.0f) << "image " << kind;  // the images do have corners
    // Outside the area nothing is written.
    EXPECT_EQ(got.row(0)[0], -1.0f);
    EXPECT_EQ(got.row(Images::kH - 1)[Images::kW - 1], -1.0f);
    EXPECT_EQ(got.row(area.y + area.height)[area.x], -1.0f);
    EXPECT_EQ(got.row(area.y)[area.x + area.width], -1.0f);
  }
}

TEST(HarrisIntegerTensor, SameCornersFromTheByteAndTheFloatImage) {
  HarrisConfig c;
  c.max_width = Images::kW;
  c.max_height = Images::kH;
  ArenaStorage arena(HarrisDetector::arena_bytes(c));
  HarrisDetector det;
  ASSERT_TRUE(det.init(c, arena).is_ok());
  std::vector<Corner> s1(500), s2(500);
  BoundedVector<Corner> o1(Span<Corner>(s1.data(), s1.size())), o2(Span<Corner>(s2.data(), s2.size()));
  for (int kind = 0; kind < 3; ++kind) {
    Images im;
    make(im, kind);
    ASSERT_TRUE(det.detect(ConstImageViewU8(ImageViewU8::make(im.u8.data(), Images::kW, Images::kH).value()), o1).is_ok());
    ASSERT_TRUE(det.detect(ConstImageViewF32(ImageViewF32::make(im.f32.data(), Images::kW, Images::kH).value()), o2).is_ok());
    ASSERT_EQ(o1.size(), o2.size()) << "image " << kind;
    ASSERT_GT(o1.size(), 0u);
    for (std::size_t i = 0; i < o1.size(); ++i) {
      EXPECT_EQ(bits(o1[i].x), bits(o2[i].x));
      EXPECT_EQ(bits(o1[i].y), bits(o2[i].y));
      EXPECT_EQ(bits(o1[i].score), bits(o2[i].score));
    }
  }
}

// The block NMS (suppress_blocks: only each (nms+1)^2 block's maximum gets the window check; what
// detect() runs on 8-bit images without SIMD) and the row-maximum NMS with its vector loops (with SIMD:
// a pixel equal to its window maximum gets only the tie check) against the row-maximum NMS's scalar
// loops (the full window check of every candidate): the same corners, bit for bit, in the same order,
// with ties (the checkerboard's and the plateaus' equal responses), a ROI, other radii and a cap.
TEST(Harris, BlockNmsGivesTheSameCornersAsTheRowMaximumNms) {
  struct Case {
    int nms, cap;
    RectI roi;
    bool normalise;
  };
  const Case cases[] = {{2, 500, RectI{0, 0, Images::kW, Images::kH}, true},
                        {2, 12, RectI{0, 0, Images::kW, Images::kH}, true},  // the cap is reached
                        {1, 500, RectI{0, 0, Images::kW, Images::kH}, false},
                        {3, 500, RectI{13, 9, 61, 47}, true},
                        {4, 40, RectI{30, 20, 66, 60}, false}};
  std::vector<Corner> s1(500), s2(500);
  BoundedVector<Corner> o1(Span<Corner>(s1.data(), s1.size())), o2(Span<Corner>(s2.data(), s2.size()));
  std::size_t compared = 0;
  for (const Case& k : cases) {
    HarrisConfig c;
    c.max_width = Images::kW;
    c.max_height = Images::kH;
    c.nms_radius = k.nms;
    c.max_corners = k.cap;
    c.normalise = k.normalise;
    ArenaStorage arena(3 * HarrisDetector::arena_bytes(c));
    HarrisDetector rows, vector_rows, blocks;
    ASSERT_TRUE(rows.init(c, arena).is_ok());
    ASSERT_TRUE(vector_rows.init(c, arena).is_ok());
    ASSERT_TRUE(blocks.init(c, arena).is_ok());
    rows.use_block_nms(false);
    rows.use_vector_loops(false);
    vector_rows.use_block_nms(false);
    vector_rows.use_vector_loops(true);  // compiled out without SIMD: the scalar loops again
    blocks.use_block_nms(true);
    for (int kind = 0; kind < 4; ++kind) {
      Images im;
      make(im, kind);
      const ConstImageViewU8 img(ImageViewU8::make(im.u8.data(), Images::kW, Images::kH).value());
      ASSERT_TRUE(rows.detect(img, k.roi, o1).is_ok());
      ASSERT_GT(o1.size(), 0u);
      for (HarrisDetector* other : {&vector_rows, &blocks}) {
        ASSERT_TRUE(other->detect(img, k.roi, o2).is_ok());
        ASSERT_EQ(o1.size(), o2.size()) << "image " << kind << " nms " << k.nms << " blocks " << (other == &blocks);
        for (std::size_t i = 0; i < o1.size(); ++i) {
          EXPECT_EQ(bits(o1[i].x), bits(o2[i].x)) << i;
          EXPECT_EQ(bits(o1[i].y), bits(o2[i].y)) << i;
          EXPECT_EQ(bits(o1[i].score), bits(o2[i].score)) << i;
          EXPECT_EQ(bits(o1[i].response), bits(o2[i].response)) << i;
        }
      }
      compared += o1.size();
    }
    for (HarrisDetector* other : {&vector_rows, &blocks})
      EXPECT_EQ(rows.counters().get(VisionCounter::kCornerCapReached), other->counters().get(VisionCounter::kCornerCapReached));
  }
  EXPECT_GT(compared, 100u);
}

// The top-K selection (the heap that keeps the best max_corners while the NMS offers corners in raster
// order): with a cap, the corners are exactly the first ones of the run without one (the order of the
// output is a total order, so the best K are one set), for both NMS and several caps, on an image with
// ties.
TEST(Harris, TheCapKeepsThePrefixOfTheUncappedCorners) {
  std::vector<Corner> s1(2000), s2(2000);
  BoundedVector<Corner> all(Span<Corner>(s1.data(), s1.size())), capped(Span<Corner>(s2.data(), s2.size()));
  std::size_t checked = 0;
  for (const bool block_nms : {false, true}) {
    for (int kind = 0; kind < 4; ++kind) {
      Images im;
      make(im, kind);
      const ConstImageViewU8 img(ImageViewU8::make(im.u8.data(), Images::kW, Images::kH).value());
      HarrisConfig c;
      c.max_width = Images::kW;
      c.max_height = Images::kH;
      c.max_corners = 2000;
      ArenaStorage big_arena(HarrisDetector::arena_bytes(c));
      HarrisDetector big;
      ASSERT_TRUE(big.init(c, big_arena).is_ok());
      big.use_block_nms(block_nms);
      ASSERT_TRUE(big.detect(img, all).is_ok());
      ASSERT_LT(all.size(), 2000u);  // no cap reached: every corner
      EXPECT_EQ(big.counters().get(VisionCounter::kCornerCapReached), 0u);
      for (const int cap : {1, 2, 7, 64, 200}) {
        if (static_cast<std::size_t>(cap) >= all.size()) continue;
        c.max_corners = cap;
        ArenaStorage arena(HarrisDetector::arena_bytes(c));
        HarrisDetector d;
        ASSERT_TRUE(d.init(c, arena).is_ok());
        d.use_block_nms(block_nms);
        ASSERT_TRUE(d.detect(img, capped).is_ok());
        ASSERT_EQ(capped.size(), static_cast<std::size_t>(cap));
        EXPECT_EQ(d.counters().get(VisionCounter::kCornerCapReached), 1u);
        for (std::size_t i = 0; i < capped.size(); ++i) {
          EXPECT_EQ(bits(capped[i].x), bits(all[i].x)) << "cap " << cap << " kind " << kind << " i " << i;
          EXPECT_EQ(bits(capped[i].y), bits(all[i].y)) << i;
          EXPECT_EQ(bits(capped[i].score), bits(all[i].score)) << i;
        }
        checked += capped.size();
      }
    }
  }
  EXPECT_GT(checked, 300u);
}

TEST(HarrisIntegerTensor, RefusesAnAreaTooCloseToTheEdgeOrTooLittleScratch) {
  std::vector<std::uint8_t> px(40 * 30, 7);
  std::vector<float> resp(40 * 30), ring(9 * 40);
  const ConstImageViewU8 img(ImageViewU8::make(px.data(), 40, 30).value());
  ImageViewF32 r = ImageViewF32::make(resp.data(), 40, 30).value();
  const Span<float> scratch(ring.data(), ring.size());
  EXPECT_TRUE(harris_response_u8_r1(img, RectI{2, 2, 36, 26}, 0.04f, r, scratch));
  EXPECT_FALSE(harris_response_u8_r1(img, RectI{1, 2, 36, 26}, 0.04f, r, scratch));
  EXPECT_FALSE(harris_response_u8_r1(img, RectI{2, 2, 37, 26}, 0.04f, r, scratch));
  EXPECT_FALSE(harris_response_u8_r1(img, RectI{2, 2, 36, 27}, 0.04f, r, scratch));
  EXPECT_FALSE(harris_response_u8_r1(img, RectI{2, 2, 36, 26}, 0.04f, r, Span<float>(ring.data(), 9 * 30)));
  EXPECT_FALSE(harris_response_u8_r1(img, RectI{2, 2, 0, 26}, 0.04f, r, scratch));
}


// The 4-lane vector loops of the statistics and the row-maximum NMS (what detect() runs with SIMD)
// against the scalar loops (what it runs without): the same corners bit for bit, on 8-bit noise, on
// float images with special values (NaN, +-inf, -0, huge), with ROIs that start inside a normalisation
// cell, other cell sizes and radii, and a reached cap.
TEST(Harris, VectorLoopsGiveTheSameCornersAsTheScalarLoops) {
  constexpr int kW = 301, kH = 97;
  struct Case {
    int nms, cap, cell;
    RectI roi;
    bool normalise;
  };
  const Case cases[] = {{2, 500, 16, RectI{0, 0, kW, kH}, true},   {2, 25, 16, RectI{0, 0, kW, kH}, true},
                        {1, 500, 16, RectI{7, 3, 250, 80}, true},  {3, 300, 12, RectI{0, 0, kW, kH}, true},
                        {2, 500, 16, RectI{21, 5, 270, 70}, false}};
  std::vector<std::uint8_t> u8(static_cast<std::size_t>(kW * kH));
  std::vector<float> f32(u8.size());
  std::uint32_t s = 777u;
  for (std::size_t i = 0; i < u8.size(); ++i) {
    s = s * 1664525u + 1013904223u;
    u8[i] = i < u8.size() / 2 ? static_cast<std::uint8_t>(s >> 24) : ((s >> 31) != 0 ? 255 : 0);  // binary: |Sobel| up to 1020
    f32[i] = static_cast<float>(u8[i]) * 0.37f - 20.0f;
  }
  // Special values in the float image (their neighbourhoods' responses are NaN or inf).
  const float special[] = {std::nanf(""), std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                           -0.0f, 3e18f};
  for (int j = 0; j < 5; ++j) f32[static_cast<std::size_t>((20 + 15 * j) * kW + 40 + 50 * j)] = special[j];
  std::vector<Corner> s1(500), s2(500);
  BoundedVector<Corner> o1(Span<Corner>(s1.data(), s1.size())), o2(Span<Corner>(s2.data(), s2.size()));
  std::size_t compared = 0;
  for (const Case& k : cases) {
    HarrisConfig c;
    c.max_width = kW;
    c.max_height = kH;
    c.nms_radius = k.nms;
    c.max_corners = k.cap;
    c.norm_cell_px = k.cell;
    c.normalise = k.normalise;
    ArenaStorage arena(2 * HarrisDetector::arena_bytes(c));
    HarrisDetector scalar, vector;
    ASSERT_TRUE(scalar.init(c, arena).is_ok());
    ASSERT_TRUE(vector.init(c, arena).is_ok());
    for (HarrisDetector* d : {&scalar, &vector}) d->use_block_nms(false);
    scalar.use_vector_loops(false);
    vector.use_vector_loops(true);
    for (int kind = 0; kind < 2; ++kind) {
      if (kind == 0) {
        const ConstImageViewU8 img(ImageViewU8::make(u8.data(), kW, kH).value());
        ASSERT_TRUE(scalar.detect(img, k.roi, o1).is_ok());
        ASSERT_TRUE(vector.detect(img, k.roi, o2).is_ok());
      } else {
        const ConstImageViewF32 img(ImageViewF32::make(f32.data(), kW, kH).value());
        ASSERT_TRUE(scalar.detect(img, k.roi, o1).is_ok());
        ASSERT_TRUE(vector.detect(img, k.roi, o2).is_ok());
      }
      ASSERT_EQ(o1.size(), o2.size()) << "image " << kind << " nms " << k.nms;
      // The 8-bit image always has corners. The float image with inf / 3e18 pixels has some on x86 but none in
      // either loop on aarch64 (the same on both loops is what is tested here; why aarch64 differs, likely
      // the fused multiply-adds gcc contracts there turning an inf response into the maximum that sets the
      // quality threshold, is not diagnosed).
      if (kind == 0) {
        ASSERT_GT(o1.size(), 0u) << "nms " << k.nms << " cap " << k.cap << " cell " << k.cell << " roi x " << k.roi.x;
      }
      for (std::size_t i = 0; i < o1.size(); ++i) {
        EXPECT_EQ(bits(o1[i].x), bits(o2[i].x)) << i;
        EXPECT_EQ(bits(o1[i].y), bits(o2[i].y)) << i;
        EXPECT_EQ(bits(o1[i].score), bits(o2[i].score)) << i;
        EXPECT_EQ(bits(o1[i].response), bits(o2[i].response)) << i;
      }
      compared += o1.size();
      // The response planes (the 8-bit image's tensor passes differ with the switch), where defined.
      std::size_t differ = 0;
      for (int y = 2; y < kH - 2; ++y)
        for (int x = 2; x < kW - 2; ++x)
          differ += bits(scalar.response()(x, y)) != bits(vector.response()(x, y)) ? 1u : 0u;
      EXPECT_EQ(differ, 0u) << "image " << kind;
    }
    EXPECT_EQ(scalar.counters().get(VisionCounter::kCornerCapReached), vector.counters().get(VisionCounter::kCornerCapReached));
  }
  EXPECT_GT(compared, 1000u);
}

}  // namespace
}  // namespace qnav::vision
