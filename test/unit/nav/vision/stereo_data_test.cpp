// Real-data checks of the vision front end (host only: reads the sample images under
// qnav::tools::shared_dir(): $QNAV_SHARED_DIR, else the build's ../shared).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "firmware/tools/image_reader.hpp"
#include "firmware/tools/sequence_reader.hpp"
#include "firmware/tools/stereo_eval.hpp"
#include "nav/vision/harris.hpp"
#include "nav/vision/rectify.hpp"
#include "nav/vision/stereo.hpp"
#include "firmware/tools/shared_dir.hpp"

namespace qnav::vision {
namespace {

const std::string kStereo = qnav::tools::shared_dir() + "/data/stereo/";

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t i = static_cast<std::size_t>(p * static_cast<double>(v.size() - 1) + 0.5);
  return v[i];
}

struct Detector {
  explicit Detector(int w, int h, int cap) : storage(static_cast<std::size_t>(cap)) {
    HarrisConfig c;
    c.max_width = w;
    c.max_height = h;
    c.max_corners = cap;
    arena = std::make_unique<ArenaStorage>(HarrisDetector::arena_bytes(c));
    ok = det.init(c, *arena).is_ok();
    out = BoundedVector<Corner>(Span<Corner>(storage.data(), storage.size()));
  }
  std::unique_ptr<ArenaStorage> arena;
  std::vector<Corner> storage;
  BoundedVector<Corner> out;
  HarrisDetector det;
  bool ok = false;
};

// Middlebury Aloe (full size, GT disparity in pixels, 0 = unknown): disparity at Harris corners.
TEST(StereoData, AloeDisparityAtHarrisCornersAgreesWithGroundTruth) {
  Result<ImageU8> l = tools::read_image_gray8((kStereo + "middlebury_aloe_opencv/aloeL.jpg").c_str());
  if (!l.is_ok()) GTEST_SKIP() << "Aloe sample missing under " << kStereo;
  Result<ImageU8> r = tools::read_image_gray8((kStereo + "middlebury_aloe_opencv/aloeR.jpg").c_str());
  Result<ImageU8> gt = tools::read_image_gray8((kStereo + "middlebury_aloe_opencv/aloeGT.png").c_str());
  ASSERT_TRUE(r.is_ok() && gt.is_ok());
  const int W = l->width(), H = l->height();
  Detector d(W, H, 1000);
  ASSERT_TRUE(d.ok);
  ASSERT_TRUE(d.det.detect(l->view(), d.out).is_ok());
  StereoConfig sc;
  sc.min_disparity_px = 1;
  sc.max_disparity_px = 240;
  StereoMatcher m;
  ASSERT_TRUE(m.init(sc, StereoCamera{1000.0, W / 2.0, H / 2.0, 0.1}).is_ok());
  std::vector<StereoPoint> pst(1000);
  BoundedVector<StereoPoint> pts(Span<StereoPoint>(pst.data(), pst.size()));
  ASSERT_TRUE(m.match(l->view(), r->view(), d.out.span(), pts).is_ok());
  std::vector<double> err;
  for (const StereoPoint& p : pts) {
    const int g = (*gt)(static_cast<int>(std::lround(p.x_px)), static_cast<int>(std::lround(p.y_px)));
    if (g == 0) continue;
    err.push_back(std::fabs(static_cast<double>(p.disparity_px) - g));
  }
  const double within1 = static_cast<double>(std::count_if(err.begin(), err.end(), [](double e) { return e <= 1.0; })) /
                         static_cast<double>(err.size());
  std::printf("aloe: corners %zu, matched %zu, with GT %zu, median |d - gt| %.3f px, within 1 px %.1f %%\n",
              d.out.size(), pts.size(), err.size(), percentile(err, 0.5), 100.0 * within1);
  EXPECT_GT(pts.size(), d.out.size() / 2);
  EXPECT_LT(percentile(err, 0.5), 0.5);
  EXPECT_GT(within1, 0.85);
}

// EuRoC V1_01 frame 0: after rectification, matched corners lie on the same row.
TEST(StereoData, EurocRectifiedPairHasEpipolarRowsWithinHalfAPixel) {
  const std::string dir = kStereo + "euroc_v1_01_hover40";
  Result<tools::EurocCamera> c0 = tools::read_euroc_camera(dir + "/cam0/sensor.yaml");
  if (!c0.is_ok()) GTEST_SKIP() << "EuRoC sample missing under " << dir;
  Result<tools::EurocCamera> c1 = tools::read_euroc_camera(dir + "/cam1/sensor.yaml");
  std::vector<tools::StereoFrame> frames;
  ASSERT_TRUE(c1.is_ok() && tools::read_euroc_sequence(dir, frames).is_ok());
  Result<ImageU8> rawl = tools::read_image_gray8(frames[0].left_path.c_str());
  Result<ImageU8> rawr = tools::read_image_gray8(frames[0].right_path.c_str());
  ASSERT_TRUE(rawl.is_ok() && rawr.is_ok());
  const int W = rawl->width(), H = rawl->height();
  Result<StereoRectification> rect =
      stereo_rectify(c0->model, c1->model, tools::euroc_stereo_extrinsics(*c0, *c1), W, H);
  ASSERT_TRUE(rect.is_ok()) << rect.status().message();
  RemapConfig rc;
  rc.max_width = W;
  rc.max_height = H;
  ArenaStorage arena(2 * RemapTable::arena_bytes(rc));
  RemapTable tl, tr;
  ASSERT_TRUE(tl.init(rc, arena).is_ok() && tr.init(rc, arena).is_ok());
  ASSERT_TRUE(tl.build(c0->model, rect->K, rect->R_left, FlatPortRefraction{}, W, H).is_ok());
  ASSERT_TRUE(tr.build(c1->model, rect->K, rect->R_right, FlatPortRefraction{}, W, H).is_ok());
  Result<ImageU8> recl = ImageU8::allocate(W, H), recr = ImageU8::allocate(W, H);
  ASSERT_TRUE(tl.apply(rawl->view(), recl->view()).is_ok());
  ASSERT_TRUE(tr.apply(rawr->view(), recr->view()).is_ok());

  // For each Harris corner of the left image: 2D ZNCC search in the right image (disparity 1..80,
  // rows -4..+4), sub-pixel row by a parabola; keep strong unique matches; report the row offset.
  auto row_offsets = [&](ConstImageViewU8 L, ConstImageViewU8 R) {
    Detector d(W, H, 300);
    EXPECT_TRUE(d.ok);
    EXPECT_TRUE(d.det.detect(L, d.out).is_ok());
    return tools::epipolar_row_offsets(L, R, Span<const Corner>(d.out.data(), d.out.size()));
  };
  const std::vector<double> dy_rect = row_offsets(recl->view(), recr->view());
  const std::vector<double> dy_raw = row_offsets(rawl->view(), rawr->view());
  std::printf("euroc rows: rectified %zu matches, |dy| median %.3f px, p90 %.3f px; raw %zu matches, |dy| median %.3f px\n",
              dy_rect.size(), percentile(dy_rect, 0.5), percentile(dy_rect, 0.9), dy_raw.size(), percentile(dy_raw, 0.5));
  ASSERT_GT(dy_rect.size(), 50u);
  EXPECT_LT(percentile(dy_rect, 0.5), 0.5);
  EXPECT_LT(percentile(dy_rect, 0.9), 1.0);
  EXPECT_GT(percentile(dy_raw, 0.5), 1.5);  // without rectification the rows disagree (the test can fail)
}

}  // namespace
}  // namespace qnav::vision
