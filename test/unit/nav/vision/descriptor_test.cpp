#include "nav/vision/descriptor.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "nav/vision/harris.hpp"
#include "test/support/alloc_guard.hpp"
#include "test_images.hpp"

namespace qnav::vision {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

struct Pair {
  std::vector<std::uint8_t> a, b;
  ImageViewU8 va, vb;
  Pair(int w, int h, double angle, double scale, double noise, std::uint64_t seed)
      : a(static_cast<std::size_t>(w * h)), b(static_cast<std::size_t>(w * h)) {
    va = ImageViewU8::make(a.data(), w, h).value();
    vb = ImageViewU8::make(b.data(), w, h).value();
    testing::texture(va, seed);
    testing::warp_similarity(va, angle, scale, noise, vb);
  }
};

TEST(PatchDescriptor, IsZeroMeanUnitNormAndInvariantToGainAndOffset) {
  Pair p(120, 100, 0, 1, 0, 4);
  std::vector<std::uint8_t> g(p.a.size());
  for (std::size_t i = 0; i < g.size(); ++i) g[i] = static_cast<std::uint8_t>(0.5 * p.a[i] + 40);
  PatchDescriptor d1, d2;
  ASSERT_TRUE(compute_patch_descriptor(p.va, 50.3f, 40.7f, 0.0f, 1.0f, d1).is_ok());
  ASSERT_TRUE(compute_patch_descriptor(ImageViewU8::make(g.data(), 120, 100).value(), 50.3f, 40.7f, 0.0f, 1.0f, d2).is_ok());
  float sum = 0, ss = 0;
  for (float v : d1.v) sum += v, ss += v * v;
  EXPECT_NEAR(sum, 0.0f, 1e-4f);
  EXPECT_NEAR(ss, 1.0f, 1e-4f);
  EXPECT_NEAR(zncc(d1, d1), 1.0f, 1e-5f);
  EXPECT_GT(zncc(d1, d2), 0.99f);  // 8-bit rounding of the halved image only
  // Float tile gives the same descriptor as the u8 image.
  std::vector<float> f(p.a.begin(), p.a.end());
  PatchDescriptor d3;
  ASSERT_TRUE(compute_patch_descriptor(ImageViewF32::make(f.data(), 120, 100).value(), 50.3f, 40.7f, 0.0f, 1.0f, d3).is_ok());
  EXPECT_NEAR(zncc(d1, d3), 1.0f, 1e-5f);
}

TEST(PatchDescriptor, KnownRotationIsCompensated) {
  const double angle = 35 * kDeg;
  Pair p(160, 160, angle, 1.0, 0, 6);
  int good_rot = 0, good_plain = 0, n = 0;
  for (int k = 0; k < 30; ++k) {
    const float qx = 50.0f + 2.0f * static_cast<float>(k % 6) * 5.0f, qy = 55.0f + 10.0f * static_cast<float>(k / 6);
    double px, py;
    testing::warp_point(160, 160, angle, 1.0, qx, qy, px, py);
    PatchDescriptor a, b, b0;
    ASSERT_TRUE(compute_patch_descriptor(p.va, qx, qy, 0.0f, 1.0f, a).is_ok());
    ASSERT_TRUE(compute_patch_descriptor(p.vb, static_cast<float>(px), static_cast<float>(py), static_cast<float>(angle), 1.0f, b).is_ok());
    ASSERT_TRUE(compute_patch_descriptor(p.vb, static_cast<float>(px), static_cast<float>(py), 0.0f, 1.0f, b0).is_ok());
    ++n;
    good_rot += zncc(a, b) > 0.9f ? 1 : 0;
    good_plain += zncc(a, b0) > 0.9f ? 1 : 0;
  }
  EXPECT_EQ(good_rot, n);
  EXPECT_LT(good_plain, n / 3);  // without the rotation the patches disagree (the test can fail)
}

TEST(PatchDescriptor, RejectsOutOfImageFlatAndNaN) {
  std::vector<std::uint8_t> flat(50 * 50, 90);
  const ConstImageViewU8 f = ConstImageViewU8::make(flat.data(), 50, 50).value();
  PatchDescriptor d;
  EXPECT_EQ(compute_patch_descriptor(f, 25.0f, 25.0f, 0.0f, 1.0f, d), StatusCode::kDegenerate);
  EXPECT_FALSE(d.valid);
  EXPECT_EQ(compute_patch_descriptor(f, 3.0f, 25.0f, 0.0f, 1.0f, d), StatusCode::kOutOfRange);
  EXPECT_EQ(compute_patch_descriptor(f, 25.0f, 25.0f, 0.0f, 4.0f, d), StatusCode::kOutOfRange);
  EXPECT_EQ(compute_patch_descriptor(f, std::nanf(""), 25.0f, 0.0f, 1.0f, d), StatusCode::kInvalidArgument);
  EXPECT_EQ(compute_patch_descriptor(f, 25.0f, 25.0f, 0.0f, 0.0f, d), StatusCode::kInvalidArgument);
  EXPECT_EQ(compute_patch_descriptor(ConstImageViewU8(), 25.0f, 25.0f, 0.0f, 1.0f, d), StatusCode::kInvalidArgument);
  PatchDescriptor ok;
  EXPECT_EQ(zncc(d, ok), -2.0f);
}

// Nearest-neighbour matching with Lowe's ratio test between corners of an image and a rotated copy.
TEST(OrientedDescriptor, SurvivesRotationAndMatchesWithTheRatioTest) {
  for (double angle_deg : {30.0, 150.0}) {
    const double angle = angle_deg * kDeg;
    Pair p(160, 160, angle, 1.0, 2.0, 12);
    HarrisConfig hc;
    hc.max_width = 160;
    hc.max_height = 160;
    hc.max_corners = 60;
    ArenaStorage arena(HarrisDetector::arena_bytes(hc));
    HarrisDetector det;
    ASSERT_TRUE(det.init(hc, arena).is_ok());
    std::vector<Corner> cs(60);
    BoundedVector<Corner> corners(Span<Corner>(cs.data(), cs.size()));
    ASSERT_TRUE(det.detect(p.va, RectI{35, 35, 90, 90}, corners).is_ok());
    std::vector<OrientedDescriptor> da, db;
    std::vector<double> ori_err;
    for (const Corner& c : corners) {
      double px, py;
      testing::warp_point(160, 160, angle, 1.0, c.x, c.y, px, py);
      OrientedDescriptor a, b;
      if (!compute_oriented_descriptor(p.va, c.x, c.y, 1.0f, a).is_ok()) continue;
      if (!compute_oriented_descriptor(p.vb, static_cast<float>(px), static_cast<float>(py), 1.0f, b).is_ok()) continue;
      double e = std::fmod(static_cast<double>(b.orientation_rad - a.orientation_rad) - angle + 20 * 3.141592653589793,
                           2 * 3.141592653589793);
      if (e > 3.141592653589793) e -= 2 * 3.141592653589793;
      ori_err.push_back(std::fabs(e));
      da.push_back(a);
      db.push_back(b);
    }
    ASSERT_GT(da.size(), 30u);
    int correct = 0, accepted = 0;
    for (std::size_t i = 0; i < da.size(); ++i) {
      float best = 1e30f, second = 1e30f;
      std::size_t bi = 0;
      for (std::size_t j = 0; j < db.size(); ++j) {
        const float d = descriptor_distance_sq(da[i], db[j]);
        if (d < best) second = best, best = d, bi = j;
        else if (d < second) second = d;
      }
      if (best < 0.64f * second) {  // ratio 0.8 on distances
        ++accepted;
        correct += bi == i ? 1 : 0;
      }
    }
    std::sort(ori_err.begin(), ori_err.end());
    EXPECT_LT(ori_err[ori_err.size() / 2], 5 * kDeg) << angle_deg;
    EXPECT_GT(accepted, static_cast<int>(da.size()) * 7 / 10) << angle_deg;
    EXPECT_GE(correct, accepted * 9 / 10) << angle_deg;  // measured 92..100 %
  }
}

TEST(OrientedDescriptor, RejectsBadInputAndDoesNotAllocate) {
  Pair p(80, 80, 0, 1, 0, 3);
  OrientedDescriptor d;
  Status s;
  QNAV_EXPECT_NO_ALLOC(s = compute_oriented_descriptor(p.va, 40.0f, 40.0f, 1.0f, d));
  EXPECT_TRUE(s.is_ok());
  EXPECT_TRUE(d.valid);
  float ss = 0;
  for (float v : d.v) {
    ss += v * v;
    EXPECT_LE(v, 0.2f / 0.7f);  // clipped at 0.2 before renormalisation
  }
  EXPECT_NEAR(ss, 1.0f, 1e-4f);
  EXPECT_EQ(compute_oriented_descriptor(p.va, 5.0f, 40.0f, 1.0f, d), StatusCode::kOutOfRange);
  EXPECT_FALSE(d.valid);
  EXPECT_EQ(compute_oriented_descriptor(p.va, 30.0f, 40.0f, 4.0f, d), StatusCode::kOutOfRange);  // support radius 35 px
  EXPECT_EQ(compute_oriented_descriptor(p.va, 40.0f, 40.0f, 5.0f, d), StatusCode::kInvalidArgument);  // > kOrientedMaxScale
  EXPECT_EQ(compute_oriented_descriptor(p.va, 40.0f, 40.0f, 0.0f, d), StatusCode::kInvalidArgument);
  EXPECT_EQ(compute_oriented_descriptor(p.va, std::nanf(""), 40.0f, 1.0f, d), StatusCode::kInvalidArgument);
  std::vector<std::uint8_t> flat(80 * 80, 10);
  EXPECT_EQ(compute_oriented_descriptor(ConstImageViewU8::make(flat.data(), 80, 80).value(), 40.0f, 40.0f, 1.0f, d),
            StatusCode::kDegenerate);
  OrientedDescriptor ok;
  EXPECT_GT(descriptor_distance_sq(d, ok), 1e20f);
}

}  // namespace
}  // namespace qnav::vision

