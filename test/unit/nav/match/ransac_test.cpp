#include "nav/match/ransac.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "test/support/alloc_guard.hpp"

namespace qnav::match {
namespace {

struct Data {
  std::vector<Vec2d> src, dst;
  std::vector<bool> inlier;
};

Data make(int n, double outlier_frac, double noise_m, const Pose2& truth, std::uint64_t seed) {
  DeterministicRng rng(seed);
  Data d;
  for (int i = 0; i < n; ++i) {
    const Vec2d s((rng.uniform() - 0.5) * 100.0, (rng.uniform() - 0.5) * 60.0);
    const bool in = rng.uniform() >= outlier_frac;
    Vec2d t = truth.apply(s) + Vec2d((rng.uniform() - 0.5) * 2 * noise_m, (rng.uniform() - 0.5) * 2 * noise_m);
    if (!in) t = Vec2d((rng.uniform() - 0.5) * 100.0, (rng.uniform() - 0.5) * 60.0);
    d.src.push_back(s);
    d.dst.push_back(t);
    d.inlier.push_back(in);
  }
  return d;
}

class RobustBoth : public ::testing::TestWithParam<RobustMethod> {};

TEST_P(RobustBoth, FindsTheTransformWithFortyPercentOutliers) {
  const Pose2 truth{12.0, -3.0, 0.3};
  Data d = make(80, 0.4, 0.2, truth, 7);
  RobustConfig c;
  c.method = GetParam();
  c.inlier_threshold_m = 0.6;
  std::vector<std::uint8_t> mask(d.src.size());
  std::vector<double> scratch(d.src.size());
  Result<RobustRigid2d> r = robust_rigid2d(Span<const Vec2d>(d.src.data(), d.src.size()), Span<const Vec2d>(d.dst.data(), d.dst.size()), c,
                                           Span<std::uint8_t>(mask.data(), mask.size()), Span<double>(scratch.data(), scratch.size()));
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  EXPECT_NEAR(r->fit.pose.x_m, 12.0, 0.15);
  EXPECT_NEAR(r->fit.pose.y_m, -3.0, 0.15);
  EXPECT_NEAR(r->fit.pose.heading_rad, 0.3, 0.005);
  int true_in = 0, agree = 0;
  for (std::size_t i = 0; i < d.src.size(); ++i) {
    true_in += d.inlier[i];
    agree += (mask[i] != 0) == d.inlier[i];
  }
  EXPECT_GE(r->inliers, static_cast<std::uint32_t>(true_in * 9 / 10));
  EXPECT_GE(agree, static_cast<int>(d.src.size()) - 3);
  EXPECT_LE(r->iterations, c.max_iterations);
}

TEST_P(RobustBoth, IsDeterministicForASeedAndAllocatesNothing) {
  Data d = make(60, 0.3, 0.1, Pose2{1, 2, -1.2}, 11);
  RobustConfig c;
  c.method = GetParam();
  std::vector<std::uint8_t> m1(60), m2(60);
  std::vector<double> s(60);
  Result<RobustRigid2d> a = Status(StatusCode::kNotReady, "");
  QNAV_EXPECT_NO_ALLOC(a = robust_rigid2d(Span<const Vec2d>(d.src.data(), 60), Span<const Vec2d>(d.dst.data(), 60), c,
                                          Span<std::uint8_t>(m1.data(), 60), Span<double>(s.data(), 60)));
  Result<RobustRigid2d> b = robust_rigid2d(Span<const Vec2d>(d.src.data(), 60), Span<const Vec2d>(d.dst.data(), 60), c,
                                           Span<std::uint8_t>(m2.data(), 60), Span<double>(s.data(), 60));
  ASSERT_TRUE(a.is_ok() && b.is_ok());
  EXPECT_EQ(a->inliers, b->inliers);
  EXPECT_EQ(a->fit.pose.x_m, b->fit.pose.x_m);
  EXPECT_EQ(m1, m2);
}

INSTANTIATE_TEST_SUITE_P(Methods, RobustBoth, ::testing::Values(RobustMethod::kRansac, RobustMethod::kLmeds));

TEST(Ransac, PureNoiseGivesFewInliersOrNotFound) {
  DeterministicRng rng(3);
  std::vector<Vec2d> s(50), t(50);
  for (int i = 0; i < 50; ++i) {
    s[i] = Vec2d(rng.uniform() * 100, rng.uniform() * 100);
    t[i] = Vec2d(rng.uniform() * 100, rng.uniform() * 100);
  }
  RobustConfig c;
  c.inlier_threshold_m = 0.5;
  c.min_inliers = 6;
  std::vector<std::uint8_t> m(50);
  std::vector<double> sc(50);
  Result<RobustRigid2d> r = robust_rigid2d(Span<const Vec2d>(s.data(), 50), Span<const Vec2d>(t.data(), 50), c,
                                           Span<std::uint8_t>(m.data(), 50), Span<double>(sc.data(), 50));
  EXPECT_EQ(r.status(), StatusCode::kNotFound);
}

TEST(Ransac, RejectsBadInput) {
  Vec2d a[3] = {{0, 0}, {1, 0}, {std::nan(""), 0}};
  std::uint8_t m[3];
  double s[3];
  RobustConfig c;
  c.min_inliers = 2;
  EXPECT_EQ(robust_rigid2d(Span<const Vec2d>(a), Span<const Vec2d>(a), c, Span<std::uint8_t>(m), Span<double>(s)).status(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(robust_rigid2d(Span<const Vec2d>(a), Span<const Vec2d>(a, 2), c, Span<std::uint8_t>(m), Span<double>(s)).status(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(robust_rigid2d(Span<const Vec2d>(a), Span<const Vec2d>(a), c, Span<std::uint8_t>(m, 1), Span<double>(s)).status(),
            StatusCode::kCapacityExceeded);
}

}  // namespace
}  // namespace qnav::match
