// Benchmarks of the nav/vision stages on real images at 320x256 (Middlebury Aloe at 1/4, cropped)
// and 1242x375 (KITTI frame 0), each next to its OpenCV equivalent (single thread). Size argument:
// 0 = 320x256, 1 = 1242x375. The ratio qnav/OpenCV per stage is computed by
// scripts/vision-bench-ratios.py from this program's JSON output.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "firmware/tools/image_reader.hpp"
#include "nav/vision/degrade.hpp"
#include "nav/vision/descriptor.hpp"
#include "nav/vision/downsample.hpp"
#include "nav/vision/harris.hpp"
#include "nav/vision/rectify.hpp"
#include "nav/vision/stereo.hpp"
#include "firmware/tools/shared_dir.hpp"

#ifdef QNAV_HAVE_OPENCV
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#endif

namespace {

using namespace qnav;
using namespace qnav::vision;

const std::string kStereo = qnav::tools::shared_dir() + "/data/stereo/";

struct Pair {
  ImageU8 left, right;
  int max_disparity = 64;
};

ImageU8 copy_of(ConstImageViewU8 v) {
  ImageU8 img = ImageU8::allocate(v.width(), v.height()).value();
  copy_pixels(v, img.view()).ignore();
  return img;
}

// 0: Aloe at 1/4 cropped to 320x256 (disparities up to ~53); 1: KITTI frame 0 (1242x375).
const Pair& pair(int which) {
  static std::unique_ptr<Pair> cache[2];
  if (!cache[which]) {
    auto p = std::make_unique<Pair>();
    if (which == 0) {
      for (int side = 0; side < 2; ++side) {
        Result<ImageU8> full = tools::read_image_gray8((kStereo + (side ? "middlebury_aloe_opencv/aloeR.jpg" : "middlebury_aloe_opencv/aloeL.jpg")).c_str());
        if (!full.is_ok()) {
          std::fprintf(stderr, "bench_vision: cannot read the Aloe images under %s\n", kStereo.c_str());
          std::exit(1);
        }
        ImageU8 q = ImageU8::allocate(full->width() / 4, full->height() / 4).value();
        downsample(full->view(), 4, q.view()).ignore();
        (side ? p->right : p->left) = copy_of(q.view().sub(RectI{0, 0, 320, 256}).value());
      }
      p->max_disparity = 64;
    } else {
      for (int side = 0; side < 2; ++side) {
        Result<ImageU8> img = tools::read_image_gray8(
            (kStereo + "kitti_raw_2011_09_26_0013_city100/" + (side ? "right" : "left") + "/0000000000.png").c_str());
        if (!img.is_ok()) {
          std::fprintf(stderr, "bench_vision: cannot read the KITTI images under %s\n", kStereo.c_str());
          std::exit(1);
        }
        (side ? p->right : p->left) = std::move(img.value());
      }
      p->max_disparity = 128;
    }
    cache[which] = std::move(p);
  }
  return *cache[which];
}

void set_label(benchmark::State& st, const Pair& p) {
  st.SetLabel(std::to_string(p.left.width()) + "x" + std::to_string(p.left.height()));
}

struct Harris {
  explicit Harris(int w, int h, int cap = 500) : storage(static_cast<std::size_t>(cap)) {
    HarrisConfig c;
    c.max_width = w;
    c.max_height = h;
    c.max_corners = cap;
    arena = std::make_unique<ArenaStorage>(HarrisDetector::arena_bytes(c));
    det.init(c, *arena).ignore();
    out = BoundedVector<Corner>(Span<Corner>(storage.data(), storage.size()));
  }
  std::unique_ptr<ArenaStorage> arena;
  std::vector<Corner> storage;
  BoundedVector<Corner> out;
  HarrisDetector det;
};

// ---- Harris + NMS + top 500 ----
void BM_Harris_qnav(benchmark::State& st) {
  const Pair& p = pair(static_cast<int>(st.range(0)));
  Harris h(p.left.width(), p.left.height());
  for (auto _ : st) {
    h.det.detect(p.left.view(), h.out).ignore();
    benchmark::DoNotOptimize(h.out.data());
  }
  set_label(st, p);
  st.counters["corners"] = static_cast<double>(h.out.size());
}
BENCHMARK(BM_Harris_qnav)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

#ifdef QNAV_HAVE_OPENCV
cv::Mat as_mat(const ImageU8& img) {
  return cv::Mat(img.height(), img.width(), CV_8UC1, const_cast<std::uint8_t*>(img.data()));
}

// cornerHarris (block 3, Sobel 3, k 0.04) + 5x5 NMS by dilation + threshold + top 500 by response.
void BM_Harris_opencv(benchmark::State& st) {
  const Pair& p = pair(static_cast<int>(st.range(0)));
  const cv::Mat img = as_mat(p.left);
  cv::Mat R, D;
  const cv::Mat kernel = cv::Mat::ones(5, 5, CV_8U);
  struct C {
    float s;
    int x, y;
  };
  std::vector<C> cand;
  cand.reserve(static_cast<std::size_t>(img.rows * img.cols / 4));
  for (auto _ : st) {
    cv::cornerHarris(img, R, 3, 3, 0.04);
    cv::dilate(R, D, kernel);
    double maxv = 0;
    cv::minMaxLoc(R, nullptr, &maxv);
    const float thr = static_cast<float>(1e-5 * maxv);
    cand.clear();
    for (int y = 4; y < R.rows - 4; ++y) {
      const float* r = R.ptr<float>(y);
      const float* d = D.ptr<float>(y);
      for (int x = 4; x < R.cols - 4; ++x)
        if (r[x] > thr && r[x] >= d[x]) cand.push_back(C{r[x], x, y});
    }
    const std::size_t k = std::min<std::size_t>(500, cand.size());
    std::partial_sort(cand.begin(), cand.begin() + static_cast<std::ptrdiff_t>(k), cand.end(),
                      [](const C& a, const C& b) { return a.s > b.s; });
    benchmark::DoNotOptimize(cand.data());
  }
  set_label(st, p);
}
BENCHMARK(BM_Harris_opencv)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
#endif

// ---- Downsampling: 1280x1024 -> 320x256 (factor 4, the Mars case) and 1242x375 -> 621x187 ----
struct DownCase {
  ImageU8 src;
  int factor;
};
const DownCase& down_case(int which) {
  static std::unique_ptr<DownCase> cache[2];
  if (!cache[which]) {
    auto c = std::make_unique<DownCase>();
    if (which == 0) {
      ImageU8 full = tools::read_image_gray8((kStereo + "middlebury_aloe_opencv/aloeL.jpg").c_str()).value();
      c->src = copy_of(full.view().sub(RectI{0, 0, 1280, 1024}).value());
      c->factor = 4;
    } else {
      c->src = copy_of(pair(1).left.view());
      c->factor = 2;
    }
    cache[which] = std::move(c);
  }
  return *cache[which];
}

void BM_Downsample_qnav(benchmark::State& st) {
  const DownCase& c = down_case(static_cast<int>(st.range(0)));
  ImageU8 dst = ImageU8::allocate(c.src.width() / c.factor, c.src.height() / c.factor).value();
  for (auto _ : st) {
    downsample(c.src.view(), c.factor, dst.view()).ignore();
    benchmark::DoNotOptimize(dst.data());
  }
  st.SetLabel(std::to_string(c.src.width()) + "x" + std::to_string(c.src.height()) + " /" + std::to_string(c.factor));
}
BENCHMARK(BM_Downsample_qnav)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

#ifdef QNAV_HAVE_OPENCV
void BM_Downsample_opencv(benchmark::State& st) {
  const DownCase& c = down_case(static_cast<int>(st.range(0)));
  const cv::Mat src = as_mat(c.src);
  cv::Mat dst;
  for (auto _ : st) {
    cv::resize(src, dst, cv::Size(src.cols / c.factor, src.rows / c.factor), 0, 0, cv::INTER_AREA);
    benchmark::DoNotOptimize(dst.data);
  }
  st.SetLabel(std::to_string(c.src.width()) + "x" + std::to_string(c.src.height()) + " /" + std::to_string(c.factor));
}
BENCHMARK(BM_Downsample_opencv)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);
#endif

