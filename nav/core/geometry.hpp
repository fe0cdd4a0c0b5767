// Small geometry types shared by every stage. Fixed-size Eigen types only (no heap).
// Conventions: SI units; angles in radians; right-handed frames. Pose2: x, y in metres and a yaw
// (heading_rad) in the plane; Pose3: rotation matrix R and translation t, mapping points from the
// body frame to the reference frame (p_ref = R p_body + t).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace qnav {

using Vec2f = Eigen::Vector2f;
using Vec3f = Eigen::Vector3f;
using Vec2d = Eigen::Vector2d;
using Vec3d = Eigen::Vector3d;
using Mat2d = Eigen::Matrix2d;
using Mat3d = Eigen::Matrix3d;
using Mat3f = Eigen::Matrix3f;
using Mat4d = Eigen::Matrix4d;
using Mat6d = Eigen::Matrix<double, 6, 6>;

constexpr double kPi = 3.14159265358979323846;

constexpr double deg_to_rad(double deg) noexcept { return deg * (kPi / 180.0); }
constexpr double rad_to_deg(double rad) noexcept { return rad * (180.0 / kPi); }

// Wraps an angle to (-pi, pi]. NaN stays NaN; infinities become NaN.
inline double wrap_angle_rad(double a) noexcept {
  if (!std::isfinite(a)) return std::nan("");
  a = std::fmod(a + kPi, 2.0 * kPi);
  if (a <= 0.0) a += 2.0 * kPi;
  return a - kPi;
}

struct Point2i {
  int x = 0;
  int y = 0;
};

// Integer rectangle [x, x + width) x [y, y + height).
struct RectI {
  int x = 0;
  int y = 0;
  int width = 0;
  int height = 0;

  bool empty() const noexcept { return width <= 0 || height <= 0; }
  bool contains(int px, int py) const noexcept { return px >= x && py >= y && px < x + width && py < y + height; }
  RectI intersect(const RectI& o) const noexcept {
    const int x0 = x > o.x ? x : o.x;
    const int y0 = y > o.y ? y : o.y;
    const int x1 = (x + width) < (o.x + o.width) ? (x + width) : (o.x + o.width);
    const int y1 = (y + height) < (o.y + o.height) ? (y + height) : (o.y + o.height);
    if (x1 <= x0 || y1 <= y0) return RectI{x0, y0, 0, 0};
    return RectI{x0, y0, x1 - x0, y1 - y0};
  }
};

// Rigid transform in the plane.
struct Pose2 {
  double x_m = 0.0;
  double y_m = 0.0;
  double heading_rad = 0.0;

  Vec2d translation() const noexcept { return Vec2d(x_m, y_m); }
  Mat2d rotation() const noexcept {
    const double c = std::cos(heading_rad), s = std::sin(heading_rad);
    Mat2d r;
    r << c, -s, s, c;
    return r;
  }
  Vec2d apply(const Vec2d& p) const noexcept { return rotation() * p + translation(); }
  // this * o : first o, then this.
  Pose2 compose(const Pose2& o) const noexcept {
    const Vec2d t = apply(o.translation());
    return Pose2{t.x(), t.y(), wrap_angle_rad(heading_rad + o.heading_rad)};
  }
  Pose2 inverse() const noexcept {
    const Vec2d t = -(rotation().transpose() * translation());
    return Pose2{t.x(), t.y(), wrap_angle_rad(-heading_rad)};
  }
  bool is_finite() const noexcept { return std::isfinite(x_m) && std::isfinite(y_m) && std::isfinite(heading_rad); }
};

// Rigid transform in space.
struct Pose3 {
  Mat3d R = Mat3d::Identity();
  Vec3d t = Vec3d::Zero();

  Vec3d apply(const Vec3d& p) const noexcept { return R * p + t; }
  Pose3 compose(const Pose3& o) const noexcept { return Pose3{R * o.R, R * o.t + t}; }
  Pose3 inverse() const noexcept {
    const Mat3d rt = R.transpose();
    return Pose3{rt, -(rt * t)};
  }
  bool is_finite() const noexcept { return R.allFinite() && t.allFinite(); }
};

// Rotation from roll, pitch, yaw (aerospace Z-Y-X order: R = Rz(yaw) Ry(pitch) Rx(roll)).
inline Mat3d rotation_from_rpy(double roll_rad, double pitch_rad, double yaw_rad) noexcept {
  return (Eigen::AngleAxisd(yaw_rad, Vec3d::UnitZ()) * Eigen::AngleAxisd(pitch_rad, Vec3d::UnitY()) *
          Eigen::AngleAxisd(roll_rad, Vec3d::UnitX()))
      .toRotationMatrix();
}

// Angle of the rotation R (0..pi), numerically safe near 0 and pi.
inline double rotation_angle_rad(const Mat3d& R) noexcept {
  double c = (R.trace() - 1.0) * 0.5;
  if (c > 1.0) c = 1.0;
  if (c < -1.0) c = -1.0;
  return std::acos(c);
}

}  // namespace qnav
