// Synthetic two-view scenes with exact ground truth for the F / H tests (nav/motion and nav/match):
// a 320 x 240 pinhole camera (f = 300 px) moved between two frames; either a general 3D point
// cloud (known F) or a flat seabed under a downward camera (known H); Gaussian pixel noise and
// uniform outliers from the seeded DeterministicRng (separate statements per draw, so every target
// draws the same sequence).
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "nav/core/geometry.hpp"
#include "nav/match/ransac.hpp"

namespace qnav::test {

constexpr double kFocalPx = 300.0, kCx = 160.0, kCy = 120.0, kWidthPx = 320.0, kHeightPx = 240.0;

inline Mat3d camera_matrix() {
  Mat3d k;
  k << kFocalPx, 0.0, kCx, 0.0, kFocalPx, kCy, 0.0, 0.0, 1.0;
  return k;
}

inline Mat3d skew(const Vec3d& v) {
  Mat3d s;
  s << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return s;
}

inline double gaussian(match::DeterministicRng& rng) {
  double u1 = rng.uniform();
  const double u2 = rng.uniform();
  if (u1 < 1e-300) u1 = 1e-300;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
}

struct TwoViewScene {
  std::vector<Vec2d> a, b;          // observed (noise, outliers)
  std::vector<Vec2d> b_true;        // noise-free position in view b of a[i]'s point (inliers)
  std::vector<Vec2d> a_true;
  std::vector<std::uint8_t> inlier;  // 1 = a true correspondence
  Mat3d F = Mat3d::Zero();          // x_b^T F x_a = 0 (general scene)
  Mat3d H = Mat3d::Identity();      // x_b ~ H x_a (planar scene)
  std::uint32_t inliers = 0;
};

// Camera b = R * camera a + t (points: X_b = R X_a + t).
struct Motion {
  Mat3d R = rotation_from_rpy(0.04, -0.03, 0.25);
  Vec3d t = Vec3d(0.6, -0.3, 0.15);
};

inline Vec2d project(const Vec3d& x) {
  const Vec3d u = camera_matrix() * x;
  return Vec2d(u.x() / u.z(), u.y() / u.z());
}

inline Vec2d random_pixel(match::DeterministicRng& rng) {
  const double x = rng.uniform() * kWidthPx;
  const double y = rng.uniform() * kHeightPx;
  return Vec2d(x, y);
}

inline void add_noise_and_outlier(TwoViewScene& s, const Vec2d& a_true, const Vec2d& b_true, double noise_px,
                                  double outlier_frac, match::DeterministicRng& rng) {
  const bool outlier = rng.uniform() < outlier_frac;
  Vec2d a = a_true, b = b_true;
  const double n0 = gaussian(rng), n1 = gaussian(rng), n2 = gaussian(rng), n3 = gaussian(rng);
  a += noise_px * Vec2d(n0, n1);
  b += noise_px * Vec2d(n2, n3);
  if (outlier) b = random_pixel(rng);
  s.a.push_back(a);
  s.b.push_back(b);
  s.a_true.push_back(a_true);
  s.b_true.push_back(b_true);
  s.inlier.push_back(outlier ? 0 : 1);
  s.inliers += outlier ? 0u : 1u;
}

// Points at 4..10 m in front of camera a, seen by both cameras.
inline TwoViewScene general_scene(int n, double noise_px, double outlier_frac, std::uint64_t seed, const Motion& m = Motion()) {
  match::DeterministicRng rng(seed);
  TwoViewScene s;
  const Mat3d k = camera_matrix(), kinv = k.inverse();
  s.F = kinv.transpose() * skew(m.t) * m.R * kinv;
  s.F /= s.F.norm();
  while (static_cast<int>(s.a.size()) < n) {
    const Vec2d pa = random_pixel(rng);
    const double depth = 4.0 + 6.0 * rng.uniform();
    const Vec3d xa = depth * (kinv * Vec3d(pa.x(), pa.y(), 1.0));
    const Vec3d xb = m.R * xa + m.t;
    if (xb.z() < 1.0) continue;
    const Vec2d pb = project(xb);
    if (pb.x() < 0.0 || pb.x() > kWidthPx || pb.y() < 0.0 || pb.y() > kHeightPx) continue;
    add_noise_and_outlier(s, pa, pb, noise_px, outlier_frac, rng);
  }
  return s;
}

// A flat seabed at altitude_m under camera a (plane z = altitude_m in a's frame, normal (0, 0, 1)):
// H = K (R - t n^T / d) K^-1.
inline Mat3d seabed_homography(const Motion& m, double altitude_m) {
  const Mat3d k = camera_matrix();
  const Mat3d h = k * (m.R + m.t * Vec3d(0.0, 0.0, 1.0).transpose() / altitude_m) * k.inverse();
  return h / h(2, 2);
}

inline TwoViewScene planar_scene(int n, double noise_px, double outlier_frac, std::uint64_t seed, const Motion& m = Motion(),
                                 double altitude_m = 5.0) {
  match::DeterministicRng rng(seed);
  TwoViewScene s;
  s.H = seabed_homography(m, altitude_m);
  const Mat3d kinv = camera_matrix().inverse();
  s.F = kinv.transpose() * skew(m.t) * m.R * kinv;
  s.F /= s.F.norm();
  while (static_cast<int>(s.a.size()) < n) {
    const Vec2d pa = random_pixel(rng);
    const Vec3d u = s.H * Vec3d(pa.x(), pa.y(), 1.0);
    const Vec2d pb(u.x() / u.z(), u.y() / u.z());
    if (pb.x() < 0.0 || pb.x() > kWidthPx || pb.y() < 0.0 || pb.y() > kHeightPx) continue;
    add_noise_and_outlier(s, pa, pb, noise_px, outlier_frac, rng);
  }
  return s;
}

// RMS distance (px) between H_est and H_true transfers over a 9 x 9 grid covering the image.
inline double homography_grid_error_px(const Mat3d& h_est, const Mat3d& h_true) {
  double sse = 0.0;
  int n = 0;
  for (int gy = 0; gy < 9; ++gy)
    for (int gx = 0; gx < 9; ++gx) {
      const Vec3d p(kWidthPx * gx / 8.0, kHeightPx * gy / 8.0, 1.0);
      const Vec3d ue = h_est * p, ut = h_true * p;
      sse += (ue.head<2>() / ue.z() - ut.head<2>() / ut.z()).squaredNorm();
      ++n;
    }
  return std::sqrt(sse / n);
}

}  // namespace qnav::test
