// qnav's two-view estimators side by side with OpenCV on the SAME matches (issue 16, "measured, not
// asserted"): robust fundamental (RANSAC, LMedS, and the paper's both-accept rule) against
// cv::findFundamentalMat(FM_RANSAC / FM_LMEDS), robust homography against
// cv::findHomography(RANSAC), and the ratio-test matcher against cv::BFMatcher::knnMatch + ratio.
// Synthetic scenes (test/unit/nav/motion/two_view_scene.hpp: 200 matches, 0.5 px noise, known
// outliers at 30 % and 50 %, 4 seeds) give the truth; one real pair of the sparus snippet gives
// agreement only (no truth). OpenCV is a peer here, never a runtime dependency. Every case prints
// its numbers (one "peer ..." line each).
#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "nav/match/robust_two_view.hpp"
#include "test/reference/opencv_peer.hpp"
#include "test/unit/nav/motion/two_view_scene.hpp"

namespace qnav::peer {
namespace {

using match::RobustMethod;
using match::RobustTwoViewConfig;
using test::TwoViewScene;

constexpr double kThresholdPx = 2.0;   // both libraries: inlier bound (px), ~3 sigma of 0.5 px noise
constexpr int kMatches = 200;
constexpr double kNoisePx = 0.5;
const std::uint64_t kSeeds[] = {1, 2, 3, 4};

Span<const Vec2d> span_of(const std::vector<Vec2d>& v) { return Span<const Vec2d>(v.data(), v.size()); }

struct Overlap {
  double jaccard = 0.0;      // |A and B| / |A or B|
  double recall = 0.0;       // vs truth: true inliers kept / true inliers
  double precision = 0.0;    // vs truth: true inliers kept / kept
  int kept = 0;
};

double jaccard(const std::vector<std::uint8_t>& x, const std::vector<std::uint8_t>& y) {
  int both = 0, either = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    both += (x[i] != 0 && y[i] != 0);
    either += (x[i] != 0 || y[i] != 0);
  }
  return either == 0 ? 1.0 : static_cast<double>(both) / either;
}

Overlap vs_truth(const std::vector<std::uint8_t>& mask, const std::vector<std::uint8_t>& truth) {
  Overlap o;
  int tp = 0, t = 0;
  for (std::size_t i = 0; i < mask.size(); ++i) {
    o.kept += mask[i] != 0;
    t += truth[i] != 0;
    tp += (mask[i] != 0 && truth[i] != 0);
  }
  o.recall = t == 0 ? 1.0 : static_cast<double>(tp) / t;
  o.precision = o.kept == 0 ? 0.0 : static_cast<double>(tp) / o.kept;
  return o;
}

std::vector<std::uint8_t> cv_mask(const cv::Mat& m, std::size_t n) {
  std::vector<std::uint8_t> out(n, 0);
  if (m.total() != n) return out;
  for (std::size_t i = 0; i < n; ++i) out[i] = m.data[i] != 0 ? 1 : 0;
  return out;
}

// RMS symmetric epipolar distance (px) of the noise-free true correspondences under F:
// sqrt(mean(d(b, F a)^2 + d(a, F^T b)^2) / 2).
double epipolar_rms_px(const Mat3d& F, const TwoViewScene& s) {
  double sse = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < s.a.size(); ++i) {
    if (s.inlier[i] == 0) continue;
    const Vec3d a(s.a_true[i].x(), s.a_true[i].y(), 1.0), b(s.b_true[i].x(), s.b_true[i].y(), 1.0);
    const Vec3d lb = F * a, la = F.transpose() * b;
    const double e = b.dot(F * a);
    const double db2 = e * e / std::max(1e-300, lb.head<2>().squaredNorm());
    const double da2 = e * e / std::max(1e-300, la.head<2>().squaredNorm());
    sse += 0.5 * (db2 + da2);
    ++n;
  }
  return n == 0 ? 0.0 : std::sqrt(sse / n);
}

RobustTwoViewConfig qnav_config(RobustMethod m) {
  RobustTwoViewConfig c;
  c.method = m;
  c.max_iterations = 2000;
  c.inlier_threshold_px = kThresholdPx;
  c.confidence = 0.999;
  return c;
}

struct QnavF {
  bool ok = false;
  Mat3d F = Mat3d::Zero();
  std::vector<std::uint8_t> mask;
};