// ---- Remap (undistortion table, EuRoC-like distortion scaled to the image) ----
PinholeRadTan camera_for(int w, int h) {
  PinholeRadTan c;
  c.fx = c.fy = 0.61 * w;
  c.cx = 0.5 * (w - 1);
  c.cy = 0.5 * (h - 1);
  c.k1 = -0.28;
  c.k2 = 0.074;
  c.p1 = 0.0002;
  c.p2 = 0.00002;
  c.width = w;
  c.height = h;
  return c;
}

void BM_Remap_qnav(benchmark::State& st) {
  const Pair& p = pair(static_cast<int>(st.range(0)));
  const int w = p.left.width(), h = p.left.height();
  RemapConfig rc;
  rc.max_width = w;
  rc.max_height = h;
  ArenaStorage arena(RemapTable::arena_bytes(rc));
  RemapTable t;
  t.init(rc, arena).ignore();
  t.build_undistort(camera_for(w, h), FlatPortRefraction{}).ignore();
  ImageU8 dst = ImageU8::allocate(w, h).value();
  for (auto _ : st) {
    t.apply(p.left.view(), dst.view()).ignore();
    benchmark::DoNotOptimize(dst.data());
  }
  set_label(st, p);
}
BENCHMARK(BM_Remap_qnav)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

