#include "nav/vision/harris.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "test/support/alloc_guard.hpp"
#include "test_images.hpp"

namespace qnav::vision {
namespace {

using testing::draw_rect;
using testing::fill;

struct Fixture {
  explicit Fixture(const HarrisConfig& c, std::size_t cap = 2000) : arena(HarrisDetector::arena_bytes(c)), storage(cap) {
    out = BoundedVector<Corner>(Span<Corner>(storage.data(), storage.size()));
    init_status = det.init(c, arena);
  }
  ArenaStorage arena;
  std::vector<Corner> storage;
  BoundedVector<Corner> out;
  HarrisDetector det;
  Status init_status;
};

HarrisConfig small_config(int w, int h) {
  HarrisConfig c;
  c.max_width = w;
  c.max_height = h;
  return c;
}

bool has_corner_near(const BoundedVector<Corner>& cs, float x, float y, float tol) {
  for (const Corner& c : cs)
    if (std::hypot(c.x - x, c.y - y) <= tol) return true;
  return false;
}

TEST(Harris, FindsTheFourCornersOfARectangleFirst) {
  std::vector<std::uint8_t> px(120 * 100);
  ImageViewU8 img = ImageViewU8::make(px.data(), 120, 100).value();
  fill(img, 30);
  draw_rect(img, 30, 25, 90, 75, 220);  // corners at pixel boundaries 29.5/89.5 x 24.5/74.5
  Fixture f(small_config(120, 100));
  ASSERT_TRUE(f.init_status.is_ok());
  ASSERT_TRUE(f.det.detect(ConstImageViewU8(img), f.out).is_ok());
  ASSERT_GE(f.out.size(), 4u);
  // The four strongest corners are the rectangle's, each within 1.5 px of the true corner (the Harris
  // peak of an ideal step corner sits ~0.7 px inside the corner along both axes: a known bias).
  const float tx[4] = {29.5f, 89.5f, 29.5f, 89.5f}, ty[4] = {24.5f, 24.5f, 74.5f, 74.5f};
  for (int i = 0; i < 4; ++i) {
    bool found = false;
    for (int j = 0; j < 4; ++j) found = found || std::hypot(f.out[j].x - tx[i], f.out[j].y - ty[i]) <= 1.5f;
    EXPECT_TRUE(found) << "corner " << i;
  }
  // Nothing along the straight edges scores like a corner.
  for (std::size_t j = 4; j < f.out.size(); ++j) EXPECT_LT(f.out[j].response, 0.05f * f.out[3].response);
}

TEST(Harris, OutputIsSortedByScoreAndRespectsTheCap) {
  std::vector<std::uint8_t> px(200 * 160);
  ImageViewU8 img = ImageViewU8::make(px.data(), 200, 160).value();
  testing::texture(img, 7);
  HarrisConfig c = small_config(200, 160);
  c.max_corners = 1000;
  Fixture all(c);
  ASSERT_TRUE(all.det.detect(ConstImageViewU8(img), all.out).is_ok());
  ASSERT_GT(all.out.size(), 60u);
  for (std::size_t i = 1; i < all.out.size(); ++i) EXPECT_GE(all.out[i - 1].score, all.out[i].score);

  c.max_corners = 40;
  Fixture capped(c);
  ASSERT_TRUE(capped.det.detect(ConstImageViewU8(img), capped.out).is_ok());
  ASSERT_EQ(capped.out.size(), 40u);
  for (std::size_t i = 0; i < 40; ++i) {
    EXPECT_EQ(capped.out[i].x, all.out[i].x);
    EXPECT_EQ(capped.out[i].y, all.out[i].y);
  }
  EXPECT_EQ(capped.det.counters().get(VisionCounter::kCornerCapReached), 1u);

  // The output container's own capacity caps too.
  std::vector<Corner> small(10);
  BoundedVector<Corner> out10(Span<Corner>(small.data(), small.size()));
  ASSERT_TRUE(all.det.detect(ConstImageViewU8(img), out10).is_ok());
  ASSERT_EQ(out10.size(), 10u);
  EXPECT_EQ(out10[9].x, all.out[9].x);
}

TEST(Harris, RoiGivesTheFullImageResultRestrictedToTheRoi) {
  std::vector<std::uint8_t> px(200 * 160);
  ImageViewU8 img = ImageViewU8::make(px.data(), 200, 160).value();
  testing::texture(img, 11);
  HarrisConfig c = small_config(200, 160);
  c.normalise = false;  // normalisation cells see only the ROI, so compare raw scores
  c.max_corners = 2000;  // no cap
  c.quality_level = 0.0f;
  c.min_response = 1.0f;
  c.subpixel = false;
  Fixture full(c), part(c);
  ASSERT_TRUE(full.det.detect(ConstImageViewU8(img), full.out).is_ok());
  const RectI roi{50, 40, 90, 70};
  ASSERT_TRUE(part.det.detect(ConstImageViewU8(img), roi, part.out).is_ok());
  std::size_t inside = 0;
  for (const Corner& k : full.out)
    if (roi.contains(static_cast<int>(k.x), static_cast<int>(k.y))) {
      ++inside;
      EXPECT_TRUE(has_corner_near(part.out, k.x, k.y, 0.0f)) << k.x << "," << k.y;
    }
  EXPECT_GT(inside, 5u);
  EXPECT_EQ(part.out.size(), inside);
}

TEST(Harris, NormalisedScoresSpreadCornersOverLowContrastAreas) {
  // Left: strong squares (0 / 255); right: faint squares (100 / 160); same geometry, 48 corners
  // each side, the halves > 48 px apart (the normalisation neighbourhood: 3 x 3 cells of 16 px).
  const int W = 256, H = 128;
  std::vector<std::uint8_t> px(W * H);
  ImageViewU8 img = ImageViewU8::make(px.data(), W, H).value();
  fill(img, 0);
  draw_rect(img, W / 2, 0, W, H, 100);
  for (int gy = 0; gy < 4; ++gy)
    for (int gx : {0, 1, 2, 5, 6, 7}) {
      const int x = 8 + gx * 30, y = 10 + gy * 30;
      draw_rect(img, x, y, x + 14, y + 14, gx < 4 ? 255 : 160);
    }
  HarrisConfig c = small_config(W, H);
  c.max_corners = 48;  // half of the 96 square corners
  c.normalise = false;
  Fixture raw(c);
  c.normalise = true;
  Fixture norm(c);
  ASSERT_TRUE(raw.det.detect(ConstImageViewU8(img), raw.out).is_ok());
  ASSERT_TRUE(norm.det.detect(ConstImageViewU8(img), norm.out).is_ok());
  auto right_share = [&](const BoundedVector<Corner>& cs) {
    std::size_t n = 0;
    for (const Corner& k : cs) n += k.x > W / 2 + 4 ? 1 : 0;
    return static_cast<double>(n) / static_cast<double>(cs.size());
  };
  ASSERT_EQ(raw.out.size(), 48u);
  ASSERT_EQ(norm.out.size(), 48u);
  EXPECT_LT(right_share(raw.out), 0.05);  // raw Harris: all from the strong half
  EXPECT_GT(right_share(norm.out), 0.35);  // normalised: both halves represented
}

// Anti-aliased rectangle [x0, x0 + 40) x [y0, y0 + 30) with real-valued edges.
void render_rect(ImageViewU8 img, double x0, double y0) {
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < img.width(); ++x) {
      auto cover = [](double a0, double a1, double p) {  // overlap of [p-0.5, p+0.5] with [a0, a1]
        const double lo = std::max(a0, p - 0.5), hi = std::min(a1, p + 0.5);
        return hi > lo ? hi - lo : 0.0;
      };
      const double cov = cover(x0, x0 + 40, x) * cover(y0, y0 + 30, y);
      img(x, y) = static_cast<std::uint8_t>(std::lround(40 + 180 * cov));
    }
}

TEST(Harris, SubPixelRefinementFollowsASubPixelShift) {
  std::vector<std::uint8_t> a(100 * 80), b(100 * 80);
  ImageViewU8 ia = ImageViewU8::make(a.data(), 100, 80).value();
  ImageViewU8 ib = ImageViewU8::make(b.data(), 100, 80).value();
  render_rect(ia, 20.0, 20.0);
  render_rect(ib, 20.4, 20.3);
  HarrisConfig c = small_config(100, 80);
  c.max_corners = 4;
  Fixture fa(c), fb(c);
  ASSERT_TRUE(fa.det.detect(ConstImageViewU8(ia), fa.out).is_ok());
  ASSERT_TRUE(fb.det.detect(ConstImageViewU8(ib), fb.out).is_ok());
  ASSERT_EQ(fa.out.size(), 4u);
  ASSERT_EQ(fb.out.size(), 4u);
  int matched = 0;
  for (const Corner& p : fa.out)
    for (const Corner& q : fb.out)
      if (std::hypot(q.x - p.x, q.y - p.y) < 1.5f) {
        ++matched;
        EXPECT_NEAR(q.x - p.x, 0.4f, 0.15f);
        EXPECT_NEAR(q.y - p.y, 0.3f, 0.15f);
      }
  EXPECT_EQ(matched, 4);
}

TEST(Harris, FloatInputGivesTheSameCornersAsU8) {
  const int W = 160, H = 120;
  std::vector<std::uint8_t> px(W * H);
  std::vector<float> fpx(W * H);
  ImageViewU8 img = ImageViewU8::make(px.data(), W, H).value();
  testing::texture(img, 3);
  for (int i = 0; i < W * H; ++i) fpx[i] = px[i];
  HarrisConfig c = small_config(W, H);
  Fixture a(c), b(c);
  ASSERT_TRUE(a.det.detect(ConstImageViewU8(img), a.out).is_ok());
  ASSERT_TRUE(b.det.detect(ConstImageViewF32::make(fpx.data(), W, H).value(), b.out).is_ok());
  ASSERT_EQ(a.out.size(), b.out.size());
  for (std::size_t i = 0; i < a.out.size(); ++i) {
    EXPECT_EQ(a.out[i].x, b.out[i].x);
    EXPECT_EQ(a.out[i].y, b.out[i].y);
  }
}

TEST(Harris, OddStrideViewGivesTheSameCornersAsAPackedCopy) {
  const int W = 150, H = 110, S = 157;  // odd stride, not a multiple of anything useful
  std::vector<std::uint8_t> packed(W * H), strided(S * H, 0xEE);
  ImageViewU8 pv = ImageViewU8::make(packed.data(), W, H).value();
  testing::texture(pv, 17);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) strided[static_cast<std::size_t>(y * S + x)] = pv(x, y);
  Fixture a(small_config(W, H)), b(small_config(W, H));
  ASSERT_TRUE(a.det.detect(ConstImageViewU8(pv), a.out).is_ok());
  ASSERT_TRUE(b.det.detect(ConstImageViewU8::make(strided.data(), W, H, S).value(), b.out).is_ok());
  ASSERT_EQ(a.out.size(), b.out.size());
  ASSERT_GT(a.out.size(), 20u);
  for (std::size_t i = 0; i < a.out.size(); ++i) {
    EXPECT_EQ(a.out[i].x, b.out[i].x);
    EXPECT_EQ(a.out[i].y, b.out[i].y);
  }
}

