#include "nav/vo/track_refiner.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace qnav::vo {

Status TrackRefiner::init(const TrackRefineConfig& config, const vision::StereoCamera& camera) noexcept {
  ready_ = false;
  if (config.normal_neighbours < 3 || config.normal_neighbours > kMaxNeighbours || !(config.max_planarity > 0.0) ||
      !(config.max_planarity <= 1.0) || !(config.max_disparity_change_px > 0.0f))
    return Status(StatusCode::kInvalidArgument, "track refine config out of range");
  if (!(camera.focal_px > 0.0) || !(camera.baseline_m > 0.0) || !std::isfinite(camera.focal_px) ||
      !std::isfinite(camera.baseline_m) || !std::isfinite(camera.cu_px) || !std::isfinite(camera.cv_px))
    return Status(StatusCode::kInvalidArgument, "track refine: invalid stereo camera");
  QNAV_RETURN_IF_ERROR(aligner_.configure(config.align));
  config_ = config;
  camera_ = camera;
  ready_ = true;
  return Status::ok();
}

bool TrackRefiner::sort_by_x(Span<const match::Landmark3> ref, Span<std::int32_t> order) noexcept {
  if (order.size() < ref.size()) return false;
  for (std::size_t j = 0; j < ref.size(); ++j) {
    if (!ref[j].position_m.allFinite()) return false;
    order[j] = static_cast<std::int32_t>(j);
  }
  std::sort(order.data(), order.data() + ref.size(), [&ref](std::int32_t a, std::int32_t b) {
    const double xa = ref[static_cast<std::size_t>(a)].position_m.x(), xb = ref[static_cast<std::size_t>(b)].position_m.x();
    return xa < xb || (xa == xb && a < b);
  });
  return true;
}

Vec3d TrackRefiner::local_normal(Span<const match::Landmark3> ref, std::size_t index,
                                 Span<const std::int32_t> ref_by_x) const noexcept {
  const Vec3d& p = ref[index].position_m;
  const Vec3d facing = -p.normalized();  // fallback: a plane facing the camera (scale change only)
  // The K nearest reference landmarks (insertion into a sorted fixed array; K <= kMaxNeighbours): the K
  // smallest (squared distance, index) pairs in that order, as the scan in ascending index gives them
  // (an equal distance later in the scan neither displaces nor passes one held).
  const int k_max = config_.normal_neighbours;
  double d2[kMaxNeighbours];
  std::size_t idx[kMaxNeighbours];
  int k = 0;
  if (ref_by_x.size() == ref.size() && p.allFinite()) {
    // Outwards from p's x along ref_by_x on both sides; a side ends once K are held and dx^2 exceeds the
    // K-th distance (every later one there is at least as far in x, and its squared norm, dx^2 plus
    // non-negative rounded squares, at least dx^2). Equal distances are decided by index.
    auto visit = [&](std::int32_t jj) {
      const std::size_t j = static_cast<std::size_t>(jj);
      const Vec3d& q = ref[j].position_m;
      const double dx = q.x() - p.x();
      if (k == k_max && dx * dx > d2[k - 1]) return false;
      const double d = (q - p).squaredNorm();
      if (k == k_max && (d > d2[k - 1] || (d == d2[k - 1] && j > idx[k - 1]))) return true;
      int pos = k < k_max ? k++ : k - 1;
      while (pos > 0 && (d2[pos - 1] > d || (d2[pos - 1] == d && idx[pos - 1] > j))) {
        d2[pos] = d2[pos - 1];
        idx[pos] = idx[pos - 1];
        --pos;
      }
      d2[pos] = d;
      idx[pos] = j;
      return true;
    };
    const std::int32_t* first = ref_by_x.data();
    const std::int32_t* last = first + ref_by_x.size();
    const std::int32_t* split = std::lower_bound(first, last, p.x(), [&ref](std::int32_t a, double x) {
      return ref[static_cast<std::size_t>(a)].position_m.x() < x;
    });
    for (const std::int32_t* o = split; o != last && visit(*o); ++o) {
    }
    for (const std::int32_t* o = split; o != first && visit(*(o - 1)); --o) {
    }
  } else {
    for (std::size_t j = 0; j < ref.size(); ++j) {
      const Vec3d& q = ref[j].position_m;
      // Once K are held, a point whose x difference alone reaches the K-th distance is out: the squared
      // norm (a sum of non-negative rounded squares) is at least dx^2, so the test below would drop it too.
      if (k == k_max) {
        const double dx = q.x() - p.x();
        if (dx * dx >= d2[k - 1]) continue;
      }
      const double d = (q - p).squaredNorm();
      if (k == k_max && d >= d2[k - 1]) continue;
      int pos = k < k_max ? k++ : k - 1;
      while (pos > 0 && d2[pos - 1] > d) {
        d2[pos] = d2[pos - 1];
        idx[pos] = idx[pos - 1];
        --pos;
      }
      d2[pos] = d;
      idx[pos] = j;
    }
  }
  if (k < 3) return facing;
  Vec3d mean = Vec3d::Zero();
  for (int i = 0; i < k; ++i) mean += ref[idx[i]].position_m;
  mean /= static_cast<double>(k);
  Mat3d cov = Mat3d::Zero();
  for (int i = 0; i < k; ++i) {
    const Vec3d d = ref[idx[i]].position_m - mean;
    cov += d * d.transpose();
  }
  // The closed-form 3 x 3 solve (the characteristic cubic's roots, eigenvectors by cross products) rather
  // than the iterative one: on a LEON3 most of local_normal's count was the tridiagonal QL iterations.
  Eigen::SelfAdjointEigenSolver<Mat3d> es;
  es.computeDirect(cov);
  if (es.info() != Eigen::Success) return facing;
  const Vec3d ev = es.eigenvalues();  // increasing
  if (!(ev(1) > 0.0) || !(ev(0) <= config_.max_planarity * ev(1))) return facing;
  Vec3d n = es.eigenvectors().col(0);
  if (n.dot(p) > 0.0) n = -n;  // towards the camera
  return n.allFinite() ? n : facing;
}

