// qnav's two-view stages of the downward-camera mapping next to OpenCV, on the same input (see
// CMakeLists.txt). Arguments: scene 0 = synthetic general / planar scene, 200 matches, 30 %
// outliers; 1 = the same at 50 %; 2 = sparus frames 0 -> 1 (207 real ratio matches, undistorted).
// Both sides use threshold 2 px, confidence 0.999, at most 2000 iterations; OpenCV's RNG is reseeded
// every iteration, qnav's seed is fixed, so every iteration repeats the same work.
#include <benchmark/benchmark.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include <cstdio>
#include <cstdlib>
#include <vector>

#include "firmware/tools/shared_dir.hpp"
#include "nav/match/robust_two_view.hpp"
#include "test/reference/opencv_peer.hpp"
#include "test/unit/nav/motion/two_view_scene.hpp"

namespace {

using namespace qnav;
using match::RobustMethod;

const peer::RealPair& real() {
  static const peer::RealPair p = peer::load_real_pair(tools::shared_dir());
  if (!p.ok) {
    std::fprintf(stderr, "bench_mapping_opencv: %s\n", p.why.c_str());
    std::exit(1);
  }
  return p;
}

struct Points {
  std::vector<Vec2d> a, b;
};

// planar: the seabed scene (for H), else the general 3D scene (for F); scene 2 = the real pair.
const Points& points(int scene, bool planar) {
  static Points cache[3][2];
  Points& p = cache[scene][planar ? 1 : 0];
  if (p.a.empty()) {
    if (scene == 2) {
      p.a = real().a;
      p.b = real().b;
    } else {
      const double frac = scene == 0 ? 0.3 : 0.5;
      const test::TwoViewScene s = planar ? test::planar_scene(200, 0.5, frac, 1) : test::general_scene(200, 0.5, frac, 1);
      p.a = s.a;
      p.b = s.b;
    }
  }
  return p;
}

void label(benchmark::State& st, int scene) {
  st.SetLabel(scene == 0 ? "synthetic 30% outliers" : scene == 1 ? "synthetic 50% outliers" : "sparus 0->1");
}

match::RobustTwoViewConfig config(RobustMethod m) {
  match::RobustTwoViewConfig c;
  c.method = m;
  c.max_iterations = 2000;
  c.inlier_threshold_px = 2.0;
  c.confidence = 0.999;
  return c;
}

Span<const Vec2d> span_of(const std::vector<Vec2d>& v) { return Span<const Vec2d>(v.data(), v.size()); }

// ---- Ratio-test matching on the same descriptors (sparus frames 0, 1: ~480 x ~480) ----
void BM_RatioMatch_qnav(benchmark::State& st) {
  const peer::RealPair& p = real();
  const match::RatioMatchConfig rc = peer::real_ratio_config();
  ArenaStorage arena(match::RatioMatcher::arena_bytes(rc));
  match::RatioMatcher m;
  m.init(rc, arena).ignore();
  std::vector<match::DescriptorMatch> storage(rc.max_query);
  BoundedVector<match::DescriptorMatch> out(Span<match::DescriptorMatch>(storage.data(), storage.size()));
  for (auto _ : st) {
    m.match(Span<const vision::OrientedDescriptor>(p.da.data(), p.da.size()),
            Span<const vision::OrientedDescriptor>(p.db.data(), p.db.size()), out)
        .ignore();
    benchmark::DoNotOptimize(out.data());
  }
  st.counters["matches"] = static_cast<double>(out.size());
  st.SetLabel(std::to_string(p.da.size()) + "x" + std::to_string(p.db.size()) + " descriptors");
}
BENCHMARK(BM_RatioMatch_qnav)->Unit(benchmark::kMillisecond);

void BM_RatioMatch_opencv_bf_knn(benchmark::State& st) {
  const peer::RealPair& p = real();
  const cv::Mat qa = peer::descriptor_mat(p.da), tb = peer::descriptor_mat(p.db);
  cv::BFMatcher bf(cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> knn;
  std::vector<cv::DMatch> good;
  for (auto _ : st) {
    knn.clear();  // knnMatch appends to a non-empty vector
    bf.knnMatch(qa, tb, knn, 2);
    good.clear();
    for (const auto& k : knn)
      if (k.size() == 2 && k[0].distance < 0.8f * k[1].distance) good.push_back(k[0]);
    benchmark::DoNotOptimize(good.data());
  }
  st.counters["matches"] = static_cast<double>(good.size());
  st.SetLabel(std::to_string(p.da.size()) + "x" + std::to_string(p.db.size()) + " descriptors");
}
BENCHMARK(BM_RatioMatch_opencv_bf_knn)->Unit(benchmark::kMillisecond);

// ---- Fundamental ----
void BM_Fundamental_qnav(benchmark::State& st, RobustMethod m) {
  const int scene = static_cast<int>(st.range(0));
  const Points& p = points(scene, false);
  std::vector<std::uint8_t> mask(p.a.size());
  std::vector<double> scratch(p.a.size());
  std::uint32_t inl = 0, it = 0;
  for (auto _ : st) {
    Result<match::RobustFundamental> r = match::robust_fundamental(span_of(p.a), span_of(p.b), config(m),
                                                                   Span<std::uint8_t>(mask.data(), mask.size()),
                                                                   Span<double>(scratch.data(), scratch.size()));
    if (r.is_ok()) {
      inl = r->inliers;
      it = r->iterations;
    }
    benchmark::DoNotOptimize(mask.data());
  }
  st.counters["inliers"] = inl;
  st.counters["hypotheses"] = it;
  label(st, scene);
}
void BM_FundamentalRansac_qnav(benchmark::State& st) { BM_Fundamental_qnav(st, RobustMethod::kRansac); }
void BM_FundamentalLmeds_qnav(benchmark::State& st) { BM_Fundamental_qnav(st, RobustMethod::kLmeds); }
BENCHMARK(BM_FundamentalRansac_qnav)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FundamentalLmeds_qnav)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

void BM_FundamentalBoth_qnav(benchmark::State& st) {
  const int scene = static_cast<int>(st.range(0));
  const Points& p = points(scene, false);
  std::vector<std::uint8_t> mask(p.a.size()), m2(p.a.size());
  std::vector<double> scratch(p.a.size());
  std::uint32_t inl = 0;
  for (auto _ : st) {
    Result<match::FundamentalConsensus> r = match::robust_fundamental_both(
        span_of(p.a), span_of(p.b), config(RobustMethod::kRansac), config(RobustMethod::kLmeds),
        Span<std::uint8_t>(mask.data(), mask.size()), Span<std::uint8_t>(m2.data(), m2.size()),
        Span<double>(scratch.data(), scratch.size()));
    if (r.is_ok()) inl = r->inliers;
    benchmark::DoNotOptimize(mask.data());
  }
  st.counters["inliers"] = inl;
  label(st, scene);
}
BENCHMARK(BM_FundamentalBoth_qnav)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

void BM_Fundamental_opencv(benchmark::State& st, int method) {
  const int scene = static_cast<int>(st.range(0));
  const Points& p = points(scene, false);
  const std::vector<cv::Point2f> a = peer::to_cv(p.a), b = peer::to_cv(p.b);
  cv::Mat mask, F;
  for (auto _ : st) {
    cv::setRNGSeed(0x51A7);
    F = cv::findFundamentalMat(a, b, method, 2.0, 0.999, 2000, mask);
    benchmark::DoNotOptimize(F.data);
  }
  st.counters["inliers"] = mask.empty() ? 0.0 : cv::countNonZero(mask);
  label(st, scene);
}
void BM_FundamentalRansac_opencv(benchmark::State& st) { BM_Fundamental_opencv(st, cv::FM_RANSAC); }
void BM_FundamentalLmeds_opencv(benchmark::State& st) { BM_Fundamental_opencv(st, cv::FM_LMEDS); }
BENCHMARK(BM_FundamentalRansac_opencv)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FundamentalLmeds_opencv)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

