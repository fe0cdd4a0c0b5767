#include "firmware/tools/mosaic.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/LU>

namespace qnav::tools {

namespace {

// H applied to (x, y); false when the denominator is not clearly positive.
bool map_point(const Mat3d& H, double x, double y, Vec2d& out) {
  const double w = H(2, 0) * x + H(2, 1) * y + H(2, 2);
  if (!(w > 1e-9)) return false;
  out = Vec2d((H(0, 0) * x + H(0, 1) * y + H(0, 2)) / w, (H(1, 0) * x + H(1, 1) * y + H(1, 2)) / w);
  return out.allFinite();
}

// The outline of a w x h frame (pixel centres 0 .. w-1) mapped through H: min / max corners.
bool outline(const Mat3d& H, int w, int h, Vec2d& lo, Vec2d& hi) {
  lo = Vec2d::Constant(std::numeric_limits<double>::infinity());
  hi = -lo;
  const double xs[2] = {-0.5, w - 0.5}, ys[2] = {-0.5, h - 0.5};
  for (double x : xs)
    for (double y : ys) {
      Vec2d p;
      if (!map_point(H, x, y, p)) return false;
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  return true;
}

void put(std::vector<std::uint8_t>& rgb, int width, int height, int x, int y, RgbColour c) {
  if (x < 0 || y < 0 || x >= width || y >= height) return;
  std::uint8_t* p = &rgb[(static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)) * 3];
  p[0] = c.r;
  p[1] = c.g;
  p[2] = c.b;
}

}  // namespace

Result<MosaicGeometry> mosaic_geometry(const std::vector<Mat3d>& H_0_cur, int frame_w, int frame_h, int max_side, double margin) {
  if (frame_w <= 0 || frame_h <= 0 || max_side < 16 || !(margin >= 0.0))
    return Status(StatusCode::kInvalidArgument, "mosaic: bad frame size, canvas limit or margin");
  Vec2d lo = Vec2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  bool any = false;
  for (const Mat3d& H : H_0_cur) {
    Vec2d a, b;
    if (!H.allFinite() || !outline(H, frame_w, frame_h, a, b)) continue;
    lo = lo.cwiseMin(a);
    hi = hi.cwiseMax(b);
    any = true;
  }
  if (!any) return Status(StatusCode::kInvalidArgument, "mosaic: no frame with a usable homography");
  lo -= Vec2d::Constant(margin);
  hi += Vec2d::Constant(margin);
  const double span = std::max(hi.x() - lo.x(), hi.y() - lo.y());
  MosaicGeometry g;
  g.scale = span > max_side ? max_side / span : 1.0;
  g.x0 = std::floor(lo.x());
  g.y0 = std::floor(lo.y());
  g.width = std::min(max_side, static_cast<int>(std::ceil((hi.x() - g.x0) * g.scale)) + 1);
  g.height = std::min(max_side, static_cast<int>(std::ceil((hi.y() - g.y0) * g.scale)) + 1);
  return g;
}

bool MosaicCanvas::paste(ConstImageViewU8 frame, const Mat3d& H_0_cur) {
  const MosaicGeometry& g = geometry;
  const int fw = frame.width(), fh = frame.height();
  Vec2d lo, hi;
  if (frame.empty() || !H_0_cur.allFinite() || !outline(H_0_cur, fw, fh, lo, hi)) return false;
  const Eigen::FullPivLU<Mat3d> lu(H_0_cur);
  if (!lu.isInvertible()) return false;
  const Mat3d Hinv = lu.inverse();
  const Vec2d clo = g.to_canvas(lo), chi = g.to_canvas(hi);
  const int c0 = std::max(0, static_cast<int>(std::floor(clo.x()))), c1 = std::min(g.width - 1, static_cast<int>(std::ceil(chi.x())));
  const int r0 = std::max(0, static_cast<int>(std::floor(clo.y()))), r1 = std::min(g.height - 1, static_cast<int>(std::ceil(chi.y())));
  for (int r = r0; r <= r1; ++r)
    for (int c = c0; c <= c1; ++c) {
      const Vec2d m = g.to_mosaic(Vec2d(c, r));
      Vec2d f;
      if (!map_point(Hinv, m.x(), m.y(), f)) continue;
      if (!(f.x() >= 0.0 && f.y() >= 0.0 && f.x() <= fw - 1 && f.y() <= fh - 1)) continue;
      const int x = std::min(static_cast<int>(f.x()), fw - 2), y = std::min(static_cast<int>(f.y()), fh - 2);
      const double tx = f.x() - x, ty = f.y() - y;
      const std::uint8_t* a = frame.row(y) + x;
      const std::uint8_t* b = frame.row(y + 1) + x;
      const double v = (a[0] * (1 - tx) + a[1] * tx) * (1 - ty) + (b[0] * (1 - tx) + b[1] * tx) * ty;
      const std::size_t i = static_cast<std::size_t>(r) * static_cast<std::size_t>(g.width) + static_cast<std::size_t>(c);
      grey[i] = static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 255.0)));
      covered[i] = 1;
    }
  return true;
}

