#include "nav/motion/rigid2d.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace qnav::motion {
namespace {

TEST(Rigid2d, RecoversAnExactTransform) {
  const Pose2 truth{3.0, -2.0, 0.7};
  Vec2d src[6] = {{0, 0}, {5, 1}, {-3, 4}, {2, -6}, {7, 7}, {-1, -2}};
  Vec2d dst[6];
  for (int i = 0; i < 6; ++i) dst[i] = truth.apply(src[i]);
  Result<Rigid2dFit> f = fit_rigid2d(Span<const Vec2d>(src), Span<const Vec2d>(dst));
  ASSERT_TRUE(f.is_ok());
  EXPECT_NEAR(f->pose.x_m, 3.0, 1e-9);
  EXPECT_NEAR(f->pose.y_m, -2.0, 1e-9);
  EXPECT_NEAR(f->pose.heading_rad, 0.7, 1e-9);
  EXPECT_LT(f->rms_m, 1e-9);
}

TEST(Rigid2d, HandlesHalfTurnAndMaskedOutliers) {
  const Pose2 truth{-10.0, 4.0, 3.0};  // near pi: a reverse pass
  Vec2d src[5] = {{0, 0}, {5, 1}, {-3, 4}, {2, -6}, {9, 9}};
  Vec2d dst[5];
  for (int i = 0; i < 5; ++i) dst[i] = truth.apply(src[i]);
  dst[4] += Vec2d(30, -30);
  const std::uint8_t mask[5] = {1, 1, 1, 1, 0};
  Result<Rigid2dFit> f = fit_rigid2d(Span<const Vec2d>(src), Span<const Vec2d>(dst), Span<const std::uint8_t>(mask));
  ASSERT_TRUE(f.is_ok());
  EXPECT_NEAR(f->pose.heading_rad, 3.0, 1e-9);
  EXPECT_NEAR(f->pose.x_m, -10.0, 1e-9);
  EXPECT_EQ(f->used, 4u);
}

TEST(Rigid2d, CovarianceGrowsWithNoise) {
  const Pose2 truth{1.0, 2.0, 0.1};
  Vec2d src[8], dst[8], dst2[8];
  for (int i = 0; i < 8; ++i) {
    src[i] = Vec2d(std::cos(i * 0.8) * 10, std::sin(i * 1.3) * 10);
    const Vec2d e(((i * 37) % 7 - 3) * 0.01, ((i * 53) % 5 - 2) * 0.01);
    dst[i] = truth.apply(src[i]) + e;
    dst2[i] = truth.apply(src[i]) + 10.0 * e;
  }
  Result<Rigid2dFit> a = fit_rigid2d(Span<const Vec2d>(src), Span<const Vec2d>(dst));
  Result<Rigid2dFit> b = fit_rigid2d(Span<const Vec2d>(src), Span<const Vec2d>(dst2));
  ASSERT_TRUE(a.is_ok() && b.is_ok());
  EXPECT_GT(a->covariance(0, 0), 0.0);
  EXPECT_NEAR(b->covariance(0, 0) / a->covariance(0, 0), 100.0, 1.0);
  EXPECT_NEAR(a->pose.heading_rad, 0.1, 0.01);
}

TEST(Rigid2d, DegenerateAndBadInputAreErrors) {
  Vec2d one[1] = {{1, 1}};
  EXPECT_EQ(fit_rigid2d(Span<const Vec2d>(one), Span<const Vec2d>(one)).status(), StatusCode::kDegenerate);
  Vec2d same[3] = {{1, 1}, {1, 1}, {1, 1}};
  EXPECT_EQ(fit_rigid2d(Span<const Vec2d>(same), Span<const Vec2d>(same)).status(), StatusCode::kDegenerate);
  Vec2d nan[2] = {{0, 0}, {std::nan(""), 1}};
  EXPECT_EQ(fit_rigid2d(Span<const Vec2d>(nan), Span<const Vec2d>(nan)).status(), StatusCode::kInvalidArgument);
  EXPECT_EQ(rigid2d_from_two(Vec2d(0, 0), Vec2d(0.1, 0), Vec2d(0, 0), Vec2d(0.1, 0), 0.5).status(), StatusCode::kDegenerate);
}

}  // namespace
}  // namespace qnav::motion
