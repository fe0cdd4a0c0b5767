#include "nav/match/robust_two_view.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "test/support/alloc_guard.hpp"
#include "test/unit/nav/motion/two_view_scene.hpp"

namespace qnav::match {
namespace {

using test::TwoViewScene;

Span<const Vec2d> span_of(const std::vector<Vec2d>& v) { return Span<const Vec2d>(v.data(), v.size()); }

struct MaskScore {
  int true_kept = 0;    // true correspondences in the mask
  int false_kept = 0;   // outliers in the mask
  int true_total = 0;
  int false_total = 0;
};

MaskScore score(const std::vector<std::uint8_t>& mask, const TwoViewScene& s) {
  MaskScore m;
  for (std::size_t i = 0; i < mask.size(); ++i) {
    if (s.inlier[i] != 0) {
      ++m.true_total;
      m.true_kept += mask[i] != 0;
    } else {
      ++m.false_total;
      m.false_kept += mask[i] != 0;
    }
  }
  return m;
}

double true_pairs_rms_sampson(const Mat3d& F, const TwoViewScene& s) {
  double sse = 0.0;
  for (std::size_t i = 0; i < s.a.size(); ++i) sse += motion::sampson_distance_sq(F, s.a_true[i], s.b_true[i]);
  return std::sqrt(sse / static_cast<double>(s.a.size()));
}

const char* name(RobustMethod m) { return m == RobustMethod::kRansac ? "RANSAC" : "LMedS"; }

class TwoViewBoth : public ::testing::TestWithParam<RobustMethod> {};

TEST_P(TwoViewBoth, HomographyWithFortyPercentOutliersRecoversTheInliersAndH) {
  const TwoViewScene s = test::planar_scene(200, 0.5, 0.4, 11);
  RobustTwoViewConfig c;
  c.method = GetParam();
  c.max_iterations = 500;
  std::vector<std::uint8_t> mask(s.a.size());
  std::vector<double> scratch(s.a.size());
  Result<RobustHomography> r = robust_homography(span_of(s.a), span_of(s.b), c, Span<std::uint8_t>(mask.data(), mask.size()),
                                                 Span<double>(scratch.data(), scratch.size()));
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  const MaskScore m = score(mask, s);
  const double err = test::homography_grid_error_px(r->fit.H, s.H);
  std::printf("[measured] H %s, 200 pairs, %d outliers, sigma 0.5 px: inliers %d/%d kept, %d outliers kept, threshold %.2f px, "
              "%u hypotheses, grid error %.3f px, rms %.3f px\n",
              name(GetParam()), m.false_total, m.true_kept, m.true_total, m.false_kept, r->threshold_px, r->iterations, err,
              r->fit.rms_transfer_px);
  EXPECT_GE(m.true_kept, m.true_total * 95 / 100);
  EXPECT_LE(m.false_kept, 3);
  EXPECT_EQ(r->inliers, static_cast<std::uint32_t>(m.true_kept + m.false_kept));
  // 0.5 px noise over ~120 inliers: the fitted H transfers the image within a few tenths of a pixel.
  EXPECT_LT(err, 0.35);
  EXPECT_LE(r->iterations, c.max_iterations);
}

TEST_P(TwoViewBoth, FundamentalWithFortyPercentOutliersRecoversTheInliers) {
  const TwoViewScene s = test::general_scene(200, 0.5, 0.4, 12);
  RobustTwoViewConfig c;
  c.method = GetParam();
  std::vector<std::uint8_t> mask(s.a.size());
  std::vector<double> scratch(s.a.size());
  Result<RobustFundamental> r = robust_fundamental(span_of(s.a), span_of(s.b), c, Span<std::uint8_t>(mask.data(), mask.size()),
                                                   Span<double>(scratch.data(), scratch.size()));
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  const MaskScore m = score(mask, s);
  const double rms_true = true_pairs_rms_sampson(r->fit.F, s);
  std::printf("[measured] F %s, 200 pairs, %d outliers, sigma 0.5 px: inliers %d/%d kept, %d outliers kept, threshold %.2f px, "
              "%u hypotheses, true pairs rms Sampson %.3f px\n",
              name(GetParam()), m.false_total, m.true_kept, m.true_total, m.false_kept, r->threshold_px, r->iterations, rms_true);
  EXPECT_GE(m.true_kept, m.true_total * 93 / 100);
  // An outlier passes an epipolar test when it falls within the threshold of its epipolar line: a
  // band of ~ 2 x 1.5 px x 400 px of the 320 x 240 image, ~ 1.5 % of them; allow 6 %.
  EXPECT_LE(m.false_kept, m.false_total * 6 / 100);
  EXPECT_LT(rms_true, 0.35);
  EXPECT_TRUE(r->fit.unique);
  EXPECT_LE(r->iterations, c.max_iterations);
}

TEST_P(TwoViewBoth, SameSeedSameAnswerAndNoAllocation) {
  const TwoViewScene s = test::planar_scene(150, 0.5, 0.3, 13);
  const TwoViewScene g = test::general_scene(150, 0.5, 0.3, 13);
  RobustTwoViewConfig c;
  c.method = GetParam();
  const std::size_t n = 150;
  std::vector<std::uint8_t> m1(n), m2(n);
  std::vector<double> scratch(n);
  Result<RobustHomography> h1 = Status(StatusCode::kNotReady, "");
  Result<RobustFundamental> f1 = Status(StatusCode::kNotReady, "");
  QNAV_EXPECT_NO_ALLOC(h1 = robust_homography(span_of(s.a), span_of(s.b), c, Span<std::uint8_t>(m1.data(), n),
                                              Span<double>(scratch.data(), n)));
  Result<RobustHomography> h2 =
      robust_homography(span_of(s.a), span_of(s.b), c, Span<std::uint8_t>(m2.data(), n), Span<double>(scratch.data(), n));
  ASSERT_TRUE(h1.is_ok() && h2.is_ok());
  EXPECT_EQ(h1->fit.H, h2->fit.H);
  EXPECT_EQ(m1, m2);
  QNAV_EXPECT_NO_ALLOC(f1 = robust_fundamental(span_of(g.a), span_of(g.b), c, Span<std::uint8_t>(m1.data(), n),
                                               Span<double>(scratch.data(), n)));
  Result<RobustFundamental> f2 =
      robust_fundamental(span_of(g.a), span_of(g.b), c, Span<std::uint8_t>(m2.data(), n), Span<double>(scratch.data(), n));
  ASSERT_TRUE(f1.is_ok() && f2.is_ok());
  EXPECT_EQ(f1->fit.F, f2->fit.F);
  EXPECT_EQ(m1, m2);
  // Another seed: the same inliers up to a few borderline pairs.
  c.seed = 0xBEEF;
  Result<RobustHomography> h3 =
      robust_homography(span_of(s.a), span_of(s.b), c, Span<std::uint8_t>(m2.data(), n), Span<double>(scratch.data(), n));
  ASSERT_TRUE(h3.is_ok());
  EXPECT_NEAR(static_cast<double>(h3->inliers), static_cast<double>(h1->inliers), 3.0);
}

TEST_P(TwoViewBoth, AllOutliersFindNoConsensus) {
  // Pure random pairs: no H / F explains min_inliers of them within the threshold; LMedS's median
  // residual is far above max_threshold_px.
  const TwoViewScene s = test::planar_scene(100, 0.5, 1.0, 14);
  RobustTwoViewConfig c;
  c.method = GetParam();
  c.min_inliers = 20;
  std::vector<std::uint8_t> mask(100);
  std::vector<double> scratch(100);
  Result<RobustHomography> h =
      robust_homography(span_of(s.a), span_of(s.b), c, Span<std::uint8_t>(mask.data(), 100), Span<double>(scratch.data(), 100));
  ASSERT_FALSE(h.is_ok());
  EXPECT_EQ(h.status().code(), StatusCode::kNotFound);
  Result<RobustFundamental> f =
      robust_fundamental(span_of(s.a), span_of(s.b), c, Span<std::uint8_t>(mask.data(), 100), Span<double>(scratch.data(), 100));
  ASSERT_FALSE(f.is_ok());
  EXPECT_EQ(f.status().code(), StatusCode::kNotFound);
}

INSTANTIATE_TEST_SUITE_P(Methods, TwoViewBoth, ::testing::Values(RobustMethod::kRansac, RobustMethod::kLmeds));

TEST(RobustFundamentalBoth, KeepsOnlyTheMatchesBothMethodsAccept) {
  const TwoViewScene s = test::general_scene(250, 0.5, 0.4, 21);
  const std::size_t n = s.a.size();
  RobustTwoViewConfig rc, lc;
  lc.method = RobustMethod::kLmeds;
  std::vector<std::uint8_t> both(n), lmeds_mask(n), ransac_only(n);
  std::vector<double> scratch(n);
  Result<FundamentalConsensus> r = Status(StatusCode::kNotReady, "");
  QNAV_EXPECT_NO_ALLOC(r = robust_fundamental_both(span_of(s.a), span_of(s.b), rc, lc, Span<std::uint8_t>(both.data(), n),
                                                   Span<std::uint8_t>(lmeds_mask.data(), n), Span<double>(scratch.data(), n)));
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  // The RANSAC mask alone, to check both ⊆ ransac and both ⊆ lmeds.
  Result<RobustFundamental> ro = robust_fundamental(span_of(s.a), span_of(s.b), rc, Span<std::uint8_t>(ransac_only.data(), n),
                                                    Span<double>(scratch.data(), n));
  ASSERT_TRUE(ro.is_ok());
  int common = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (both[i] != 0) {
      EXPECT_NE(ransac_only[i], 0) << i;
      EXPECT_NE(lmeds_mask[i], 0) << i;
    }
    common += (ransac_only[i] != 0 && lmeds_mask[i] != 0);
  }
  EXPECT_EQ(r->inliers, static_cast<std::uint32_t>(common));
  const MaskScore mb = score(both, s), mr = score(ransac_only, s), ml = score(lmeds_mask, s);
  std::printf("[measured] F RANSAC+LMedS, 250 pairs, %d outliers: outliers kept RANSAC %d, LMedS %d, both %d; inliers kept %d, %d, %d of %d; "
              "true pairs rms Sampson %.3f px\n",
              mb.false_total, mr.false_kept, ml.false_kept, mb.false_kept, mr.true_kept, ml.true_kept, mb.true_kept, mb.true_total,
              true_pairs_rms_sampson(r->fit.F, s));
  EXPECT_LE(mb.false_kept, std::min(mr.false_kept, ml.false_kept));
  EXPECT_GE(mb.true_kept, mb.true_total * 90 / 100);
  EXPECT_LE(mb.false_kept, mb.false_total * 5 / 100);
  EXPECT_EQ(r->fit.used, r->inliers);
  EXPECT_LT(true_pairs_rms_sampson(r->fit.F, s), 0.35);
}

TEST(RobustFundamentalBoth, OnAFlatSeabedItStillSeparatesTheOutliers) {
  // The paper's case: a downward camera over a flat floor. F is not unique there (fundamental.hpp),
  // but every F of the family passes the true pairs, so the epipolar test still removes outliers.
  const TwoViewScene s = test::planar_scene(200, 0.5, 0.4, 22);
  const std::size_t n = s.a.size();
  RobustTwoViewConfig rc, lc;
  std::vector<std::uint8_t> both(n), tmp(n);
  std::vector<double> scratch(n);
  Result<FundamentalConsensus> r = robust_fundamental_both(span_of(s.a), span_of(s.b), rc, lc, Span<std::uint8_t>(both.data(), n),
                                                           Span<std::uint8_t>(tmp.data(), n), Span<double>(scratch.data(), n));
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  const MaskScore m = score(both, s);
  std::printf("[measured] F RANSAC+LMedS on a flat seabed, 200 pairs, %d outliers: inliers kept %d/%d, outliers kept %d, uniqueness ratio %.1e\n",
              m.false_total, m.true_kept, m.true_total, m.false_kept, r->fit.unique_ratio);
  EXPECT_GE(m.true_kept, m.true_total * 90 / 100);
  EXPECT_LE(m.false_kept, m.false_total * 8 / 100);
}

TEST(RobustTwoView, BadInputGivesAClearStatus) {
  const TwoViewScene s = test::planar_scene(30, 0.5, 0.0, 23);
  RobustTwoViewConfig c;
  std::vector<std::uint8_t> mask(30);
  std::vector<double> scratch(30);
  auto h = [&](Span<const Vec2d> a, Span<const Vec2d> b, const RobustTwoViewConfig& cfg, std::size_t buf) {
    return robust_homography(a, b, cfg, Span<std::uint8_t>(mask.data(), buf), Span<double>(scratch.data(), buf)).status().code();
  };
  EXPECT_EQ(h(span_of(s.a), span_of(s.b), c, 29), StatusCode::kCapacityExceeded);
  EXPECT_EQ(h(span_of(s.a), Span<const Vec2d>(s.b.data(), 29), c, 30), StatusCode::kInvalidArgument);
  EXPECT_EQ(h(Span<const Vec2d>(s.a.data(), 10), Span<const Vec2d>(s.b.data(), 10), c, 30), StatusCode::kNotFound);
  RobustTwoViewConfig bad = c;
  bad.max_iterations = 0;
  EXPECT_EQ(h(span_of(s.a), span_of(s.b), bad, 30), StatusCode::kInvalidArgument);
  bad = c;
  bad.min_inliers = 3;  // below the minimal sample
  EXPECT_EQ(h(span_of(s.a), span_of(s.b), bad, 30), StatusCode::kInvalidArgument);
  std::vector<Vec2d> nan_b = s.b;
  nan_b[3].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(h(span_of(s.a), span_of(nan_b), c, 30), StatusCode::kInvalidArgument);
  // Every point on one line: every 4-point sample is degenerate.
  std::vector<Vec2d> la, lb;
  for (int i = 0; i < 30; ++i) {
    la.emplace_back(3.0 * i, 2.0 * i + 1.0);
    lb.emplace_back(3.0 * i + 5.0, 2.0 * i - 1.0);
  }
  EXPECT_EQ(h(span_of(la), span_of(lb), c, 30), StatusCode::kDegenerate);
  EXPECT_EQ(robust_fundamental(span_of(la), span_of(lb), c, Span<std::uint8_t>(mask.data(), 30), Span<double>(scratch.data(), 30))
                .status()
                .code(),
            StatusCode::kDegenerate);
}

}  // namespace
}  // namespace qnav::match
