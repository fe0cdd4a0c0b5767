#include "nav/route/camera_tile.hpp"

#include <algorithm>
#include <cmath>

namespace qnav::route {

Status CameraTileProjector::init(const CameraTileConfig& c) noexcept {
  ready_ = false;
  if (!(c.resolution_m > 0.0) || !std::isfinite(c.resolution_m) || c.width_px < 8 || c.height_px < 8 ||
      !(c.max_tilt_rad > 0.0) || !(c.max_tilt_rad < deg_to_rad(90.0)))
    return Status(StatusCode::kInvalidArgument, "camera tile config out of range");
  config_ = c;
  ready_ = true;
  return Status::ok();
}

Result<double> CameraTileProjector::project(ConstImageViewU8 image, const CameraIntrinsics& k, const Pose3& ned_T_cam,
                                            double ground_down_m, double heading_rad, ImageViewF32 out,
                                            ImageViewU8 coverage, TileGeometry& geometry) noexcept {
  if (!ready_) return Status(StatusCode::kNotReady, "CameraTileProjector::project before init");
  const int W = config_.width_px, H = config_.height_px;
  if (image.empty() || image.width() < 2 || image.height() < 2 || out.empty() || coverage.empty() || out.width() < W ||
      out.height() < H || coverage.width() < W || coverage.height() < H) {
    counters_.increment(CameraTileCounter::kBadInput);
    return Status(StatusCode::kInvalidArgument, "camera tile: empty image or output smaller than the configured raster");
  }
  if (!ned_T_cam.is_finite() || !std::isfinite(ground_down_m) || !std::isfinite(heading_rad) || !(k.fx_px > 0.0) ||
      !(k.fy_px > 0.0) || !std::isfinite(k.fx_px) || !std::isfinite(k.fy_px) || !std::isfinite(k.cu_px) ||
      !std::isfinite(k.cv_px)) {
    counters_.increment(CameraTileCounter::kBadInput);
    return Status(StatusCode::kInvalidArgument, "camera tile: non-finite pose, ground or intrinsics");
  }
  // Optical axis in NED; it must point down within the tilt limit and meet the ground below the camera.
  const Vec3d axis = ned_T_cam.R.col(2);
  const double range = ground_down_m - ned_T_cam.t.z();  // vertical distance camera -> ground
  if (!(axis.z() > std::cos(config_.max_tilt_rad)) || !(range > 0.0)) {
    counters_.increment(CameraTileCounter::kGroundNotVisible);
    return Status(StatusCode::kInvalidArgument, "camera tile: the ground is not below the camera within the tilt limit");
  }
  const double s = range / axis.z();
  const double cn = ned_T_cam.t.x() + s * axis.x(), ce = ned_T_cam.t.y() + s * axis.y();
  const double res = config_.resolution_m;
  geometry.resolution_m = res;
  geometry.origin_north_m = cn + 0.5 * H * res;
  geometry.origin_east_m = ce - 0.5 * W * res;
  geometry.pose = Pose2{ned_T_cam.t.x(), ned_T_cam.t.y(), heading_rad};  // the nadir: the vehicle's position
  // Camera coordinates of a ground point G: R^T (G - t), linear in the raster's (c, r).
  const Mat3d Rt = ned_T_cam.R.transpose();
  const Vec3d p00 = Rt * (Vec3d(geometry.origin_north_m - 0.5 * res, geometry.origin_east_m + 0.5 * res, ground_down_m) - ned_T_cam.t);
  const Vec3d dc = Rt * Vec3d(0.0, res, 0.0);   // one raster column east
  const Vec3d dr = Rt * Vec3d(-res, 0.0, 0.0);  // one raster row south
  const double umax = image.width() - 1, vmax = image.height() - 1;
  long covered = 0;
  for (int r = 0; r < H; ++r) {
    float* o = out.row(r);
    std::uint8_t* cv = coverage.row(r);
    Vec3d p = p00 + static_cast<double>(r) * dr;
    for (int c = 0; c < W; ++c, p += dc) {
      o[c] = 0.0f;
      cv[c] = 0;
      if (!(p.z() > 1e-9)) continue;
      const double u = k.fx_px * p.x() / p.z() + k.cu_px, v = k.fy_px * p.y() / p.z() + k.cv_px;
      if (!(u >= 0.0 && v >= 0.0 && u <= umax && v <= vmax)) continue;
      const int u0 = std::min(static_cast<int>(u), image.width() - 2), v0 = std::min(static_cast<int>(v), image.height() - 2);
      const double fu = u - u0, fv = v - v0;
      const std::uint8_t* a = image.row(v0) + u0;
      const std::uint8_t* b = image.row(v0 + 1) + u0;
      const double top = a[0] + fu * (a[1] - a[0]), bot = b[0] + fu * (b[1] - b[0]);
      o[c] = static_cast<float>(top + fv * (bot - top));
      cv[c] = 255;
      ++covered;
    }
  }
  if (covered == 0) {
    counters_.increment(CameraTileCounter::kEmptyTile);
    return Status(StatusCode::kInvalidArgument, "camera tile: no raster pixel falls inside the image");
  }
  return static_cast<double>(covered) / (static_cast<double>(W) * H);
}

}  // namespace qnav::route
