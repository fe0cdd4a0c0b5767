// A deterministic textured seabed seen by a downward pinhole camera (drivers/downward_sim, header-only):
// the scene of the nav/topo tests and of `qnav map eval`, so the tool and the tests render one scene.
// The seabed is a flat ground raster (1 texel = texel_m metres, ground axes X right / Y down like the
// image) of smooth value noise plus hashed rectangles (sharp corners for Harris), built once from an
// integer hash (same texels on every target). A camera at ground position C (metres), yaw psi (the
// angle of the image x axis in the ground frame, image convention: +psi turns x towards y) and
// altitude h sees pixel (u, v) at ground C + (h / f) R(psi) (u - cx, v - cy); 2 x 2 samples per pixel,
// bilinear on the raster. So H_0<-k has rotation psi_k - psi_0 and maps the principal point of frame
// k to R(psi_0)^T (C_k - C_0) f / h_0 + c.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "nav/core/image.hpp"

namespace qnav::sim::downward {

inline std::uint32_t hash32(std::int32_t i, std::int32_t j, std::uint32_t salt) {
  std::uint32_t h = static_cast<std::uint32_t>(i) * 0x8DA6B343u ^ static_cast<std::uint32_t>(j) * 0xD8163841u ^ salt * 0xCB1AB31Fu;
  h ^= h >> 15;
  h *= 0x2C1B3C6Du;
  h ^= h >> 12;
  h *= 0x297A2D39u;
  h ^= h >> 15;
  return h;
}
inline double hash01(std::int32_t i, std::int32_t j, std::uint32_t salt) { return (hash32(i, j, salt) & 0xFFFFFFu) / 16777215.0; }

inline double value_noise(double x, double y, std::uint32_t salt) {
  const double fx = std::floor(x), fy = std::floor(y);
  const auto i = static_cast<std::int32_t>(fx), j = static_cast<std::int32_t>(fy);
  double tx = x - fx, ty = y - fy;
  tx = tx * tx * (3.0 - 2.0 * tx);
  ty = ty * ty * (3.0 - 2.0 * ty);
  const double a = hash01(i, j, salt), b = hash01(i + 1, j, salt), c = hash01(i, j + 1, salt), d = hash01(i + 1, j + 1, salt);
  return (a * (1 - tx) + b * tx) * (1 - ty) + (c * (1 - tx) + d * tx) * ty;
}

struct Seabed {
  double texel_m = 0.004;
  double origin_m = -2.5;  // ground coordinate of texel 0 (both axes)
  int side = 1250;         // texels per side (5 m)
  std::vector<float> tex;

  Seabed() {
    tex.resize(static_cast<std::size_t>(side) * side);
    const double cell = 0.15;
    for (int r = 0; r < side; ++r)
      for (int q = 0; q < side; ++q) {
        const double X = origin_m + q * texel_m, Y = origin_m + r * texel_m;
        double v = 0.45 * value_noise(X / 0.12, Y / 0.12, 1) + 0.2 * value_noise(X / 0.04, Y / 0.04, 2);
        // Hashed rectangle in this cell and its neighbours (they may overlap cell borders).
        const auto ci = static_cast<std::int32_t>(std::floor(X / cell)), cj = static_cast<std::int32_t>(std::floor(Y / cell));
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di) {
            const std::int32_t i = ci + di, j = cj + dj;
            const double mx = (i + hash01(i, j, 3)) * cell, my = (j + hash01(i, j, 4)) * cell;
            const double hx = 0.012 + 0.035 * hash01(i, j, 5), hy = 0.012 + 0.035 * hash01(i, j, 6);
            if (std::abs(X - mx) < hx && std::abs(Y - my) < hy) v = 0.15 + 0.85 * hash01(i, j, 7);
          }
        tex[static_cast<std::size_t>(r) * side + q] = static_cast<float>(30.0 + 190.0 * v);
      }
  }

  double sample(double X, double Y) const {
    const double u = (X - origin_m) / texel_m, v = (Y - origin_m) / texel_m;
    if (!(u >= 0 && v >= 0 && u < side - 1 && v < side - 1)) return 0.0;
    const int q = static_cast<int>(u), r = static_cast<int>(v);
    const double tx = u - q, ty = v - r;
    const float* t = &tex[static_cast<std::size_t>(r) * side + q];
    const double a = static_cast<double>(t[0]), b = static_cast<double>(t[1]), c = static_cast<double>(t[side]),
                 d = static_cast<double>(t[side + 1]);
    return (a * (1 - tx) + b * tx) * (1 - ty) + (c * (1 - tx) + d * tx) * ty;
  }
};

struct CameraPose {
  double x_m = 0.0, y_m = 0.0;  // ground position of the optical axis
  double yaw_rad = 0.0;         // image x axis in the ground frame
  double altitude_m = 2.0;
};

struct Camera {
  int width = 320, height = 240;
  double f = 300.0;
  double cx = 159.5, cy = 119.5;
};

inline void render(const Seabed& s, const Camera& cam, const CameraPose& p, ImageViewU8 out) {
  const double m = p.altitude_m / cam.f, c = std::cos(p.yaw_rad), sn = std::sin(p.yaw_rad);
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      double acc = 0.0;
      for (int k = 0; k < 4; ++k) {
        const double du = u + ((k & 1) ? 0.25 : -0.25) - cam.cx, dv = v + ((k & 2) ? 0.25 : -0.25) - cam.cy;
        acc += s.sample(p.x_m + m * (c * du - sn * dv), p.y_m + m * (sn * du + c * dv));
      }
      const double g = std::round(acc / 4.0);
      out(u, v) = static_cast<std::uint8_t>(g < 0 ? 0 : (g > 255 ? 255 : g));
    }
}

// The test path: forward along the camera's -y (content moves down the image, like the sparus data),
// a slow turn, a small altitude change.
inline CameraPose path_pose(int k) {
  CameraPose p;
  p.yaw_rad = 0.0175 * k;  // ~1 deg per frame
  double x = 0.0, y = 0.0;
  for (int i = 0; i < k; ++i) {
    const double yaw = 0.0175 * i;
    x += 0.04 * std::sin(yaw) + 0.01;  // 4 cm per frame along -y of the camera, 1 cm sideways drift
    y += -0.04 * std::cos(yaw);
  }
  p.x_m = x;
  p.y_m = y;
  p.altitude_m = 2.0 + 0.004 * k;
  return p;
}

// A closed loop for the topological map: a circle of radius_m about the seabed centre, frames_per_lap
// frames a lap, starting at angle 0 and going counter-clockwise in ground axes (X right, Y down);
// the camera looks along its -y axis in the direction of travel (yaw = angle + pi), at a constant
// altitude. Frame k and frame k + frames_per_lap see the same place from the same pose.
inline CameraPose loop_pose(int k, int frames_per_lap, double radius_m = 0.8, double altitude_m = 2.0) {
  const double kTwoPi = 6.283185307179586;
  const double a = kTwoPi * k / frames_per_lap;
  CameraPose p;
  p.x_m = radius_m * std::cos(a);
  p.y_m = radius_m * std::sin(a);
  p.yaw_rad = a + 0.5 * kTwoPi;
  p.altitude_m = altitude_m;
  return p;
}

}  // namespace qnav::sim::downward
