#include "nav/vo/track_refiner.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "test/support/alloc_guard.hpp"

namespace qnav::vo {
namespace {

vision::StereoCamera camera() {
  vision::StereoCamera c;
  c.focal_px = 333.3;
  c.cu_px = 159.5;
  c.cv_px = 127.5;
  c.baseline_m = 0.05;
  return c;
}

// Texture painted on the ground plane (metres in the plane), wavelengths 3-8 cm: below 0.5 rad/px from
// 0.8 m at f = 333 px.
double ground_texture(double a, double b) {
  return 128.0 + 45.0 * std::sin(120.0 * a + 0.3) * std::cos(105.0 * b) + 35.0 * std::sin(75.0 * a - 140.0 * b) +
         25.0 * std::cos(190.0 * b + 60.0 * a);
}

// The Mars bench over flat ground: the world is the reference left camera's frame (x right, y down,
// z forward), the camera 0.8 m above the ground and looking 70 deg down, so the ground plane n . X = d
// has its normal 20 deg from the optical axis.
struct Scene {
  Vec3d n_w = Vec3d(0.0, -std::sin(deg_to_rad(20.0)), -std::cos(deg_to_rad(20.0)));  // towards the camera
  double d_w = -0.8;  // the camera is 0.8 m from the plane
  vision::StereoCamera cam = camera();
  int w = 320, h = 256;
  // Renders the left (right = false) or right camera of a rig at world_T_cam.
  std::vector<std::uint8_t> render(const Pose3& world_T_cam, bool right) const {
    std::vector<std::uint8_t> px(static_cast<std::size_t>(w * h));
    const Vec3d origin = world_T_cam.apply(Vec3d(right ? cam.baseline_m : 0.0, 0.0, 0.0));
    const Vec3d e1 = n_w.unitOrthogonal(), e2 = n_w.cross(e1);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const Vec3d dir = world_T_cam.R * Vec3d((x - cam.cu_px) / cam.focal_px, (y - cam.cv_px) / cam.focal_px, 1.0);
        const double lam = (d_w - n_w.dot(origin)) / n_w.dot(dir);
        const Vec3d p = origin + lam * dir;
        const double v = ground_texture(e1.dot(p), e2.dot(p));
        px[static_cast<std::size_t>(y * w + x)] = static_cast<std::uint8_t>(std::lround(std::min(255.0, std::max(0.0, v))));
      }
    return px;
  }
  ConstImageViewU8 view(const std::vector<std::uint8_t>& px) const { return ConstImageViewU8::make(px.data(), w, h).value(); }
  // The world point seen by the left camera at pixel (u, v).
  Vec3d point(const Pose3& world_T_cam, double u, double v) const {
    const Vec3d dir = world_T_cam.R * Vec3d((u - cam.cu_px) / cam.focal_px, (v - cam.cv_px) / cam.focal_px, 1.0);
    const double lam = (d_w - n_w.dot(world_T_cam.t)) / n_w.dot(dir);
    return world_T_cam.t + lam * dir;
  }
};

match::Landmark3 landmark(const Pose3& world_T_cam, const Vec3d& world_point, const vision::StereoCamera& c) {
  match::Landmark3 l;
  l.position_m = world_T_cam.inverse().apply(world_point);
  l.u_px = static_cast<float>(c.focal_px * l.position_m.x() / l.position_m.z() + c.cu_px);
  l.v_px = static_cast<float>(c.focal_px * l.position_m.y() / l.position_m.z() + c.cv_px);
  return l;
}

TEST(TrackRefiner, PlaneAffineOfAFrontoParallelPlaneIsTheDepthRatio) {
  TrackRefiner t;
  ASSERT_TRUE(t.init(TrackRefineConfig{}, camera()).is_ok());
  const Vec3d p(0.0, 0.0, 2.0), n(0.0, 0.0, -1.0);
  Pose3 step;  // current camera 0.2 m closer
  step.t = Vec3d(0.0, 0.0, 0.2);
  float a[4];
  ASSERT_TRUE(t.plane_affine(p, n, step, camera().cu_px, camera().cv_px, a));
  EXPECT_NEAR(a[0], 1.8 / 2.0, 1e-4);  // one current pixel is 0.9 reference pixels
  EXPECT_NEAR(a[3], 1.8 / 2.0, 1e-4);
  EXPECT_NEAR(a[1], 0.0, 1e-4);
  EXPECT_NEAR(a[2], 0.0, 1e-4);
  // A rotation about the optical axis rotates the patch.
  Pose3 roll;
  roll.R = Eigen::AngleAxisd(deg_to_rad(10.0), Vec3d::UnitZ()).toRotationMatrix();
  ASSERT_TRUE(t.plane_affine(p, n, roll, camera().cu_px, camera().cv_px, a));
  EXPECT_NEAR(a[0], std::cos(deg_to_rad(10.0)), 1e-4);
  EXPECT_NEAR(a[2], std::sin(deg_to_rad(10.0)), 1e-4);
  // A plane seen edge-on has no affine.
  EXPECT_FALSE(t.plane_affine(p, Vec3d(1.0, 0.0, 0.0), Pose3{}, camera().cu_px, camera().cv_px, a));
}

TEST(TrackRefiner, NeighbourSearchAlongXGivesTheFullScansNormalBitForBit) {
  TrackRefiner t;
  TrackRefineConfig cfg;
  ASSERT_TRUE(t.init(cfg, camera()).is_ok());
  // A lattice on a tilted plane in binary fractions of a metre (exact distances: many equal ones, so the
  // K-th neighbour is decided by index), with a few exact duplicates and points off the plane.
  std::vector<match::Landmark3> ref;
  for (int j = 0; j < 9; ++j)
    for (int i = 0; i < 11; ++i) {
      match::Landmark3 l;
      l.position_m = Vec3d(0.125 * (i - 5), 0.125 * (j - 4), 2.0 + 0.0625 * i + 0.03125 * ((i * j) % 3));
      ref.push_back(l);
    }
  // Landmarks appended out of x order: duplicates of earlier ones and a scattered cloud.
  for (int k = 0; k < 12; ++k) ref.push_back(ref[static_cast<std::size_t>((k * 37) % 99)]);
  for (int k = 0; k < 40; ++k) {
    match::Landmark3 l;
    l.position_m = Vec3d(std::sin(1.7 * k) * 0.8, std::cos(2.3 * k) * 0.6, 2.5 + 0.4 * std::sin(0.9 * k));
    ref.push_back(l);
  }
  const Span<const match::Landmark3> span(ref.data(), ref.size());
  std::vector<std::int32_t> order(ref.size());
  ASSERT_TRUE(TrackRefiner::sort_by_x(span, Span<std::int32_t>(order.data(), order.size())));
  for (std::size_t k = 1; k < order.size(); ++k)
    ASSERT_LE(ref[static_cast<std::size_t>(order[k - 1])].position_m.x(), ref[static_cast<std::size_t>(order[k])].position_m.x());
  const Span<const std::int32_t> by_x(order.data(), order.size());
  int planar = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const Vec3d a = t.local_normal(span, i), b = t.local_normal(span, i, by_x);
    EXPECT_EQ(a.x(), b.x()) << i;
    EXPECT_EQ(a.y(), b.y()) << i;
    EXPECT_EQ(a.z(), b.z()) << i;
    if (!a.isApprox(-ref[i].position_m.normalized())) ++planar;  // not the facing fallback
  }
  EXPECT_GT(planar, 80);
  // Orders that cannot be made: a non-finite position, too small a buffer.
  std::vector<match::Landmark3> bad = ref;
  bad[5].position_m.y() = std::nan("");
  EXPECT_FALSE(TrackRefiner::sort_by_x(Span<const match::Landmark3>(bad.data(), bad.size()),
                                       Span<std::int32_t>(order.data(), order.size())));
  EXPECT_FALSE(TrackRefiner::sort_by_x(span, Span<std::int32_t>(order.data(), order.size() - 1)));
}

