// Shared by the OpenCV peer test (test/reference/opencv_peer_test.cpp) and benchmark
// (test/bench/mapping/bench_mapping_opencv.cpp): one real downward-camera pair from
// ../shared/data/downward/sparus_snippet turned into descriptor matches, and the conversions that
// hand the SAME points to qnav and to OpenCV. OpenCV is a test / benchmark peer only (never linked
// by nav/ or firmware/).
//   real pair: Harris on level 0 (up to 500 corners), the oriented descriptor at each (scale 1.5),
//   qnav's RatioMatcher all-against-all (ratio 0.8); the matched positions are undistorted with the
//   camera's plumb_bob model (cv::undistortPoints, P = K) so that a homography / F fits them.
#pragma once

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "firmware/tools/image_reader.hpp"
#include "nav/core/arena.hpp"
#include "nav/core/fixed_vector.hpp"
#include "nav/core/geometry.hpp"
#include "nav/match/ratio_match.hpp"
#include "nav/vision/corner.hpp"
#include "nav/vision/descriptor.hpp"
#include "nav/vision/harris.hpp"

namespace qnav::peer {

inline std::vector<cv::Point2f> to_cv(const std::vector<Vec2d>& v) {
  std::vector<cv::Point2f> out;
  out.reserve(v.size());
  for (const Vec2d& p : v) out.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()));
  return out;
}

inline Mat3d from_cv(const cv::Mat& m) {
  Mat3d r = Mat3d::Zero();
  if (m.rows != 3 || m.cols != 3) return r;
  cv::Mat d;
  m.convertTo(d, CV_64F);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = d.at<double>(i, j);
  return r;
}

// Descriptors as an n x 128 CV_32F matrix (the same floats qnav compares).
inline cv::Mat descriptor_mat(const std::vector<vision::OrientedDescriptor>& d) {
  cv::Mat m(static_cast<int>(d.size()), vision::kOrientedDims, CV_32F);
  for (std::size_t i = 0; i < d.size(); ++i)
    for (int k = 0; k < vision::kOrientedDims; ++k) m.at<float>(static_cast<int>(i), k) = d[i].v[k];
  return m;
}

// Harris (level 0, up to max_corners) + oriented descriptors; only valid descriptors are kept.
inline std::vector<vision::OrientedDescriptor> describe(const ImageU8& img, int max_corners = 500) {
  vision::HarrisConfig c;
  c.max_width = img.width();
  c.max_height = img.height();
  c.max_corners = max_corners;
  c.border_px = 12;
  ArenaStorage arena(vision::HarrisDetector::arena_bytes(c));
  vision::HarrisDetector det;
  std::vector<vision::Corner> storage(static_cast<std::size_t>(max_corners));
  BoundedVector<vision::Corner> corners(Span<vision::Corner>(storage.data(), storage.size()));
  std::vector<vision::OrientedDescriptor> out;
  if (!det.init(c, arena).is_ok() || !det.detect(img.view(), corners).is_ok()) return out;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    vision::OrientedDescriptor d;
    if (!vision::compute_oriented_descriptor(img.view(), corners[i].x, corners[i].y, 1.5f, d).is_ok() || !d.valid) continue;
    d.x = corners[i].x;
    d.y = corners[i].y;
    out.push_back(d);
  }
  return out;
}

struct RealPair {
  bool ok = false;
  std::string why;
  int width = 0, height = 0;
  std::vector<vision::OrientedDescriptor> da, db;  // frame A (query), frame B (train)
  std::vector<match::DescriptorMatch> matches;     // qnav ratio matches A -> B
  std::vector<Vec2d> a, b;                         // undistorted matched positions (pixels, same K)
};

inline match::RatioMatchConfig real_ratio_config() {
  match::RatioMatchConfig rc;
  rc.max_query = 512;
  rc.max_train = 512;
  rc.max_ratio = 0.8f;
  return rc;
}

// frames/frame_<ia>.png and frame_<ib>.png of the sparus snippet under shared_dir.
inline RealPair load_real_pair(const std::string& shared_dir, int ia = 0, int ib = 1) {
  RealPair p;
  const std::string dir = shared_dir + "/data/downward/sparus_snippet/frames/";
  char na[32], nb[32];
  std::snprintf(na, sizeof na, "frame_%04d.png", ia);
  std::snprintf(nb, sizeof nb, "frame_%04d.png", ib);
  Result<ImageU8> ra = tools::read_image_gray8((dir + na).c_str());
  Result<ImageU8> rb = tools::read_image_gray8((dir + nb).c_str());
  if (!ra.is_ok() || !rb.is_ok()) {
    p.why = "cannot read " + dir + na + " / " + nb;
    return p;
  }
  p.width = ra->width();
  p.height = ra->height();
  p.da = describe(ra.value());
  p.db = describe(rb.value());
  const match::RatioMatchConfig rc = real_ratio_config();
  ArenaStorage arena(match::RatioMatcher::arena_bytes(rc));
  match::RatioMatcher m;
  std::vector<match::DescriptorMatch> storage(rc.max_query);
  BoundedVector<match::DescriptorMatch> out(Span<match::DescriptorMatch>(storage.data(), storage.size()));
  if (!m.init(rc, arena).is_ok() ||
      !m.match(Span<const vision::OrientedDescriptor>(p.da.data(), p.da.size()),
               Span<const vision::OrientedDescriptor>(p.db.data(), p.db.size()), out)
           .is_ok()) {
    p.why = "ratio matching failed";
    return p;
  }
  p.matches.assign(out.data(), out.data() + out.size());
  // camera.yaml of the snippet (plumb_bob).
  const cv::Mat K = (cv::Mat_<double>(3, 3) << 405.638, 0, 189.905, 0, 405.588, 139.915, 0, 0, 1);
  const cv::Mat D = (cv::Mat_<double>(1, 5) << -0.36707, 0.20300, 0.0033369, -0.00048743, 0.0);
  std::vector<cv::Point2f> pa, pb, ua, ub;
  for (const match::DescriptorMatch& mm : p.matches) {
    pa.emplace_back(p.da[mm.query].x, p.da[mm.query].y);
    pb.emplace_back(p.db[mm.train].x, p.db[mm.train].y);
  }
  if (pa.empty()) {
    p.why = "no matches";
    return p;
  }
  cv::undistortPoints(pa, ua, K, D, cv::noArray(), K);
  cv::undistortPoints(pb, ub, K, D, cv::noArray(), K);
  for (std::size_t i = 0; i < ua.size(); ++i) {
    p.a.emplace_back(ua[i].x, ua[i].y);
    p.b.emplace_back(ub[i].x, ub[i].y);
  }
  p.ok = true;
  return p;
}

}  // namespace qnav::peer