namespace qnav::vision {
namespace {

// The gradient-plane path (what the homography chain runs) gives the per-support path's descriptor bit
// for bit, and the same errors, at every scale, sub-pixel positions and the image edges.
TEST(OrientedDescriptor, FromGradientPlanesIsBitIdenticalToThePerSupportPath) {
  constexpr int kW = 160, kH = 120;
  Pair p(kW, kH, 0, 1, 0, 11);
  std::vector<float> mag(kW * kH, -1.0f), ang(kW * kH, -1.0f);
  GradientPlanes planes;
  ASSERT_TRUE(compute_gradient_planes(ConstImageViewU8(p.va), Span<float>(mag.data(), mag.size()),
                                      Span<float>(ang.data(), ang.size()), planes)
                  .is_ok());
  int compared = 0, refused = 0;
  const float scales[] = {0.25f, 0.5f, 1.0f, 1.5f, 2.0f, 3.0f, 4.0f};
  for (float scale : scales) {
    for (int k = 0; k < 60; ++k) {
      const float x = 2.0f + static_cast<float>((k * 37) % 157) + 0.13f * static_cast<float>(k % 7);
      const float y = 2.0f + static_cast<float>((k * 53) % 117) - 0.29f * static_cast<float>(k % 5);
      OrientedDescriptor a, b;
      const Status sa = compute_oriented_descriptor(p.va, x, y, scale, a);
      const Status sb = compute_oriented_descriptor(planes, x, y, scale, b);
      ASSERT_EQ(sa.code(), sb.code()) << x << " " << y << " " << scale;
      ASSERT_EQ(a.valid, b.valid);
      if (!sa.is_ok()) {
        ++refused;
        continue;
      }
      ++compared;
      ASSERT_EQ(std::memcmp(a.v, b.v, sizeof a.v), 0) << x << " " << y << " " << scale;
      ASSERT_EQ(std::memcmp(&a.orientation_rad, &b.orientation_rad, sizeof(float)), 0);
    }
  }
  EXPECT_GT(compared, 150);  // most points inside, and some supports leave the image
  EXPECT_GT(refused, 20);
  // Planes too small, an image under 3 x 3, empty planes: named errors.
  EXPECT_EQ(compute_gradient_planes(ConstImageViewU8(p.va), Span<float>(mag.data(), 10), Span<float>(ang.data(), ang.size()), planes)
                .code(),
            StatusCode::kCapacityExceeded);
  OrientedDescriptor d;
  EXPECT_EQ(compute_oriented_descriptor(GradientPlanes{}, 50.0f, 50.0f, 1.0f, d).code(), StatusCode::kInvalidArgument);
  EXPECT_FALSE(d.valid);
}

}  // namespace
}  // namespace qnav::vision