// local_normal's closed-form 3 x 3 solve: on points scattered over a tilted plane (an irregular cloud, so
// the neighbourhoods differ) the normal is the plane's to 1e-9 and faces the camera; with the points lifted
// off the plane by up to 0.1 mm (neighbours about 0.1 m apart) it stays within 0.5 deg.
TEST(TrackRefiner, LocalNormalIsThePlanesNormal) {
  TrackRefiner t;
  ASSERT_TRUE(t.init(TrackRefineConfig{}, camera()).is_ok());
  const Vec3d n_true = Vec3d(0.2, -0.5, -1.0).normalized();  // towards the camera (n . p < 0 ahead)
  const Vec3d e1 = n_true.unitOrthogonal(), e2 = n_true.cross(e1);
  const Vec3d origin(0.0, 0.0, 2.0);
  for (const double rough_m : {0.0, 1e-4}) {
    std::vector<match::Landmark3> ref;
    for (int k = 0; k < 60; ++k) {
      match::Landmark3 l;
      l.position_m = origin + 0.5 * std::sin(1.3 * k + 0.2) * e1 + 0.4 * std::cos(2.1 * k) * e2 +
                     rough_m * std::sin(5.7 * k) * n_true;
      ref.push_back(l);
    }
    const Span<const match::Landmark3> span(ref.data(), ref.size());
    for (std::size_t i = 0; i < ref.size(); ++i) {
      const Vec3d n = t.local_normal(span, i);
      ASSERT_NEAR(n.norm(), 1.0, 1e-12) << i;
      const double angle = std::atan2(n.cross(n_true).norm(), n.dot(n_true));
      if (rough_m == 0.0)
        EXPECT_LT(angle, 1e-9) << i;
      else
        EXPECT_LT(angle, deg_to_rad(0.5)) << i;
    }
  }
}

