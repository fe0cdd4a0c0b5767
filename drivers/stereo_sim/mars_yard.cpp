#include "drivers/stereo_sim/mars_yard.hpp"

#include <cmath>

namespace qnav::sim {

namespace {

std::uint32_t hash3(std::int64_t x, std::int64_t y, std::uint64_t seed) noexcept {
  std::uint64_t h = seed * 0x9E3779B97F4A7C15ULL;
  h ^= static_cast<std::uint64_t>(x) * 0xBF58476D1CE4E5B9ULL;
  h = (h ^ (h >> 31)) * 0x94D049BB133111EBULL;
  h ^= static_cast<std::uint64_t>(y) * 0xD6E8FEB86659FD93ULL;
  h = (h ^ (h >> 29)) * 0xBF58476D1CE4E5B9ULL;
  h ^= h >> 32;
  return static_cast<std::uint32_t>(h);
}

double hash01(std::int64_t x, std::int64_t y, std::uint64_t seed) noexcept {
  return static_cast<double>(hash3(x, y, seed)) / 4294967296.0;
}

// Value noise in [-1, 1] at wavelength w (smoothstep interpolation of lattice values).
double value_noise(double x, double y, double w, std::uint64_t seed) noexcept {
  const double fx = x / w, fy = y / w;
  const double x0 = std::floor(fx), y0 = std::floor(fy);
  const std::int64_t ix = static_cast<std::int64_t>(x0), iy = static_cast<std::int64_t>(y0);
  double tx = fx - x0, ty = fy - y0;
  tx = tx * tx * (3.0 - 2.0 * tx);
  ty = ty * ty * (3.0 - 2.0 * ty);
  const double a = hash01(ix, iy, seed), b = hash01(ix + 1, iy, seed);
  const double c = hash01(ix, iy + 1, seed), d = hash01(ix + 1, iy + 1, seed);
  const double v = (a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * ty;
  return 2.0 * v - 1.0;
}

}  // namespace

double MarsYardTerrain::rock_height_m(double x, double y, double* rock_albedo) const noexcept {
  const double cell = config_.rock_cell_m;
  const std::int64_t cx = static_cast<std::int64_t>(std::floor(x / cell));
  const std::int64_t cy = static_cast<std::int64_t>(std::floor(y / cell));
  const std::uint64_t s = config_.seed * 31u + 5u;
  if (hash01(cx, cy, s) >= config_.rock_probability) return 0.0;
  const double r = config_.rock_radius_min_m + (config_.rock_radius_max_m - config_.rock_radius_min_m) * hash01(cx, cy, s + 1);
  const double margin = r / cell;
  const double px = (static_cast<double>(cx) + margin + (1.0 - 2.0 * margin) * hash01(cx, cy, s + 2)) * cell;
  const double py = (static_cast<double>(cy) + margin + (1.0 - 2.0 * margin) * hash01(cx, cy, s + 3)) * cell;
  const double q2 = ((x - px) * (x - px) + (y - py) * (y - py)) / (r * r);
  if (q2 >= 1.0) return 0.0;
  const double hmax = r * (0.3 + 0.2 * hash01(cx, cy, s + 4));
  if (rock_albedo != nullptr) *rock_albedo = 0.25 + 0.35 * hash01(cx, cy, s + 5);
  return hmax * (1.0 - q2) * (1.0 - q2);
}

double MarsYardTerrain::height_m(double x, double y) const noexcept {
  const std::uint64_t s = config_.seed;
  double h = config_.undulation_amplitude_m * (value_noise(x, y, 2.0, s + 100) + 0.35 * value_noise(x, y, 0.5, s + 101));
  h += config_.grain_amplitude_m * (value_noise(x, y, 0.02, s + 102) + 0.5 * value_noise(x, y, 0.01, s + 103));
  h += rock_height_m(x, y, nullptr);
  return h;
}

double MarsYardTerrain::albedo(double x, double y) const noexcept {
  const std::uint64_t s = config_.seed + 1000;
  double rock = 0.0;
  const bool on_rock = rock_height_m(x, y, &rock) > 0.0;
  const double base = on_rock ? rock : 0.5 + 0.08 * value_noise(x, y, 0.2, s);
  double a = base + 0.12 * value_noise(x, y, 0.032, s + 1) + 0.10 * value_noise(x, y, 0.016, s + 2) +
             0.08 * value_noise(x, y, 0.008, s + 3);
  if (on_rock) a += 0.08 * value_noise(x, y, 0.012, s + 4);
  return a < 0.02 ? 0.02 : (a > 1.0 ? 1.0 : a);
}

Vec3d MarsYardTerrain::normal(double x, double y) const noexcept {
  const double e = 0.002;
  const double dx = (height_m(x + e, y) - height_m(x - e, y)) / (2.0 * e);
  const double dy = (height_m(x, y + e) - height_m(x, y - e)) / (2.0 * e);
  return Vec3d(-dx, -dy, 1.0).normalized();
}

double MarsYardTerrain::radiance(double x, double y) const noexcept {
  const double lambert = normal(x, y).dot(config_.sun_direction.normalized());
  const double shade = config_.ambient + (1.0 - config_.ambient) * (lambert > 0.0 ? lambert : 0.0);
  return albedo(x, y) * shade;
}

Pose3 StereoBench::rover_T_left() const noexcept {
  const double a = tilt_down_rad;
  const Vec3d zc(std::cos(a), 0.0, -std::sin(a));
  const Vec3d xc(0.0, -1.0, 0.0);
  const Vec3d yc = zc.cross(xc);
  Pose3 p;
  p.R.col(0) = xc;
  p.R.col(1) = yc;
  p.R.col(2) = zc;
  p.t = Vec3d(0.0, 0.0, height_m);
  return p;
}

bool cast_ray(const MarsYardTerrain& terrain, const StereoBench& bench, const Pose3& world_T_cam, double u, double v,
              Vec3d& out) noexcept {
  const double f = bench.focal_px();
  const Vec3d d = world_T_cam.R * Vec3d((u - bench.cu_px()) / f, (v - bench.cv_px()) / f, 1.0);
  const Vec3d& o = world_T_cam.t;
  if (!(d.z() < -1e-3)) return false;
  double h = 0.0;
  Vec3d p = o;
  for (int it = 0; it < kRayIterations; ++it) {
    const double t = (h - o.z()) / d.z();
    p = o + t * d;
    const double hn = terrain.height_m(p.x(), p.y());
    if (std::fabs(hn - h) < 2e-5) {
      h = hn;
      break;
    }
    h += 0.9 * (hn - h);  // lightly damped fixed point
  }
  p = o + ((h - o.z()) / d.z()) * d;
  out = p;
  return std::isfinite(p.x());
}

Status render_stereo(const MarsYardTerrain& terrain, const StereoBench& bench, const Pose3& world_T_left,
                     std::uint64_t frame_seed, ImageViewU8 left, ImageViewU8 right) noexcept {
  const int w = bench.width(), hgt = bench.height();
  if (left.empty() || right.empty() || left.width() != w || left.height() != hgt || right.width() != w ||
      right.height() != hgt)
    return Status(StatusCode::kInvalidArgument, "render target size differs from the bench");
  if (!world_T_left.is_finite()) return Status(StatusCode::kInvalidArgument, "camera pose not finite");
  Pcg32 rng(frame_seed * 2654435761ULL + 17u);
  for (int cam = 0; cam < 2; ++cam) {
    Pose3 pose = world_T_left;
    if (cam == 1) pose.t += world_T_left.R.col(0) * bench.baseline_m;
    ImageViewU8 img = cam == 0 ? left : right;
    for (int y = 0; y < hgt; ++y) {
      std::uint8_t* row = img.row(y);
      for (int x = 0; x < w; ++x) {
        Vec3d p;
        double val = 0.0;
        if (cast_ray(terrain, bench, pose, x, y, p)) val = 255.0 * 0.95 * terrain.radiance(p.x(), p.y());
        val += bench.sensor_noise_dn * rng.normal();
        const long q = std::lround(val);
        row[x] = static_cast<std::uint8_t>(q < 0 ? 0 : (q > 255 ? 255 : q));
      }
    }
  }
  return Status::ok();
}

MarsYardTrajectory::MarsYardTrajectory(const TrajectoryConfig& config) noexcept : config_(config), rng_(config.seed) {}

const RoverSample& MarsYardTrajectory::next() noexcept {
  const double step = rng_.uniform(config_.step_min_m, config_.step_max_m);
  heading_rad_ = 0.7 * heading_rad_ + config_.heading_wander_rad * rng_.normal();
  x_m_ += step * std::cos(heading_rad_);
  y_m_ += step * std::sin(heading_rad_);
  // Drawn in order, in separate statements: the evaluation order of function arguments is unspecified
  // (x86-64 and SPARC gcc differ), and the same seed must give the same trajectory on every target.
  // Pitch first: the order x86-64 gcc used, so the host's trajectories (and docs/vo.md) are unchanged.
  const double pitch_rad = config_.roll_pitch_rad * rng_.normal();
  const double roll_rad = config_.roll_pitch_rad * rng_.normal();
  cur_.world_T_rover.R = rotation_from_rpy(roll_rad, pitch_rad, heading_rad_);
  cur_.world_T_rover.t = Vec3d(x_m_, y_m_, 0.0);
  cur_.time_s += step / config_.speed_m_s;
  cur_.path_m += step;
  return cur_;
}

}  // namespace qnav::sim