bool TrackRefiner::plane_affine(const Vec3d& point_ref_m, const Vec3d& normal_ref, const Pose3& prev_T_cur, double u_px,
                                double v_px, float (&affine)[4]) const noexcept {
  const double f = camera_.focal_px;
  const double dp = normal_ref.dot(point_ref_m);
  const double nt = normal_ref.dot(prev_T_cur.t);
  // Current pixel -> ray in the reference frame -> plane -> reference pixel.
  auto map = [&](double u, double v, double& uo, double& vo) {
    const Vec3d dir = prev_T_cur.R * Vec3d((u - camera_.cu_px) / f, (v - camera_.cv_px) / f, 1.0);
    const double den = normal_ref.dot(dir);
    if (!(std::fabs(den) > 1e-6)) return false;
    const Vec3d x = prev_T_cur.t + ((dp - nt) / den) * dir;
    if (!(x.z() > 1e-6)) return false;
    uo = f * x.x() / x.z();
    vo = f * x.y() / x.z();
    return std::isfinite(uo) && std::isfinite(vo);
  };
  double u1 = 0.0, v1 = 0.0, u2 = 0.0, v2 = 0.0, u3 = 0.0, v3 = 0.0, u4 = 0.0, v4 = 0.0;
  if (!map(u_px + 0.5, v_px, u1, v1) || !map(u_px - 0.5, v_px, u2, v2) || !map(u_px, v_px + 0.5, u3, v3) ||
      !map(u_px, v_px - 0.5, u4, v4))
    return false;
  affine[0] = static_cast<float>(u1 - u2);
  affine[1] = static_cast<float>(u3 - u4);
  affine[2] = static_cast<float>(v1 - v2);
  affine[3] = static_cast<float>(v3 - v4);
  return true;
}

Status TrackRefiner::refine(ConstImageViewU8 ref_left, Span<const match::Landmark3> ref, std::size_t ref_index,
                            ConstImageViewU8 left, ConstImageViewU8 right, const match::Landmark3& cur,
                            const Pose3& prev_T_cur, Vec3d& cur_point_m, Span<const std::int32_t> ref_by_x) noexcept {
  if (!ready_) return Status(StatusCode::kNotReady, "TrackRefiner::refine before init");
  if (ref_index >= ref.size()) return Status(StatusCode::kOutOfRange, "track refine: reference index");
  const match::Landmark3& a = ref[ref_index];
  float warp[4] = {1.0f, 0.0f, 0.0f, 1.0f};
  const Vec3d n = local_normal(ref, ref_index, ref_by_x);
  if (!plane_affine(a.position_m, n, prev_T_cur, static_cast<double>(cur.u_px), static_cast<double>(cur.v_px), warp)) {
    warp[0] = 1.0f;
    warp[1] = 0.0f;
    warp[2] = 0.0f;
    warp[3] = 1.0f;
  }
  vision::PatchAlignResult rl, rr;
  Status s = aligner_.align_warped(ref_left, a.u_px, a.v_px, warp, left, cur.u_px, cur.v_px, false, rl);
  if (!s.is_ok() && s.code() == StatusCode::kInvalidArgument)  // an extreme warp: try without it
    s = aligner_.align(ref_left, a.u_px, a.v_px, left, cur.u_px, cur.v_px, false, rl);
  if (!s.is_ok()) return Status(StatusCode::kNotFound, "track refine: left patch did not align");
  const double z = cur.position_m.z();
  const float d0 = z > 0.0 ? static_cast<float>(camera_.baseline_m * camera_.focal_px / z) : 0.0f;
  if (!aligner_.align(left, rl.x_px, rl.y_px, right, rl.x_px - d0, rl.y_px, true, rr).is_ok())
    return Status(StatusCode::kNotFound, "track refine: disparity did not align");
  Vec3f q;
  if (!vision::triangulate(camera_, rl.x_px, rl.y_px, rl.x_px - rr.x_px, q) || !q.allFinite())
    return Status(StatusCode::kNotFound, "track refine: no positive disparity");
  cur_point_m = q.cast<double>();
  return Status::ok();
}

Status TrackRefiner::refine_disparity(ConstImageViewU8 left, ConstImageViewU8 right, float disparity_sigma_px,
                                      vision::StereoPoint& p) noexcept {
  if (!ready_) return Status(StatusCode::kNotReady, "TrackRefiner::refine_disparity before init");
  vision::PatchAlignResult ra;
  if (!aligner_.align(left, p.x_px, p.y_px, right, p.x_px - p.disparity_px, p.y_px, true, ra).is_ok())
    return Status(StatusCode::kNotFound, "track refine: disparity did not align");
  const float d = p.x_px - ra.x_px;
  Vec3f q;
  if (!(std::fabs(d - p.disparity_px) <= config_.max_disparity_change_px) ||
      !vision::triangulate(camera_, p.x_px, p.y_px, d, q))
    return Status(StatusCode::kNotFound, "track refine: aligned disparity implausible");
  p.disparity_px = d;
  p.p_m = q;
  p.sigma_z_m = vision::depth_sigma_m(camera_, q.z(), disparity_sigma_px);
  return Status::ok();
}

}  // namespace qnav::vo