TEST(TrackRefiner, RefinedPointIsTheSamePhysicalPointToAFractionOfAPixel) {
  const Scene s;
  Pose3 ref_pose;  // the reference camera is the world
  Pose3 cur_pose;
  cur_pose.t = Vec3d(0.01, -0.188, 0.068);  // a 0.2 m step along the ground (n . t = 0)
  cur_pose.R = Eigen::AngleAxisd(deg_to_rad(1.5), Vec3d(0.3, 1.0, 0.2).normalized()).toRotationMatrix();
  const std::vector<std::uint8_t> l0 = s.render(ref_pose, false), l1 = s.render(cur_pose, false),
                                   r1 = s.render(cur_pose, true);
  // Reference landmarks on a grid (exact 3D), the current ones with the Harris jitter (0.3 px) and a
  // depth error, as the VO would have them.
  std::vector<match::Landmark3> ref;
  for (double v = 30; v <= 150; v += 20)
    for (double u = 60; u <= 280; u += 20) ref.push_back(landmark(ref_pose, s.point(ref_pose, u, v), s.cam));
  TrackRefiner t;
  ASSERT_TRUE(t.init(TrackRefineConfig{}, s.cam).is_ok());
  const Pose3 step = ref_pose.inverse().compose(cur_pose);
  int ok = 0;
  double worst_px = 0.0, worst_depth = 0.0, sum2_px = 0.0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const Vec3d w = ref_pose.apply(ref[i].position_m);
    match::Landmark3 cur = landmark(cur_pose, w, s.cam);
    if (cur.u_px < 12 || cur.u_px > 300 || cur.v_px < 12 || cur.v_px > 244) continue;
    const Vec3d truth = cur.position_m;
    cur.u_px += (i % 2 ? 0.3f : -0.3f);
    cur.v_px += (i % 3 ? -0.25f : 0.25f);
    cur.position_m *= 1.02;
    Vec3d out;
    const Status st = t.refine(s.view(l0), Span<const match::Landmark3>(ref.data(), ref.size()), i, s.view(l1),
                               s.view(r1), cur, step, out);
    EXPECT_TRUE(st.is_ok()) << i << " at " << cur.u_px << "," << cur.v_px << ": " << st.message();
    if (!st.is_ok()) continue;
    ++ok;
    const double u = s.cam.focal_px * out.x() / out.z() + s.cam.cu_px, v = s.cam.focal_px * out.y() / out.z() + s.cam.cv_px;
    const double tu = s.cam.focal_px * truth.x() / truth.z() + s.cam.cu_px, tv = s.cam.focal_px * truth.y() / truth.z() + s.cam.cv_px;
    worst_px = std::max(worst_px, std::hypot(u - tu, v - tv));
    sum2_px += (u - tu) * (u - tu) + (v - tv) * (v - tv);
    worst_depth = std::max(worst_depth, std::fabs(out.z() - truth.z()) / truth.z());
  }
  // From 0.39 px of jitter and 2 % of depth (measured: rms 0.04 px, worst 0.11 px, 0.41 %).
  EXPECT_GE(ok, 50);
  EXPECT_LT(std::sqrt(sum2_px / ok), 0.06);
  EXPECT_LT(worst_px, 0.15);
  EXPECT_LT(worst_depth, 0.006);
}