#ifdef QNAV_HAVE_OPENCV
void remap_opencv(benchmark::State& st, int map_type) {
  const Pair& p = pair(static_cast<int>(st.range(0)));
  const int w = p.left.width(), h = p.left.height();
  const PinholeRadTan c = camera_for(w, h);
  const cv::Mat K = (cv::Mat_<double>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
  const cv::Mat dist = (cv::Mat_<double>(1, 4) << c.k1, c.k2, c.p1, c.p2);
  cv::Mat m1, m2, dst;
  cv::initUndistortRectifyMap(K, dist, cv::Mat(), K, cv::Size(w, h), map_type, m1, m2);
  const cv::Mat src = as_mat(p.left);
  for (auto _ : st) {
    cv::remap(src, dst, m1, m2, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    benchmark::DoNotOptimize(dst.data);
  }
  set_label(st, p);
}
// CV_16SC2: OpenCV's fastest (fixed-point) map format; CV_32FC1: float maps.
void BM_Remap_opencv(benchmark::State& st) { remap_opencv(st, CV_16SC2); }
void BM_Remap_opencv_float_maps(benchmark::State& st) { remap_opencv(st, CV_32FC1); }
BENCHMARK(BM_Remap_opencv)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Remap_opencv_float_maps)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);
#endif

// ---- Stereo correlation at 500 Harris corners (ZNCC 7x7, left-right check) ----
struct StereoCase {
  Harris h;
  StereoConfig sc;
  explicit StereoCase(const Pair& p) : h(p.left.width(), p.left.height()) {
    h.det.detect(p.left.view(), h.out).ignore();
    sc.max_disparity_px = p.max_disparity;
  }
};

void BM_StereoAtCorners_qnav(benchmark::State& st) {
  const Pair& p = pair(static_cast<int>(st.range(0)));
  StereoCase c(p);
  StereoMatcher m;
  m.init(c.sc, StereoCamera{500.0, p.left.width() / 2.0, p.left.height() / 2.0, 0.1}).ignore();
  std::vector<StereoPoint> ps(c.h.out.size());
  BoundedVector<StereoPoint> pts(Span<StereoPoint>(ps.data(), ps.size()));
  for (auto _ : st) {
    m.match(p.left.view(), p.right.view(), c.h.out.span(), pts).ignore();
    benchmark::DoNotOptimize(pts.data());
  }
  set_label(st, p);
  st.counters["corners"] = static_cast<double>(c.h.out.size());
  st.counters["points"] = static_cast<double>(pts.size());
}
BENCHMARK(BM_StereoAtCorners_qnav)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

#ifdef QNAV_HAVE_OPENCV
// The same work with OpenCV: matchTemplate(TM_CCOEFF_NORMED) of the 7x7 left patch along the right
// row over the disparity range, minMaxLoc, then the reverse search for the left-right check.
void BM_StereoAtCorners_opencv(benchmark::State& st) {
  const Pair& p = pair(static_cast<int>(st.range(0)));
  StereoCase c(p);
  const cv::Mat L = as_mat(p.left), R = as_mat(p.right);
  const int r = c.sc.patch_radius, dmin = c.sc.min_disparity_px, dmax = c.sc.max_disparity_px;
  cv::Mat res, res2;
  int accepted = 0;
  for (auto _ : st) {
    accepted = 0;
    for (const Corner& k : c.h.out) {
      const int x = static_cast<int>(std::lround(k.x)), y = static_cast<int>(std::lround(k.y));
      const int dm = std::min(dmax, x - r);
      if (y < r || y >= L.rows - r || x >= L.cols - r || dm < dmin + 2) continue;
      const cv::Mat templ = L(cv::Rect(x - r, y - r, 2 * r + 1, 2 * r + 1));
      const cv::Mat strip = R(cv::Rect(x - dm - r, y - r, dm - dmin + 2 * r + 1, 2 * r + 1));
      cv::matchTemplate(strip, templ, res, cv::TM_CCOEFF_NORMED);
      double best;
      cv::Point loc;
      cv::minMaxLoc(res, nullptr, &best, nullptr, &loc);
      if (best < static_cast<double>(c.sc.min_zncc)) continue;
      const int xr = x - dm + loc.x;
      const int lmax = std::min(xr + dmax, L.cols - 1 - r);
      if (xr - r < 0 || lmax < xr + dmin) continue;
      const cv::Mat t2 = R(cv::Rect(xr - r, y - r, 2 * r + 1, 2 * r + 1));
      const cv::Mat strip2 = L(cv::Rect(xr + dmin - r, y - r, lmax - xr - dmin + 2 * r + 1, 2 * r + 1));
      cv::matchTemplate(strip2, t2, res2, cv::TM_CCOEFF_NORMED);
      cv::Point loc2;
      cv::minMaxLoc(res2, nullptr, nullptr, nullptr, &loc2);
      accepted += std::abs(xr + dmin + loc2.x - x) <= 1 ? 1 : 0;
    }
    benchmark::DoNotOptimize(accepted);
  }
  set_label(st, p);
  st.counters["points"] = accepted;
}
BENCHMARK(BM_StereoAtCorners_opencv)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Context only (different work: a dense disparity map): StereoBM over the whole image.
void BM_StereoBM_dense_opencv(benchmark::State& st) {
  const Pair& p = pair(static_cast<int>(st.range(0)));
  auto bm = cv::StereoBM::create(p.max_disparity, 7);
  cv::Mat disp;
  for (auto _ : st) {
    bm->compute(as_mat(p.left), as_mat(p.right), disp);
    benchmark::DoNotOptimize(disp.data);
  }
  set_label(st, p);
}
BENCHMARK(BM_StereoBM_dense_opencv)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
#endif

