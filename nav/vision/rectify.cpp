#include "nav/vision/rectify.hpp"

#include <cmath>

namespace qnav::vision {

namespace {

bool finite(double v) noexcept { return std::isfinite(v); }

Status check_rotation(const Mat3d& R) noexcept {
  if (!R.allFinite()) return Status(StatusCode::kInvalidArgument, "rectify: rotation has non-finite values");
  if ((R * R.transpose() - Mat3d::Identity()).cwiseAbs().maxCoeff() > 1e-5 || std::fabs(R.determinant() - 1.0) > 1e-5)
    return Status(StatusCode::kInvalidArgument, "rectify: matrix is not a rotation");
  return Status::ok();
}

Status check_K(const Mat3d& K) noexcept {
  if (!K.allFinite()) return Status(StatusCode::kInvalidArgument, "rectify: K has non-finite values");
  if (K(1, 0) != 0.0 || K(2, 0) != 0.0 || K(2, 1) != 0.0 || K(2, 2) != 1.0)
    return Status(StatusCode::kInvalidArgument, "rectify: K must be upper triangular with K(2,2) = 1");
  if (!(K(0, 0) > 0.0) || !(K(1, 1) > 0.0)) return Status(StatusCode::kDegenerate, "rectify: K is singular (focal <= 0)");
  return Status::ok();
}

// Radial distortion stays monotonic (no fold-back of far rays into the image) while
// d/dr [r (1 + k1 r^2 + k2 r^4)] > 0.
bool radial_monotonic(const PinholeRadTan& c, double r2) noexcept { return 1.0 + 3.0 * c.k1 * r2 + 5.0 * c.k2 * r2 * r2 > 0.0; }

}  // namespace

Status validate(const PinholeRadTan& c) noexcept {
  for (double v : {c.fx, c.fy, c.cx, c.cy, c.k1, c.k2, c.p1, c.p2})
    if (!finite(v)) return Status(StatusCode::kInvalidArgument, "camera: non-finite intrinsics or distortion");
  if (!(c.fx > 0.0) || !(c.fy > 0.0)) return Status(StatusCode::kDegenerate, "camera: singular intrinsics (focal <= 0)");
  if (c.width <= 1 || c.height <= 1 || c.width > kMaxImageSide || c.height > kMaxImageSide)
    return Status(StatusCode::kInvalidArgument, "camera: image size out of range");
  return Status::ok();
}

Vec2d distort_normalised(const PinholeRadTan& c, const Vec2d& p) noexcept {
  const double x = p.x(), y = p.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + c.k1 * r2 + c.k2 * r2 * r2;
  return Vec2d(x * radial + 2.0 * c.p1 * x * y + c.p2 * (r2 + 2.0 * x * x),
               y * radial + c.p1 * (r2 + 2.0 * y * y) + 2.0 * c.p2 * x * y);
}

bool undistort_normalised(const PinholeRadTan& c, const Vec2d& xd, Vec2d& xy, int max_iterations) noexcept {
  if (!xd.allFinite()) return false;
  Vec2d p = xd;
  for (int it = 0; it < max_iterations && it < 100; ++it) {
    const Vec2d e = distort_normalised(c, p) - xd;
    if (e.norm() < 1e-12) break;
    // Gauss-Newton with the analytic Jacobian of the distortion.
    const double x = p.x(), y = p.y(), r2 = x * x + y * y;
    const double radial = 1.0 + c.k1 * r2 + c.k2 * r2 * r2;
    const double dradial = c.k1 + 2.0 * c.k2 * r2;  // d radial / d r2
    Mat2d J;
    J(0, 0) = radial + 2.0 * x * x * dradial + 2.0 * c.p1 * y + 6.0 * c.p2 * x;
    J(0, 1) = 2.0 * x * y * dradial + 2.0 * c.p1 * x + 2.0 * c.p2 * y;
    J(1, 0) = 2.0 * x * y * dradial + 2.0 * c.p1 * x + 2.0 * c.p2 * y;
    J(1, 1) = radial + 2.0 * y * y * dradial + 6.0 * c.p1 * y + 2.0 * c.p2 * x;
    const double det = J.determinant();
    if (!(std::fabs(det) > 1e-12)) return false;
    p -= J.inverse() * e;
    if (!p.allFinite()) return false;
  }
  if ((distort_normalised(c, p) - xd).norm() > 1e-9) return false;
  xy = p;
  return true;
}

bool refract_radius(double r_water, double n, double& r_air) noexcept {
  if (!finite(r_water) || !finite(n) || r_water < 0.0 || !(n > 0.0)) return false;
  const double s = n * std::sin(std::atan(r_water));
  if (!(s < 1.0)) return false;
  r_air = std::tan(std::asin(s));
  return true;
}

bool rectify_point(const PinholeRadTan& cam, const Mat3d& R_out_to_cam, const Mat3d& K_out, const FlatPortRefraction& port,
                   const Vec2d& raw_px, Vec2d& out_px) noexcept {
  if (!validate(cam).is_ok() || !check_K(K_out).is_ok() || !check_rotation(R_out_to_cam).is_ok() || !raw_px.allFinite())
    return false;
  Vec2d xy;
  const Vec2d xd((raw_px.x() - cam.cx) / cam.fx, (raw_px.y() - cam.cy) / cam.fy);
  if (!undistort_normalised(cam, xd, xy)) return false;
  if (port.enabled) {
    // Inverse of eq. 1: r_air -> angle in air -> angle in water.
    const double r_air = xy.norm();
    if (r_air > 0.0) {
      const double s = std::sin(std::atan(r_air)) / port.index_ratio;
      if (!(s < 1.0)) return false;
      const double r_water = std::tan(std::asin(s));
      xy *= r_water / r_air;
    }
  }
  const Vec3d ray_cam(xy.x(), xy.y(), 1.0);
  const Vec3d ray_out = R_out_to_cam.transpose() * ray_cam;
  if (!(ray_out.z() > 0.0)) return false;
  const Vec3d p = K_out * (ray_out / ray_out.z());
  out_px = Vec2d(p.x(), p.y());
  return out_px.allFinite();
}

std::size_t RemapTable::arena_bytes(const RemapConfig& config) noexcept {
  if (config.max_width < 2 || config.max_height < 2 || config.max_width > kMaxImageSide || config.max_height > kMaxImageSide)
    return 0;
  return static_cast<std::size_t>(config.max_width) * static_cast<std::size_t>(config.max_height) * sizeof(Entry) +
         alignof(Entry);
}

Status RemapTable::init(const RemapConfig& config, Arena& arena) noexcept {
  ready_ = false;
  if (config.max_width < 2 || config.max_height < 2 || config.max_width > kMaxImageSide || config.max_height > kMaxImageSide)
    return Status(StatusCode::kInvalidArgument, "remap: max size out of range");
  table_ = arena.allocate<Entry>(static_cast<std::size_t>(config.max_width) * static_cast<std::size_t>(config.max_height));
  if (table_.empty()) return Status(StatusCode::kCapacityExceeded, "remap: arena too small");
  config_ = config;
  ready_ = true;
  out_w_ = out_h_ = raw_w_ = raw_h_ = 0;
  valid_ = 0;
  return Status::ok();
}

Status RemapTable::build(const PinholeRadTan& raw, const Mat3d& K_out, const Mat3d& R_out_to_cam,
                         const FlatPortRefraction& port, int out_width, int out_height) noexcept {
  if (!ready_) return Status(StatusCode::kNotReady, "remap: build before init");
  out_w_ = out_h_ = 0;  // an error leaves the table unusable rather than half-built
  QNAV_RETURN_IF_ERROR(validate(raw));
  QNAV_RETURN_IF_ERROR(check_K(K_out));
  QNAV_RETURN_IF_ERROR(check_rotation(R_out_to_cam));
  if (port.enabled && (!finite(port.index_ratio) || !(port.index_ratio >= 1.0) || port.index_ratio > 3.0))
    return Status(StatusCode::kInvalidArgument, "remap: refraction index ratio must be in [1, 3]");
  if (out_width < 2 || out_height < 2 || out_width > config_.max_width || out_height > config_.max_height)
    return Status(StatusCode::kInvalidArgument, "remap: output size out of range");
  const Mat3d Kinv = K_out.inverse();
  const Mat3d M = R_out_to_cam * Kinv;  // output pixel -> ray in the raw camera frame
  const double xmax = static_cast<double>(raw.width - 1), ymax = static_cast<double>(raw.height - 1);
  std::size_t valid = 0;
  for (int v = 0; v < out_height; ++v) {
    Entry* row = table_.data() + static_cast<std::size_t>(v) * static_cast<std::size_t>(out_width);
    for (int u = 0; u < out_width; ++u) {
      Entry& e = row[u];
      e = Entry{0, 0, 0, 0, 0};
      const Vec3d ray = M * Vec3d(u, v, 1.0);
      if (!(ray.z() > 1e-12)) continue;
      Vec2d xy(ray.x() / ray.z(), ray.y() / ray.z());
      if (port.enabled) {
        const double r = xy.norm();
        double r_air = 0.0;
        if (r > 0.0) {
          if (!refract_radius(r, port.index_ratio, r_air)) continue;
          xy *= r_air / r;
        }
      }
      if (!radial_monotonic(raw, xy.squaredNorm())) continue;
      const Vec2d d = distort_normalised(raw, xy);
      double sx = raw.fx * d.x() + raw.cx, sy = raw.fy * d.y() + raw.cy;
      // A tolerance of 1e-6 px keeps the image border valid whatever the rounding (Eigen uses FMA on
      // aarch64, so pixel 0 may map to -1e-15). The last column/row is sampled with weight 255/256.
      constexpr double kEps = 1e-6;
      if (!(sx >= -kEps && sy >= -kEps && sx <= xmax + kEps && sy <= ymax + kEps)) continue;
      sx = sx < 0.0 ? 0.0 : (sx > xmax ? xmax : sx);
      sy = sy < 0.0 ? 0.0 : (sy > ymax ? ymax : sy);
      int x0 = static_cast<int>(sx), y0 = static_cast<int>(sy);
      int fx = static_cast<int>(std::lround((sx - x0) * 256.0));
      int fy = static_cast<int>(std::lround((sy - y0) * 256.0));
      if (fx == 256) {
        fx = 0;
        ++x0;
      }
      if (fy == 256) {
        fy = 0;
        ++y0;
      }
      if (x0 > raw.width - 2 || y0 > raw.height - 2) {
        // Rounded onto the last column/row: sample it with weight 255/256 from the previous one.
        if (x0 > raw.width - 2) {
          x0 = raw.width - 2;
          fx = 255;
        }
        if (y0 > raw.height - 2) {
          y0 = raw.height - 2;
          fy = 255;
        }
      }
      e = Entry{y0 * raw.width + x0, static_cast<std::uint8_t>(fx), static_cast<std::uint8_t>(fy), 1, 0};
      ++valid;
    }
  }
  out_w_ = out_width;
  out_h_ = out_height;
  raw_w_ = raw.width;
  raw_h_ = raw.height;
  valid_ = valid;
  return Status::ok();
}

Status RemapTable::build_undistort(const PinholeRadTan& raw, const FlatPortRefraction& port) noexcept {
  QNAV_RETURN_IF_ERROR(validate(raw));
  Mat3d K = Mat3d::Identity();
  K(0, 0) = raw.fx;
  K(1, 1) = raw.fy;
  K(0, 2) = raw.cx;
  K(1, 2) = raw.cy;
  return build(raw, K, Mat3d::Identity(), port, raw.width, raw.height);
}

Status RemapTable::apply(ConstImageViewU8 src, ImageViewU8 dst) const noexcept {
  if (!ready_ || out_w_ == 0) return Status(StatusCode::kNotReady, "remap: apply before a successful build");
  if (src.empty() || dst.empty()) return Status(StatusCode::kInvalidArgument, "remap: empty image");
  if (src.width() != raw_w_ || src.height() != raw_h_) return Status(StatusCode::kInvalidArgument, "remap: source size differs from the calibration");
  if (dst.width() != out_w_ || dst.height() != out_h_) return Status(StatusCode::kInvalidArgument, "remap: destination size differs from the table");
  // Locals: uint8_t stores may alias any member, so the loops must not read members.
  const std::uint8_t fill = config_.fill_value;
  const std::ptrdiff_t stride = src.stride();
  const std::uint8_t* base = src.data();
  const int ow = out_w_, oh = out_h_, rw = raw_w_;
  const Entry* const table = table_.data();
  if (stride == rw) {
    // Packed source (the usual case): one add per pixel to find the 2x2, no branch.
    for (int v = 0; v < oh; ++v) {
      const Entry* __restrict row = table + static_cast<std::size_t>(v) * static_cast<std::size_t>(ow);
      std::uint8_t* __restrict o = dst.row(v);
      for (int u = 0; u < ow; ++u) {
        const Entry e = row[u];
        const std::uint8_t* p = base + e.offset;
        const std::uint32_t fx = e.fx, fy = e.fy;
        const std::uint32_t top = p[0] * (256u - fx) + p[1] * fx;
        const std::uint32_t bot = p[stride] * (256u - fx) + p[stride + 1] * fx;
        const std::uint8_t val = static_cast<std::uint8_t>((top * (256u - fy) + bot * fy + 32768u) >> 16);
        o[u] = e.valid ? val : fill;
      }
    }
    return Status::ok();
  }
  for (int v = 0; v < oh; ++v) {
    const Entry* __restrict row = table + static_cast<std::size_t>(v) * static_cast<std::size_t>(ow);
    std::uint8_t* __restrict o = dst.row(v);
    for (int u = 0; u < ow; ++u) {
      const Entry e = row[u];
      if (!e.valid) {
        o[u] = fill;
        continue;
      }
      const std::int32_t y0 = e.offset / rw, x0 = e.offset - y0 * rw;
      const std::uint8_t* p = base + static_cast<std::ptrdiff_t>(y0) * stride + x0;
      const std::uint32_t fx = e.fx, fy = e.fy;
      const std::uint32_t top = p[0] * (256u - fx) + p[1] * fx;
      const std::uint32_t bot = p[stride] * (256u - fx) + p[stride + 1] * fx;
      o[u] = static_cast<std::uint8_t>((top * (256u - fy) + bot * fy + 32768u) >> 16);
    }
  }
  return Status::ok();
}

bool RemapTable::source_of(int x, int y, float& sx, float& sy) const noexcept {
  if (out_w_ == 0 || x < 0 || y < 0 || x >= out_w_ || y >= out_h_) return false;
  const Entry e = table_[static_cast<std::size_t>(y) * static_cast<std::size_t>(out_w_) + static_cast<std::size_t>(x)];
  if (!e.valid) return false;
  const std::int32_t y0 = e.offset / raw_w_, x0 = e.offset - y0 * raw_w_;
  sx = static_cast<float>(x0) + static_cast<float>(e.fx) / 256.0f;
  sy = static_cast<float>(y0) + static_cast<float>(e.fy) / 256.0f;
  return true;
}

Result<StereoRectification> stereo_rectify(const PinholeRadTan& left, const PinholeRadTan& right, const Pose3& T_left_right,
                                           int out_width, int out_height) noexcept {
  QNAV_RETURN_IF_ERROR(validate(left));
  QNAV_RETURN_IF_ERROR(validate(right));
  QNAV_RETURN_IF_ERROR(check_rotation(T_left_right.R));
  if (!T_left_right.t.allFinite()) return Status(StatusCode::kInvalidArgument, "rectify: translation has non-finite values");
  if (out_width < 2 || out_height < 2 || out_width > kMaxImageSide || out_height > kMaxImageSide)
    return Status(StatusCode::kInvalidArgument, "rectify: output size out of range");
  const double b = T_left_right.t.norm();
  if (!(b > 1e-9)) return Status(StatusCode::kDegenerate, "rectify: zero baseline");
  // Everything in the left camera frame. Right camera centre = t, its axes = columns of R.
  const Vec3d e1 = T_left_right.t / b;  // new x: along the baseline (right camera at +x)
  const Eigen::AngleAxisd aa(T_left_right.R);
  const Mat3d R_half = Eigen::AngleAxisd(0.5 * aa.angle(), aa.axis()).toRotationMatrix();
  const Vec3d z_mid = R_half * Vec3d::UnitZ();  // mean optical axis
  Vec3d e3 = z_mid - z_mid.dot(e1) * e1;
  if (!(e3.norm() > 1e-6)) return Status(StatusCode::kDegenerate, "rectify: baseline along the optical axis");
  e3.normalize();
  const Vec3d e2 = e3.cross(e1);
  Mat3d M;
  M.col(0) = e1;
  M.col(1) = e2;
  M.col(2) = e3;
  StereoRectification out;
  out.R_left = M;                                // rectified -> left camera
  out.R_right = T_left_right.R.transpose() * M;  // rectified -> right camera (directions)
  out.baseline_m = b;
  out.width = out_width;
  out.height = out_height;
  const double f = 0.25 * (left.fx + left.fy + right.fx + right.fy);
  // Principal point: the mean of where the two raw principal rays land is put at the image centre.
  const Vec3d a0 = out.R_left.transpose() * Vec3d::UnitZ();
  const Vec3d a1 = out.R_right.transpose() * Vec3d::UnitZ();
  const double mx = 0.5 * (a0.x() / a0.z() + a1.x() / a1.z()), my = 0.5 * (a0.y() / a0.z() + a1.y() / a1.z());
  out.K = Mat3d::Identity();
  out.K(0, 0) = f;
  out.K(1, 1) = f;
  out.K(0, 2) = 0.5 * (out_width - 1) - f * mx;
  out.K(1, 2) = 0.5 * (out_height - 1) - f * my;
  if (!out.K.allFinite() || !out.R_left.allFinite() || !out.R_right.allFinite())
    return Status(StatusCode::kDegenerate, "rectify: non-finite result");
  return out;
}

}  // namespace qnav::vision