TEST(TrackRefiner, BadInputIsAnError) {
  TrackRefiner t;
  std::vector<match::Landmark3> ref(3);
  std::vector<std::uint8_t> img(64 * 64, 100);
  const ConstImageViewU8 v = ConstImageViewU8::make(img.data(), 64, 64).value();
  Vec3d out;
  EXPECT_EQ(t.refine(v, Span<const match::Landmark3>(ref.data(), ref.size()), 0, v, v, ref[0], Pose3{}, out).code(),
            StatusCode::kNotReady);
  vision::StereoCamera bad = camera();
  bad.baseline_m = 0.0;
  EXPECT_EQ(t.init(TrackRefineConfig{}, bad).code(), StatusCode::kInvalidArgument);
  TrackRefineConfig c;
  c.normal_neighbours = 2;
  EXPECT_EQ(t.init(c, camera()).code(), StatusCode::kInvalidArgument);
  c = TrackRefineConfig{};
  c.align.radius = 0;
  EXPECT_EQ(t.init(c, camera()).code(), StatusCode::kInvalidArgument);
  ASSERT_TRUE(t.init(TrackRefineConfig{}, camera()).is_ok());
  EXPECT_EQ(t.refine(v, Span<const match::Landmark3>(ref.data(), ref.size()), 3, v, v, ref[0], Pose3{}, out).code(),
            StatusCode::kOutOfRange);
  // A flat image has nothing to align: not found, nothing written.
  ref[0].position_m = Vec3d(0.0, 0.0, 1.0);
  ref[0].u_px = ref[0].v_px = 32.0f;
  out = Vec3d(7.0, 7.0, 7.0);
  EXPECT_EQ(t.refine(v, Span<const match::Landmark3>(ref.data(), ref.size()), 0, v, v, ref[0], Pose3{}, out).code(),
            StatusCode::kNotFound);
  EXPECT_EQ(out, Vec3d(7.0, 7.0, 7.0));
  vision::StereoPoint p;
  p.x_px = 32.0f;
  p.y_px = 32.0f;
  p.disparity_px = 5.0f;
  EXPECT_EQ(t.refine_disparity(v, v, 0.1f, p).code(), StatusCode::kNotFound);
  EXPECT_EQ(p.disparity_px, 5.0f);
}

TEST(TrackRefiner, RefinesWithoutHeap) {
  const Scene s;
  Pose3 cur_pose;
  cur_pose.t = Vec3d(0.0, -0.14, 0.05);
  const std::vector<std::uint8_t> l0 = s.render(Pose3{}, false), l1 = s.render(cur_pose, false), r1 = s.render(cur_pose, true);
  std::vector<match::Landmark3> ref;
  for (double u = 100; u <= 220; u += 20) ref.push_back(landmark(Pose3{}, s.point(Pose3{}, u, 150.0), s.cam));
  TrackRefiner t;
  ASSERT_TRUE(t.init(TrackRefineConfig{}, s.cam).is_ok());
  const match::Landmark3 cur = landmark(cur_pose, ref[3].position_m, s.cam);
  Vec3d out;
  Status st;
  QNAV_EXPECT_NO_ALLOC(st = t.refine(s.view(l0), Span<const match::Landmark3>(ref.data(), ref.size()), 3, s.view(l1),
                                     s.view(r1), cur, cur_pose, out));
  EXPECT_TRUE(st.is_ok());
}

}  // namespace
}  // namespace qnav::vo