// ---- Descriptors at 500 Harris corners ----
void BM_PatchDescriptor_qnav(benchmark::State& st) {
  const Pair& p = pair(static_cast<int>(st.range(0)));
  Harris h(p.left.width(), p.left.height());
  h.det.detect(p.left.view(), h.out).ignore();
  std::vector<PatchDescriptor> d(h.out.size());
  for (auto _ : st) {
    for (std::size_t i = 0; i < h.out.size(); ++i)
      compute_patch_descriptor(p.left.view(), h.out[i].x, h.out[i].y, 0.3f, 1.0f, d[i]).ignore();
    benchmark::DoNotOptimize(d.data());
  }
  set_label(st, p);
}
BENCHMARK(BM_PatchDescriptor_qnav)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

void BM_OrientedDescriptor_qnav(benchmark::State& st) {
  const Pair& p = pair(static_cast<int>(st.range(0)));
  Harris h(p.left.width(), p.left.height());
  h.det.detect(p.left.view(), h.out).ignore();
  std::vector<OrientedDescriptor> d(h.out.size());
  for (auto _ : st) {
    for (std::size_t i = 0; i < h.out.size(); ++i)
      compute_oriented_descriptor(p.left.view(), h.out[i].x, h.out[i].y, 1.5f, d[i]).ignore();
    benchmark::DoNotOptimize(d.data());
  }
  set_label(st, p);
}
BENCHMARK(BM_OrientedDescriptor_qnav)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

#ifdef QNAV_HAVE_OPENCV
// Context: SIFT descriptors at the same 500 corners (OpenCV builds its Gaussian scale space first).
void BM_SiftDescriptor_opencv(benchmark::State& st) {
  const Pair& p = pair(static_cast<int>(st.range(0)));
  Harris h(p.left.width(), p.left.height());
  h.det.detect(p.left.view(), h.out).ignore();
  std::vector<cv::KeyPoint> kp;
  for (const Corner& c : h.out) kp.emplace_back(c.x, c.y, 3.0f);
  auto sift = cv::SIFT::create();
  cv::Mat desc;
  for (auto _ : st) {
    std::vector<cv::KeyPoint> k = kp;
    sift->compute(as_mat(p.left), k, desc);
    benchmark::DoNotOptimize(desc.data);
  }
  set_label(st, p);
}
BENCHMARK(BM_SiftDescriptor_opencv)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
#endif

// ---- Pyramid (4 levels) and the underwater degradation ----
void BM_Pyramid_qnav(benchmark::State& st) {
  const Pair& p = pair(static_cast<int>(st.range(0)));
  PyramidConfig pc;
  pc.max_width = p.left.width();
  pc.max_height = p.left.height();
  pc.levels = 4;
  ArenaStorage arena(static_cast<std::size_t>(p.left.width() * p.left.height()) * 2 + 64);
  ImagePyramid pyr;
  pyr.init(pc, arena).ignore();
  for (auto _ : st) {
    pyr.build(p.left.view()).ignore();
    benchmark::DoNotOptimize(pyr.level(3).data());
  }
  set_label(st, p);
}
BENCHMARK(BM_Pyramid_qnav)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

void BM_Degrade_qnav(benchmark::State& st) {
  const Pair& p = pair(static_cast<int>(st.range(0)));
  ImageU8 dst = ImageU8::allocate(p.left.width(), p.left.height()).value();
  const UnderwaterDegradation f = table1_filter(4);
  for (auto _ : st) {
    degrade_underwater(p.left.view(), f, dst.view()).ignore();
    benchmark::DoNotOptimize(dst.data());
  }
  set_label(st, p);
}
BENCHMARK(BM_Degrade_qnav)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
#ifdef QNAV_HAVE_OPENCV
  cv::setNumThreads(0);  // single thread, like nav/
#endif
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