std::vector<std::uint8_t> MosaicCanvas::to_rgb() const {
  std::vector<std::uint8_t> rgb(grey.size() * 3);
  for (std::size_t i = 0; i < grey.size(); ++i) {
    const std::uint8_t v = covered[i] ? grey[i] : 235;
    rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = v;
  }
  return rgb;
}

void draw_disc(std::vector<std::uint8_t>& rgb, int width, int height, const Vec2d& centre, double radius, RgbColour colour) {
  const int x0 = static_cast<int>(std::floor(centre.x() - radius)), x1 = static_cast<int>(std::ceil(centre.x() + radius));
  const int y0 = static_cast<int>(std::floor(centre.y() - radius)), y1 = static_cast<int>(std::ceil(centre.y() + radius));
  for (int y = std::max(0, y0); y <= std::min(height - 1, y1); ++y)
    for (int x = std::max(0, x0); x <= std::min(width - 1, x1); ++x)
      if ((Vec2d(x, y) - centre).squaredNorm() <= radius * radius) put(rgb, width, height, x, y, colour);
}

void draw_ring(std::vector<std::uint8_t>& rgb, int width, int height, const Vec2d& centre, double radius, RgbColour colour, double thickness) {
  const double ro = radius + 0.5 * thickness, ri = std::max(0.0, radius - 0.5 * thickness);
  const int x0 = static_cast<int>(std::floor(centre.x() - ro)), x1 = static_cast<int>(std::ceil(centre.x() + ro));
  const int y0 = static_cast<int>(std::floor(centre.y() - ro)), y1 = static_cast<int>(std::ceil(centre.y() + ro));
  for (int y = std::max(0, y0); y <= std::min(height - 1, y1); ++y)
    for (int x = std::max(0, x0); x <= std::min(width - 1, x1); ++x) {
      const double d2 = (Vec2d(x, y) - centre).squaredNorm();
      if (d2 <= ro * ro && d2 >= ri * ri) put(rgb, width, height, x, y, colour);
    }
}

void draw_line(std::vector<std::uint8_t>& rgb, int width, int height, const Vec2d& a_in, const Vec2d& b_in, RgbColour colour, double thickness) {
  if (!a_in.allFinite() || !b_in.allFinite()) return;
  // Clip the segment to the image grown by the line's half width (Liang-Barsky): bounded work.
  const double r = 0.5 * thickness, lo_x = -r - 1.0, lo_y = -r - 1.0, hi_x = width + r, hi_y = height + r;
  const Vec2d d = b_in - a_in;
  double t0 = 0.0, t1 = 1.0;
  const double p[4] = {-d.x(), d.x(), -d.y(), d.y()};
  const double q[4] = {a_in.x() - lo_x, hi_x - a_in.x(), a_in.y() - lo_y, hi_y - a_in.y()};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0.0) {
      if (q[i] < 0.0) return;
      continue;
    }
    const double t = q[i] / p[i];
    if (p[i] < 0.0) t0 = std::max(t0, t);
    else t1 = std::min(t1, t);
  }
  if (t0 > t1) return;
  const Vec2d a = a_in + t0 * d, b = a_in + t1 * d;
  const int steps = std::max(1, static_cast<int>(std::ceil((b - a).norm() * 2.0)));
  for (int i = 0; i <= steps; ++i) {
    const Vec2d pt = a + (b - a) * (static_cast<double>(i) / steps);
    if (r <= 0.75) put(rgb, width, height, static_cast<int>(std::lround(pt.x())), static_cast<int>(std::lround(pt.y())), colour);
    else draw_disc(rgb, width, height, pt, r, colour);
  }
}

}  // namespace qnav::tools