// ---- Homography ----
void BM_Homography_qnav(benchmark::State& st) {
  const int scene = static_cast<int>(st.range(0));
  const Points& p = points(scene, true);
  std::vector<std::uint8_t> mask(p.a.size());
  std::vector<double> scratch(p.a.size());
  std::uint32_t inl = 0, it = 0;
  for (auto _ : st) {
    Result<match::RobustHomography> r = match::robust_homography(span_of(p.a), span_of(p.b), config(RobustMethod::kRansac),
                                                                 Span<std::uint8_t>(mask.data(), mask.size()),
                                                                 Span<double>(scratch.data(), scratch.size()));
    if (r.is_ok()) {
      inl = r->inliers;
      it = r->iterations;
    }
    benchmark::DoNotOptimize(mask.data());
  }
  st.counters["inliers"] = inl;
  st.counters["hypotheses"] = it;
  label(st, scene);
}
BENCHMARK(BM_Homography_qnav)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

void BM_Homography_opencv(benchmark::State& st) {
  const int scene = static_cast<int>(st.range(0));
  const Points& p = points(scene, true);
  const std::vector<cv::Point2f> a = peer::to_cv(p.a), b = peer::to_cv(p.b);
  cv::Mat mask, H;
  for (auto _ : st) {
    cv::setRNGSeed(0x51A7);
    H = cv::findHomography(a, b, cv::RANSAC, 2.0, mask, 2000, 0.999);
    benchmark::DoNotOptimize(H.data);
  }
  st.counters["inliers"] = mask.empty() ? 0.0 : cv::countNonZero(mask);
  label(st, scene);
}
BENCHMARK(BM_Homography_opencv)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

}  // namespace

int main(int argc, char** argv) {
  cv::setNumThreads(0);  // single thread, like nav/
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