QnavF qnav_fundamental(const std::vector<Vec2d>& a, const std::vector<Vec2d>& b, RobustMethod m) {
  QnavF r;
  r.mask.assign(a.size(), 0);
  std::vector<double> scratch(a.size());
  Result<match::RobustFundamental> f = match::robust_fundamental(span_of(a), span_of(b), qnav_config(m),
                                                                 Span<std::uint8_t>(r.mask.data(), r.mask.size()),
                                                                 Span<double>(scratch.data(), scratch.size()));
  r.ok = f.is_ok();
  if (r.ok) r.F = f->fit.F;
  return r;
}

QnavF qnav_fundamental_both(const std::vector<Vec2d>& a, const std::vector<Vec2d>& b) {
  QnavF r;
  r.mask.assign(a.size(), 0);
  std::vector<std::uint8_t> m2(a.size());
  std::vector<double> scratch(a.size());
  Result<match::FundamentalConsensus> f = match::robust_fundamental_both(
      span_of(a), span_of(b), qnav_config(RobustMethod::kRansac), qnav_config(RobustMethod::kLmeds),
      Span<std::uint8_t>(r.mask.data(), r.mask.size()), Span<std::uint8_t>(m2.data(), m2.size()),
      Span<double>(scratch.data(), scratch.size()));
  r.ok = f.is_ok();
  if (r.ok) r.F = f->fit.F;
  return r;
}

struct CvF {
  bool ok = false;
  Mat3d F = Mat3d::Zero();            // as returned (OpenCV 4: the best minimal 7-point model, no refit)
  std::vector<std::uint8_t> mask;     // as returned (that model's inliers)
  Mat3d F_refit = Mat3d::Zero();      // FM_8POINT on mask (what a user adds)
  std::vector<std::uint8_t> remask;   // F_refit's inliers under OpenCV's own rule
};

// OpenCV's fundamental inlier rule (modules/calib3d/src/fundam.cpp, FMEstimatorCallback):
// max(d(b, F a), d(a, F^T b)) <= threshold.
std::vector<std::uint8_t> cv_rule_mask(const Mat3d& F, const std::vector<Vec2d>& a, const std::vector<Vec2d>& b) {
  std::vector<std::uint8_t> m(a.size(), 0);
  for (std::size_t i = 0; i < a.size(); ++i) {
    const Vec3d pa(a[i].x(), a[i].y(), 1.0), pb(b[i].x(), b[i].y(), 1.0);
    const Vec3d lb = F * pa, la = F.transpose() * pb;
    const double e = pb.dot(lb);
    const double d2 = std::max(e * e / std::max(1e-300, lb.head<2>().squaredNorm()), e * e / std::max(1e-300, la.head<2>().squaredNorm()));
    m[i] = d2 <= kThresholdPx * kThresholdPx ? 1 : 0;
  }
  return m;
}

CvF cv_fundamental(const std::vector<Vec2d>& a, const std::vector<Vec2d>& b, int method) {
  CvF r;
  cv::Mat mask;
  cv::setRNGSeed(0x51A7);
  const cv::Mat F = cv::findFundamentalMat(to_cv(a), to_cv(b), method, kThresholdPx, 0.999, 2000, mask);
  r.ok = F.rows == 3 && F.cols == 3;
  r.F = from_cv(F);
  if (r.ok) r.F /= r.F.norm();
  r.mask = cv_mask(mask, a.size());
  if (r.ok) {
    std::vector<Vec2d> ia, ib;
    for (std::size_t i = 0; i < a.size(); ++i)
      if (r.mask[i]) {
        ia.push_back(a[i]);
        ib.push_back(b[i]);
      }
    if (ia.size() >= 8) {
      const cv::Mat F8 = cv::findFundamentalMat(to_cv(ia), to_cv(ib), cv::FM_8POINT);
      if (F8.rows == 3 && F8.cols == 3) {
        r.F_refit = from_cv(F8);
        r.F_refit /= r.F_refit.norm();
        r.remask = cv_rule_mask(r.F_refit, a, b);
      }
    }
  }
  if (r.remask.empty()) r.remask.assign(a.size(), 0);
  return r;
}

// |x and y| / |y|: the share of y's inliers that x keeps too.
double containment(const std::vector<std::uint8_t>& x, const std::vector<std::uint8_t>& y) {
  int both = 0, ny = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    both += (x[i] != 0 && y[i] != 0);
    ny += y[i] != 0;
  }
  return ny == 0 ? 1.0 : static_cast<double>(both) / ny;
}

// ---- Fundamental: RANSAC / LMedS / both-accept vs OpenCV on general 3D scenes -----------------