TEST(Harris, DetectDoesNotAllocate) {
  std::vector<std::uint8_t> px(320 * 256);
  ImageViewU8 img = ImageViewU8::make(px.data(), 320, 256).value();
  testing::texture(img, 5);
  Fixture f(small_config(320, 256));
  ASSERT_TRUE(f.init_status.is_ok());
  Status s;
  QNAV_EXPECT_NO_ALLOC(s = f.det.detect(ConstImageViewU8(img), RectI{40, 30, 200, 180}, f.out));
  EXPECT_TRUE(s.is_ok());
  QNAV_EXPECT_NO_ALLOC(s = f.det.detect(ConstImageViewU8(img), f.out));
  EXPECT_TRUE(s.is_ok());
  EXPECT_GT(f.out.size(), 50u);
}

TEST(Harris, RejectsBadInputWithClearErrorsAndCounters) {
  HarrisDetector d;
  std::vector<Corner> st(10);
  BoundedVector<Corner> out(Span<Corner>(st.data(), st.size()));
  std::vector<std::uint8_t> px(64 * 64, 100);
  const ConstImageViewU8 img = ConstImageViewU8::make(px.data(), 64, 64).value();
  EXPECT_EQ(d.detect(img, out), StatusCode::kNotReady);

  ArenaStorage arena(1 << 20);
  HarrisConfig bad = small_config(64, 64);
  bad.block_radius = 0;
  EXPECT_EQ(d.init(bad, arena), StatusCode::kInvalidArgument);
  bad = small_config(64, 64);
  bad.k = std::nanf("");
  EXPECT_EQ(d.init(bad, arena), StatusCode::kInvalidArgument);
  EXPECT_EQ(d.counters().get(VisionCounter::kBadConfig), 2u);
  ArenaStorage tiny(100);
  EXPECT_EQ(d.init(small_config(64, 64), tiny), StatusCode::kCapacityExceeded);

  ASSERT_TRUE(d.init(small_config(64, 64), arena).is_ok());
  EXPECT_EQ(d.detect(ConstImageViewU8(), out), StatusCode::kInvalidArgument);
  std::vector<std::uint8_t> big(65 * 64);
  EXPECT_EQ(d.detect(ConstImageViewU8::make(big.data(), 65, 64).value(), out), StatusCode::kInvalidArgument);
  EXPECT_EQ(d.counters().get(VisionCounter::kBadImage), 2u);
  EXPECT_EQ(d.detect(img, RectI{100, 100, 10, 10}, out), StatusCode::kOutOfRange);
  EXPECT_EQ(d.detect(img, RectI{10, 10, 0, 10}, out), StatusCode::kOutOfRange);
  EXPECT_EQ(d.counters().get(VisionCounter::kBadRoi), 2u);
  // A flat image is valid input with no corners; an image smaller than the border too.
  EXPECT_TRUE(d.detect(img, out).is_ok());
  EXPECT_EQ(out.size(), 0u);
  EXPECT_TRUE(d.detect(ConstImageViewU8::make(px.data(), 6, 6).value(), out).is_ok());
  EXPECT_EQ(out.size(), 0u);
  // NaN pixels in a float tile never produce NaN corners.
  std::vector<float> f(64 * 64, std::nanf(""));
  for (int i = 0; i < 64 * 64; i += 3) f[i] = static_cast<float>(i % 251);
  EXPECT_TRUE(d.detect(ConstImageViewF32::make(f.data(), 64, 64).value(), out).is_ok());
  for (const Corner& k : out) EXPECT_TRUE(std::isfinite(k.score) && std::isfinite(k.x) && std::isfinite(k.y));
}

}  // namespace
}  // namespace qnav::vision
