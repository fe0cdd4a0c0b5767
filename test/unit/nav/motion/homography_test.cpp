#include "nav/motion/homography.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "test/support/alloc_guard.hpp"
#include "test/unit/nav/motion/two_view_scene.hpp"

namespace qnav::motion {
namespace {

using test::TwoViewScene;

Span<const Vec2d> span_of(const std::vector<Vec2d>& v) { return Span<const Vec2d>(v.data(), v.size()); }

TEST(Homography, FourExactPairsGiveTheTrueHomography) {
  const TwoViewScene s = test::planar_scene(4, 0.0, 0.0, 1);
  Result<HomographyFit> h = fit_homography_dlt(span_of(s.a), span_of(s.b));
  ASSERT_TRUE(h.is_ok()) << h.status().message();
  EXPECT_LT(test::homography_grid_error_px(h->H, s.H), 1e-7);
  EXPECT_DOUBLE_EQ(h->H(2, 2), 1.0);
  EXPECT_LT(h->rms_transfer_px, 1e-8);
}

TEST(Homography, ManyExactPairsGiveTheTrueHomography) {
  const TwoViewScene s = test::planar_scene(50, 0.0, 0.0, 2);
  Result<HomographyFit> h = fit_homography_dlt(span_of(s.a), span_of(s.b));
  ASSERT_TRUE(h.is_ok()) << h.status().message();
  EXPECT_LT(test::homography_grid_error_px(h->H, s.H), 1e-7);
  EXPECT_EQ(h->used, 50u);
}

TEST(Homography, RefinementOnNoisyPairsLowersTheSymmetricTransferError) {
  const TwoViewScene s = test::planar_scene(80, 0.7, 0.0, 3);
  Result<HomographyFit> dlt = fit_homography_dlt(span_of(s.a), span_of(s.b));
  ASSERT_TRUE(dlt.is_ok());
  Result<HomographyRefinement> r = refine_homography(span_of(s.a), span_of(s.b), dlt->H);
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  const double e_dlt = test::homography_grid_error_px(dlt->H, s.H);
  const double e_ref = test::homography_grid_error_px(r->fit.H, s.H);
  std::printf("[measured] H 80 pairs, sigma 0.7 px: symmetric rms DLT %.6f -> LM %.6f px (%u steps); grid error DLT %.3f, LM %.3f px\n",
              r->initial_rms_px, r->fit.rms_transfer_px, r->iterations, e_dlt, e_ref);
  EXPECT_NEAR(r->initial_rms_px, dlt->rms_transfer_px, 1e-9);
  EXPECT_LE(r->fit.rms_transfer_px, r->initial_rms_px);
  // sigma 0.7 px per coordinate on both points: a transfer residual has 2 sigma^2 per coordinate, so
  // the per-image distance of a perfect H is ~ 2 sigma = 1.4 px (the fit absorbs a little of it).
  EXPECT_LT(r->fit.rms_transfer_px, 1.4);
  EXPECT_GT(r->fit.rms_transfer_px, 1.0);
  EXPECT_LT(e_ref, 0.4);
  EXPECT_LE(r->iterations, HomographyRefineConfig().max_iterations);
}

TEST(Homography, RefinementConvergesFromAPerturbedStart) {
  const TwoViewScene s = test::planar_scene(30, 0.0, 0.0, 4);
  Mat3d start = s.H;
  start(0, 2) += 3.0;  // 3 px shift
  start(1, 0) += 0.01;
  start(2, 0) += 2e-5;
  ASSERT_GT(test::homography_grid_error_px(start, s.H), 2.0);
  HomographyRefineConfig c;
  c.max_iterations = 30;
  Result<HomographyRefinement> r = refine_homography(span_of(s.a), span_of(s.b), start, Span<const std::uint8_t>(), c);
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  EXPECT_LT(r->fit.rms_transfer_px, 1e-6);
  EXPECT_LT(test::homography_grid_error_px(r->fit.H, s.H), 1e-5);
}

TEST(Homography, TooFewPairsAreDegenerate) {
  const TwoViewScene s = test::planar_scene(3, 0.0, 0.0, 5);
  EXPECT_EQ(fit_homography_dlt(span_of(s.a), span_of(s.b)).status().code(), StatusCode::kDegenerate);
  EXPECT_EQ(refine_homography(span_of(s.a), span_of(s.b), s.H).status().code(), StatusCode::kDegenerate);
}

TEST(Homography, ThreeCollinearOfFourAreDegenerate) {
  const std::vector<Vec2d> a = {{10, 10}, {60, 35}, {110, 60}, {40, 200}};  // first three on a line
  const std::vector<Vec2d> b = {{20, 15}, {70, 30}, {130, 70}, {35, 210}};
  Result<HomographyFit> h = fit_homography_dlt(span_of(a), span_of(b));
  ASSERT_FALSE(h.is_ok());
  EXPECT_EQ(h.status().code(), StatusCode::kDegenerate);
  EXPECT_STREQ(h.status().message(), "homography: three of four points collinear");
}

TEST(Homography, AMirroredSampleIsDegenerate) {
  const std::vector<Vec2d> a = {{10, 10}, {200, 20}, {190, 180}, {20, 170}};
  const std::vector<Vec2d> b = {{200, 10}, {10, 20}, {20, 180}, {190, 170}};  // x flipped
  EXPECT_EQ(fit_homography_dlt(span_of(a), span_of(b)).status().code(), StatusCode::kDegenerate);
}

TEST(Homography, AllCollinearOrCoincidentPointsAreDegenerate) {
  std::vector<Vec2d> a, b;
  for (int i = 0; i < 10; ++i) {
    a.emplace_back(5.0 + 30.0 * i, 7.0 + 20.0 * i);
    b.emplace_back(9.0 + 28.0 * i, 3.0 + 21.0 * i);
  }
  EXPECT_EQ(fit_homography_dlt(span_of(a), span_of(b)).status().code(), StatusCode::kDegenerate);
  std::vector<Vec2d> same(10, Vec2d(50.0, 60.0));
  EXPECT_EQ(fit_homography_dlt(span_of(same), span_of(b)).status().code(), StatusCode::kDegenerate);
}

TEST(Homography, NonFiniteMismatchedOrSingularInputIsRefused) {
  TwoViewScene s = test::planar_scene(10, 0.0, 0.0, 6);
  std::vector<Vec2d> shorter(s.b.begin(), s.b.end() - 1);
  EXPECT_EQ(fit_homography_dlt(span_of(s.a), span_of(shorter)).status().code(), StatusCode::kInvalidArgument);
  Mat3d singular = Mat3d::Zero();
  singular(0, 0) = 1.0;
  singular(1, 1) = 1.0;  // rank 2
  EXPECT_EQ(refine_homography(span_of(s.a), span_of(s.b), singular).status().code(), StatusCode::kDegenerate);
  s.a[2].y() = std::numeric_limits<double>::infinity();
  EXPECT_EQ(fit_homography_dlt(span_of(s.a), span_of(s.b)).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(refine_homography(span_of(s.a), span_of(s.b), s.H).status().code(), StatusCode::kInvalidArgument);
}

TEST(Homography, SymmetricTransferErrorIsZeroForTheTruthAndInfiniteAtTheHorizon) {
  const TwoViewScene s = test::planar_scene(5, 0.0, 0.0, 7);
  const Mat3d hinv = s.H.inverse();
  for (std::size_t i = 0; i < s.a.size(); ++i) EXPECT_LT(symmetric_transfer_error_sq(s.H, hinv, s.a[i], s.b[i]), 1e-16);
  Mat3d h = Mat3d::Identity();
  h(2, 0) = 0.01;  // the line x = -100 maps to infinity
  EXPECT_TRUE(std::isinf(symmetric_transfer_error_sq(h, h.inverse(), Vec2d(-100.0, 5.0), Vec2d(0.0, 0.0))));
}

TEST(Homography, FitAndRefinementAllocateNothing) {
  const TwoViewScene s = test::planar_scene(100, 0.5, 0.0, 8);
  Result<HomographyFit> h = Status(StatusCode::kNotReady, "");
  QNAV_EXPECT_NO_ALLOC(h = fit_homography_dlt(span_of(s.a), span_of(s.b)));
  ASSERT_TRUE(h.is_ok());
  Result<HomographyRefinement> r = Status(StatusCode::kNotReady, "");
  QNAV_EXPECT_NO_ALLOC(r = refine_homography(span_of(s.a), span_of(s.b), h->H));
  EXPECT_TRUE(r.is_ok());
}

}  // namespace
}  // namespace qnav::motion