class OpenCvPeerFundamental : public ::testing::TestWithParam<double> {};

// OpenCV 4's FM_RANSAC / FM_LMEDS return the best minimal (7-point) model and its inliers, with no
// refit; qnav refits on the inliers and re-marks them. So the raw masks differ by the true inliers the
// minimal model misses. Asserted: qnav keeps what OpenCV keeps (containment >= 0.95), and qnav's mask
// and OpenCV's after the one step a user adds (FM_8POINT on its inliers, re-marked by OpenCV's own
// rule) overlap with Jaccard >= 0.9 (where that OpenCV mask recovers the truth); truth: qnav recall >= 0.95, precision >= 0.9, true
// correspondences within 1 px RMS of qnav's epipolar lines.
TEST_P(OpenCvPeerFundamental, SameMatchesGiveOverlappingInliersAndAccurateF) {
  const double frac = GetParam();
  // LMedS breaks down at 50 % outliers (the median pair is then an outlier): qnav's LMedS then
  // reports kNotFound (or succeeds with a correct mask); OpenCV's returns a model regardless. At 50 %
  // the LMedS / both-accept agreement is printed, and only "no wrong answer" is asserted for qnav.
  const bool lmeds_asserted = frac < 0.45;
  for (const std::uint64_t seed : kSeeds) {
    const TwoViewScene s = test::general_scene(kMatches, kNoisePx, frac, seed);
    const QnavF qr = qnav_fundamental(s.a, s.b, RobustMethod::kRansac);
    const QnavF ql = qnav_fundamental(s.a, s.b, RobustMethod::kLmeds);
    const QnavF qb = qnav_fundamental_both(s.a, s.b);
    const CvF cr = cv_fundamental(s.a, s.b, cv::FM_RANSAC);
    const CvF cl = cv_fundamental(s.a, s.b, cv::FM_LMEDS);
    // OpenCV's both-accept: the paper's rule applied to OpenCV's two (re-marked) masks.
    std::vector<std::uint8_t> cb(s.a.size()), cb_raw(s.a.size());
    for (std::size_t i = 0; i < cb.size(); ++i) {
      cb[i] = cr.remask[i] && cl.remask[i];
      cb_raw[i] = cr.mask[i] && cl.mask[i];
    }
    const Overlap oqr = vs_truth(qr.mask, s.inlier), ocr = vs_truth(cr.mask, s.inlier), ocr2 = vs_truth(cr.remask, s.inlier);
    const Overlap oql = vs_truth(ql.mask, s.inlier), ocl = vs_truth(cl.mask, s.inlier), ocl2 = vs_truth(cl.remask, s.inlier);
    const Overlap oqb = vs_truth(qb.mask, s.inlier), ocb = vs_truth(cb, s.inlier);
    const double eqr = epipolar_rms_px(qr.F, s), ecr = epipolar_rms_px(cr.F, s), ecr2 = epipolar_rms_px(cr.F_refit, s);
    const double eql = epipolar_rms_px(ql.F, s), ecl = epipolar_rms_px(cl.F, s), ecl2 = epipolar_rms_px(cl.F_refit, s);
    const double eqb = epipolar_rms_px(qb.F, s);
    std::printf("peer F outliers %2.0f%% seed %llu true %u/%d  (recall/precision vs truth; epi = RMS symmetric epipolar distance of the true points, px)\n",
                100.0 * frac, static_cast<unsigned long long>(seed), s.inliers, kMatches);
    std::printf("  RANSAC qnav %-4s kept %3d rec %.3f prec %.3f epi %.3f | opencv raw kept %3d rec %.3f prec %.3f epi %.3f | +refit kept %3d rec %.3f prec %.3f epi %.3f | jaccard raw %.3f refit %.3f contain %.3f\n",
                qr.ok ? "ok" : "FAIL", oqr.kept, oqr.recall, oqr.precision, eqr, ocr.kept, ocr.recall, ocr.precision, ecr, ocr2.kept,
                ocr2.recall, ocr2.precision, ecr2, jaccard(qr.mask, cr.mask), jaccard(qr.mask, cr.remask), containment(qr.mask, cr.mask));
    std::printf("  LMedS  qnav %-4s kept %3d rec %.3f prec %.3f epi %.3f | opencv raw kept %3d rec %.3f prec %.3f epi %.3f | +refit kept %3d rec %.3f prec %.3f epi %.3f | jaccard raw %.3f refit %.3f contain %.3f\n",
                ql.ok ? "ok" : "FAIL", oql.kept, oql.recall, oql.precision, eql, ocl.kept, ocl.recall, ocl.precision, ecl, ocl2.kept,
                ocl2.recall, ocl2.precision, ecl2, jaccard(ql.mask, cl.mask), jaccard(ql.mask, cl.remask), containment(ql.mask, cl.mask));
    std::printf("  both   qnav %-4s kept %3d rec %.3f prec %.3f epi %.3f | opencv AND of refit masks kept %3d rec %.3f prec %.3f | jaccard raw %.3f refit %.3f\n",
                qb.ok ? "ok" : "FAIL", oqb.kept, oqb.recall, oqb.precision, eqb, ocb.kept, ocb.recall, ocb.precision,
                jaccard(qb.mask, cb_raw), jaccard(qb.mask, cb));

    SCOPED_TRACE(::testing::Message() << "outliers " << frac << " seed " << seed);
    ASSERT_TRUE(qr.ok);
    ASSERT_TRUE(cr.ok);
    EXPECT_GE(containment(qr.mask, cr.mask), 0.95);
    // Where OpenCV (+ refit) recovers the truth, the two masks agree; where its minimal model was too
    // poor for one refit to recover (measured: 50 %, seed 4, recall 0.80), qnav must not do worse.
    if (ocr2.recall >= 0.95) {
      EXPECT_GE(jaccard(qr.mask, cr.remask), 0.9);
    } else {
      EXPECT_GE(oqr.recall, ocr2.recall);
    }
    EXPECT_GE(oqr.recall, 0.95);
    // Precision: an outlier whose random point falls within 2 px of its epipolar line is consistent
    // with F, and both libraries keep it; so a bound, not 1.
    EXPECT_GE(oqr.precision, 0.9);
    EXPECT_GE(ocr.precision, 0.9);
    EXPECT_LT(eqr, 1.0);
    if (lmeds_asserted) {
      ASSERT_TRUE(ql.ok);
      ASSERT_TRUE(cl.ok);
      ASSERT_TRUE(qb.ok);
      EXPECT_GE(containment(ql.mask, cl.mask), 0.95);
      EXPECT_GE(jaccard(ql.mask, cl.remask), 0.9);
      EXPECT_GE(jaccard(qb.mask, cb), 0.9);
      EXPECT_GE(oql.recall, 0.95);
      EXPECT_GE(oqb.recall, 0.95);
      EXPECT_GE(oql.precision, 0.9);
      EXPECT_GE(ocl.precision, 0.9);
      EXPECT_GE(oqb.precision, 0.9);
      EXPECT_LT(eql, 1.0);
      EXPECT_LT(eqb, 1.0);
    } else {
      if (ql.ok) {
        EXPECT_GE(oql.precision, 0.9);
      }
      if (qb.ok) {
        EXPECT_GE(oqb.precision, 0.9);
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Outliers, OpenCvPeerFundamental, ::testing::Values(0.3, 0.5),
                         [](const ::testing::TestParamInfo<double>& i) { return "pct" + std::to_string(static_cast<int>(i.param * 100 + 0.5)); });

// ---- Homography: robust_homography vs findHomography(RANSAC) on seabed scenes ----------------

struct QnavH {
  bool ok = false;
  Mat3d H = Mat3d::Identity();
  std::vector<std::uint8_t> mask;
};

QnavH qnav_homography(const std::vector<Vec2d>& a, const std::vector<Vec2d>& b) {
  QnavH r;
  r.mask.assign(a.size(), 0);
  std::vector<double> scratch(a.size());
  Result<match::RobustHomography> h = match::robust_homography(span_of(a), span_of(b), qnav_config(RobustMethod::kRansac),
                                                               Span<std::uint8_t>(r.mask.data(), r.mask.size()),
                                                               Span<double>(scratch.data(), scratch.size()));
  r.ok = h.is_ok();
  if (r.ok) r.H = h->fit.H;
  return r;
}

QnavH cv_homography(const std::vector<Vec2d>& a, const std::vector<Vec2d>& b) {
  QnavH r;
  cv::Mat mask;
  cv::setRNGSeed(0x51A7);
  const cv::Mat H = cv::findHomography(to_cv(a), to_cv(b), cv::RANSAC, kThresholdPx, mask, 2000, 0.999);
  r.ok = H.rows == 3 && H.cols == 3;
  if (r.ok) r.H = from_cv(H);
  r.mask = cv_mask(mask, a.size());
  return r;
}

// OpenCV's homography inlier rule (forward reprojection |pi(H a) - b| <= threshold) applied to the
// H it returns (LM-refined on its RANSAC inliers; the returned mask is not re-marked).
std::vector<std::uint8_t> cv_h_rule_mask(const Mat3d& H, const std::vector<Vec2d>& a, const std::vector<Vec2d>& b) {
  std::vector<std::uint8_t> m(a.size(), 0);
  for (std::size_t i = 0; i < a.size(); ++i) {
    Vec2d p;
    m[i] = motion::apply_homography(H, a[i], p) && (p - b[i]).squaredNorm() <= kThresholdPx * kThresholdPx ? 1 : 0;
  }
  return m;
}

class OpenCvPeerHomography : public ::testing::TestWithParam<double> {};

TEST_P(OpenCvPeerHomography, SameMatchesGiveOverlappingInliersAndComparableTransferError) {
  const double frac = GetParam();
  for (const std::uint64_t seed : kSeeds) {
    const TwoViewScene s = test::planar_scene(kMatches, kNoisePx, frac, seed);
    const QnavH q = qnav_homography(s.a, s.b);
    const QnavH c = cv_homography(s.a, s.b);
    const std::vector<std::uint8_t> c_remask = cv_h_rule_mask(c.H, s.a, s.b);
    const Overlap oq = vs_truth(q.mask, s.inlier), oc = vs_truth(c.mask, s.inlier), oc2 = vs_truth(c_remask, s.inlier);
    const double j = jaccard(q.mask, c.mask), j2 = jaccard(q.mask, c_remask), cont = containment(q.mask, c.mask);
    const double eq = test::homography_grid_error_px(q.H, s.H), ec = test::homography_grid_error_px(c.H, s.H);
    std::printf("peer H outliers %2.0f%% seed %llu true %u/%d\n", 100.0 * frac, static_cast<unsigned long long>(seed), s.inliers,
                kMatches);
    std::printf("  qnav %-4s kept %3d rec %.3f prec %.3f grid_err %.3f px | opencv %-4s kept %3d rec %.3f prec %.3f grid_err %.3f px | re-marked kept %3d rec %.3f prec %.3f | jaccard raw %.3f re-marked %.3f contain %.3f\n",
                q.ok ? "ok" : "FAIL", oq.kept, oq.recall, oq.precision, eq, c.ok ? "ok" : "FAIL", oc.kept, oc.recall, oc.precision, ec,
                oc2.kept, oc2.recall, oc2.precision, j, j2, cont);
    SCOPED_TRACE(::testing::Message() << "outliers " << frac << " seed " << seed);
    ASSERT_TRUE(q.ok);
    ASSERT_TRUE(c.ok);
    // OpenCV's mask is its best minimal hypothesis's inliers (it misses up to 16 % of the true ones
    // here); qnav re-marks with the refined H. Asserted: qnav keeps what OpenCV keeps, and agrees
    // with OpenCV's mask re-marked under OpenCV's returned H.
    EXPECT_GE(cont, 0.95);
    EXPECT_GE(j2, 0.9);
    EXPECT_GE(oq.recall, 0.95);
    EXPECT_GE(oq.precision, 0.95);
    EXPECT_GE(oc.precision, 0.95);
    // Transfer error of H vs the true H over a 9 x 9 grid of the image: qnav's not worse than
    // OpenCV's by more than 25 % + 0.1 px (both are ~0.1-0.3 px with 0.5 px noise).
    EXPECT_LE(eq, 1.25 * ec + 0.1);
    EXPECT_LT(eq, 1.0);
  }
}

INSTANTIATE_TEST_SUITE_P(Outliers, OpenCvPeerHomography, ::testing::Values(0.3, 0.5),
                         [](const ::testing::TestParamInfo<double>& i) { return "pct" + std::to_string(static_cast<int>(i.param * 100 + 0.5)); });

// ---- Real pair (sparus snippet frames 0 -> 1): matching and fits agree; no truth ----------------

const RealPair& real_pair() {
  static const RealPair p = load_real_pair(QNAV_SHARED_DIR);
  return p;
}

// Ratio test with OpenCV's brute-force L2 matcher on the same descriptor floats.
std::vector<std::pair<int, int>> cv_ratio_matches(const RealPair& p, float ratio) {
  cv::BFMatcher bf(cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> knn;
  bf.knnMatch(descriptor_mat(p.da), descriptor_mat(p.db), knn, 2);
  std::vector<std::pair<int, int>> out;
  for (const auto& k : knn)
    if (k.size() == 2 && k[0].distance < ratio * k[1].distance) out.emplace_back(k[0].queryIdx, k[0].trainIdx);
  return out;
}

TEST(OpenCvPeerReal, RatioMatchingEqualsBruteForceKnnWithRatio) {
  const RealPair& p = real_pair();
  ASSERT_TRUE(p.ok) << p.why;
  const std::vector<std::pair<int, int>> c = cv_ratio_matches(p, real_ratio_config().max_ratio);
  std::vector<std::pair<int, int>> q;
  for (const match::DescriptorMatch& m : p.matches) q.emplace_back(m.query, m.train);
  std::vector<std::pair<int, int>> common;
  std::set_intersection(q.begin(), q.end(), c.begin(), c.end(), std::back_inserter(common));
  const double j = static_cast<double>(common.size()) / static_cast<double>(q.size() + c.size() - common.size());
  std::printf("peer match real frames 0->1: descriptors %zu x %zu, qnav %zu matches, opencv %zu, common %zu, jaccard %.4f\n",
              p.da.size(), p.db.size(), q.size(), c.size(), common.size(), j);
  // Same floats, same rule; only the float summation order differs (a ratio within rounding of 0.8
  // could flip).
  EXPECT_GE(j, 0.99);
}

TEST(OpenCvPeerReal, FundamentalAndHomographyAgreeOnTheSameMatches) {
  const RealPair& p = real_pair();
  ASSERT_TRUE(p.ok) << p.why;
  const QnavH qh = qnav_homography(p.a, p.b);
  const QnavH ch = cv_homography(p.a, p.b);
  const QnavF qr = qnav_fundamental(p.a, p.b, RobustMethod::kRansac);
  const QnavF ql = qnav_fundamental(p.a, p.b, RobustMethod::kLmeds);
  const QnavF qb = qnav_fundamental_both(p.a, p.b);
  const CvF cr = cv_fundamental(p.a, p.b, cv::FM_RANSAC);
  const CvF cl = cv_fundamental(p.a, p.b, cv::FM_LMEDS);
  std::vector<std::uint8_t> cb(p.a.size());
  for (std::size_t i = 0; i < cb.size(); ++i) cb[i] = cr.mask[i] && cl.mask[i];
  // H vs H over the image grid (the grid of the 320 x 240 helper scaled to 384 x 288 is close enough:
  // it covers the middle 83 % of the frame).
  const double h_diff = test::homography_grid_error_px(qh.H, ch.H);
  auto count = [](const std::vector<std::uint8_t>& m) { return static_cast<int>(std::count(m.begin(), m.end(), 1)); };
  std::printf("peer real frames 0->1 (%zu matches, undistorted):\n", p.a.size());
  std::printf("  H      qnav %s kept %3d | opencv %s kept %3d | jaccard %.3f | H difference on the grid %.3f px\n", qh.ok ? "ok" : "FAIL",
              count(qh.mask), ch.ok ? "ok" : "FAIL", count(ch.mask), jaccard(qh.mask, ch.mask), h_diff);
  std::printf("  RANSAC qnav %s kept %3d | opencv %s kept %3d | jaccard %.3f\n", qr.ok ? "ok" : "FAIL", count(qr.mask),
              cr.ok ? "ok" : "FAIL", count(cr.mask), jaccard(qr.mask, cr.mask));
  std::printf("  LMedS  qnav %s kept %3d | opencv %s kept %3d | jaccard %.3f\n", ql.ok ? "ok" : "FAIL", count(ql.mask),
              cl.ok ? "ok" : "FAIL", count(cl.mask), jaccard(ql.mask, cl.mask));
  std::printf("  both   qnav %s kept %3d | opencv AND  kept %3d | jaccard %.3f\n", qb.ok ? "ok" : "FAIL", count(qb.mask), count(cb),
              jaccard(qb.mask, cb));
  ASSERT_TRUE(qh.ok);
  ASSERT_TRUE(ch.ok);
  EXPECT_GE(jaccard(qh.mask, ch.mask), 0.9);
  EXPECT_LT(h_diff, 1.0);
  ASSERT_TRUE(qr.ok);
  ASSERT_TRUE(cr.ok);
  EXPECT_GE(jaccard(qr.mask, cr.mask), 0.9);
}

}  // namespace
}  // namespace qnav::peer
