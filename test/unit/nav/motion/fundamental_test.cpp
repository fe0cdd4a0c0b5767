#include "nav/motion/fundamental.hpp"

#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "nav/motion/hartley.hpp"
#include "test/support/alloc_guard.hpp"
#include "test/unit/nav/motion/two_view_scene.hpp"

namespace qnav::motion {
namespace {

using test::TwoViewScene;

Span<const Vec2d> span_of(const std::vector<Vec2d>& v) { return Span<const Vec2d>(v.data(), v.size()); }

// |F_est - F_true| with both at unit norm and the sign of F_est chosen to agree.
double matrix_distance(const Mat3d& est, const Mat3d& truth) {
  const Mat3d a = est / est.norm(), b = truth / truth.norm();
  return std::min((a - b).norm(), (a + b).norm());
}

// RMS Sampson distance (px) of the noise-free correspondences under F.
double true_pairs_rms_sampson(const Mat3d& F, const TwoViewScene& s) {
  double sse = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < s.a.size(); ++i) {
    sse += sampson_distance_sq(F, s.a_true[i], s.b_true[i]);
    ++n;
  }
  return std::sqrt(sse / n);
}

TEST(Fundamental, ExactCorrespondencesGiveTheTrueMatrixWithRankTwo) {
  const TwoViewScene s = test::general_scene(40, 0.0, 0.0, 1);
  Result<FundamentalFit> f = fit_fundamental_8point(span_of(s.a), span_of(s.b));
  ASSERT_TRUE(f.is_ok()) << f.status().message();
  EXPECT_LT(matrix_distance(f->F, s.F), 1e-6);
  EXPECT_NEAR(f->F.norm(), 1.0, 1e-12);
  Eigen::JacobiSVD<Mat3d> svd(f->F);
  EXPECT_LT(svd.singularValues()(2), 1e-12);
  EXPECT_LT(f->rms_sampson_px, 1e-6);
  EXPECT_TRUE(f->unique);
  EXPECT_EQ(f->used, 40u);
}

TEST(Fundamental, EightPairsAreEnoughAndTheIndexedPathAgrees) {
  const TwoViewScene s = test::general_scene(20, 0.0, 0.0, 2);
  const std::uint32_t idx[8] = {1, 3, 5, 7, 9, 11, 13, 15};
  std::vector<std::uint8_t> mask(20, 0);
  for (std::uint32_t i : idx) mask[i] = 1;
  Result<FundamentalFit> fi = fit_fundamental_8point_indexed(span_of(s.a), span_of(s.b), Span<const std::uint32_t>(idx, 8));
  Result<FundamentalFit> fm = fit_fundamental_8point(span_of(s.a), span_of(s.b), Span<const std::uint8_t>(mask.data(), 20));
  ASSERT_TRUE(fi.is_ok() && fm.is_ok());
  EXPECT_LT(matrix_distance(fi->F, s.F), 1e-6);
  EXPECT_EQ(fi->F, fm->F);  // same pairs in the same order: the same arithmetic
}

TEST(Fundamental, HalfPixelNoiseKeepsTheTruePairsWithinHalfAPixel) {
  const TwoViewScene s = test::general_scene(120, 0.5, 0.0, 3);
  Result<FundamentalFit> f = fit_fundamental_8point(span_of(s.a), span_of(s.b));
  ASSERT_TRUE(f.is_ok()) << f.status().message();
  const double rms_true = true_pairs_rms_sampson(f->F, s);
  std::printf("[measured] F 8-point, 120 pairs, sigma 0.5 px: rms Sampson observed %.3f px, true pairs %.3f px, |dF| %.4f\n",
              f->rms_sampson_px, rms_true, matrix_distance(f->F, s.F));
  // Sampson distance of a pair with 0.5 px noise on both points ~ 0.5 px; the fit absorbs some.
  EXPECT_LT(f->rms_sampson_px, 0.8);
  EXPECT_LT(rms_true, 0.3);
  EXPECT_TRUE(f->unique);
}

TEST(Fundamental, TooFewPairsAreDegenerate) {
  const TwoViewScene s = test::general_scene(7, 0.0, 0.0, 4);
  Result<FundamentalFit> f = fit_fundamental_8point(span_of(s.a), span_of(s.b));
  ASSERT_FALSE(f.is_ok());
  EXPECT_EQ(f.status().code(), StatusCode::kDegenerate);
  // A mask leaving seven of twenty.
  const TwoViewScene t = test::general_scene(20, 0.0, 0.0, 4);
  std::vector<std::uint8_t> mask(20, 0);
  for (int i = 0; i < 7; ++i) mask[i] = 1;
  EXPECT_EQ(fit_fundamental_8point(span_of(t.a), span_of(t.b), Span<const std::uint8_t>(mask.data(), 20)).status().code(),
            StatusCode::kDegenerate);
}

TEST(Fundamental, CollinearOrCoincidentPointsAreDegenerate) {
  std::vector<Vec2d> a, b;
  for (int i = 0; i < 12; ++i) {
    a.emplace_back(10.0 + 20.0 * i, 30.0 + 10.0 * i);  // one line in image a
    b.emplace_back(15.0 + 17.0 * i + (i % 3), 200.0 - 9.0 * i * i / 10.0);
  }
  Result<FundamentalFit> f = fit_fundamental_8point(span_of(a), span_of(b));
  ASSERT_FALSE(f.is_ok());
  EXPECT_EQ(f.status().code(), StatusCode::kDegenerate);
  std::vector<Vec2d> same(12, Vec2d(100.0, 100.0));
  EXPECT_EQ(fit_fundamental_8point(span_of(same), span_of(b)).status().code(), StatusCode::kDegenerate);
}

TEST(Fundamental, NonFiniteOrMismatchedInputIsInvalid) {
  TwoViewScene s = test::general_scene(12, 0.0, 0.0, 5);
  std::vector<Vec2d> shorter(s.b.begin(), s.b.end() - 1);
  EXPECT_EQ(fit_fundamental_8point(span_of(s.a), span_of(shorter)).status().code(), StatusCode::kInvalidArgument);
  s.b[4].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(fit_fundamental_8point(span_of(s.a), span_of(s.b)).status().code(), StatusCode::kInvalidArgument);
  const std::uint32_t bad[8] = {0, 1, 2, 3, 4, 5, 6, 99};
  EXPECT_EQ(fit_fundamental_8point_indexed(span_of(s.a), span_of(s.b), Span<const std::uint32_t>(bad, 8)).status().code(),
            StatusCode::kOutOfRange);
}

TEST(Fundamental, APlanarSceneFitsEveryPairButIsFlaggedNotUnique) {
  // A flat seabed: the pairs fix only the family [e]x H, so F is not unique (the fit is still exact).
  const TwoViewScene s = test::planar_scene(40, 0.0, 0.0, 6);
  Result<FundamentalFit> f = fit_fundamental_8point(span_of(s.a), span_of(s.b));
  ASSERT_TRUE(f.is_ok()) << f.status().message();
  EXPECT_FALSE(f->unique);
  EXPECT_LT(f->unique_ratio, kMinUniqueRatio);
  EXPECT_LT(f->rms_sampson_px, 1e-6);
  const TwoViewScene g = test::general_scene(40, 0.0, 0.0, 6);
  Result<FundamentalFit> fg = fit_fundamental_8point(span_of(g.a), span_of(g.b));
  ASSERT_TRUE(fg.is_ok());
  std::printf("[measured] F uniqueness ratio: planar %.2e, general %.2e\n", f->unique_ratio, fg->unique_ratio);
  EXPECT_GT(fg->unique_ratio, 1e3 * kMinUniqueRatio);
}

TEST(Fundamental, FitAllocatesNothing) {
  const TwoViewScene s = test::general_scene(100, 0.5, 0.0, 7);
  Result<FundamentalFit> f = Status(StatusCode::kNotReady, "");
  QNAV_EXPECT_NO_ALLOC(f = fit_fundamental_8point(span_of(s.a), span_of(s.b)));
  EXPECT_TRUE(f.is_ok());
}

}  // namespace
}  // namespace qnav::motion
