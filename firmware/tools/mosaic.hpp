// A mosaic of downward frames in frame 0's pixel grid (the homography chain's mosaic frame, nav/topo
// ChainPose::H_0_cur), and the few drawing primitives `qnav map` uses to draw the trajectory and the
// topological map over it. Host-side only (qnav map's PNG output); allocates the canvas.
//
// Geometry: the canvas covers the union of the pasted frames' outlines mapped through their H_0_cur,
// plus a margin; when its larger side would exceed max_side pixels the whole canvas is downscaled by
// `scale` (< 1, canvas px per mosaic px) so it fits: the caller says so in the plot's title. A frame
// whose outline maps through a vanishing denominator (w <= 0) is left out of the bounds and not pasted.
// Pasting: inverse warping, each canvas pixel inside the frame's mapped outline -> H_0_cur^-1 -> the
// frame's pixel, bilinear; a later frame covers an earlier one (the newest view is on top).
#pragma once

#include <cstdint>
#include <vector>

#include "nav/core/geometry.hpp"
#include "nav/core/image.hpp"
#include "nav/core/status.hpp"

namespace qnav::tools {

struct MosaicGeometry {
  double x0 = 0.0, y0 = 0.0;  // mosaic coordinates (frame 0 pixels) of canvas pixel (0, 0)'s centre
  double scale = 1.0;         // canvas pixels per mosaic pixel (1, or < 1 when downscaled)
  int width = 0, height = 0;  // canvas size
  bool downscaled() const noexcept { return scale < 1.0; }
  Vec2d to_canvas(const Vec2d& mosaic_px) const noexcept { return Vec2d((mosaic_px.x() - x0) * scale, (mosaic_px.y() - y0) * scale); }
  Vec2d to_mosaic(const Vec2d& canvas_px) const noexcept { return Vec2d(canvas_px.x() / scale + x0, canvas_px.y() / scale + y0); }
};

// The canvas for frames of frame_w x frame_h pixels placed by H_0_cur (one per frame), with `margin`
// mosaic pixels around them and its larger side at most max_side (>= 16). kInvalidArgument without a
// usable frame.
Result<MosaicGeometry> mosaic_geometry(const std::vector<Mat3d>& H_0_cur, int frame_w, int frame_h, int max_side, double margin = 8.0);

// A grey canvas of the geometry's size with a coverage mask (0 = nothing pasted there).
struct MosaicCanvas {
  MosaicGeometry geometry;
  std::vector<std::uint8_t> grey, covered;  // width * height each
  explicit MosaicCanvas(const MosaicGeometry& g)
      : geometry(g), grey(static_cast<std::size_t>(g.width) * static_cast<std::size_t>(g.height), 0),
        covered(grey.size(), 0) {}
  // Pastes `frame` through H_0_cur (see above); false when H is not invertible or maps the frame
  // through a vanishing denominator (nothing pasted).
  bool paste(ConstImageViewU8 frame, const Mat3d& H_0_cur);
  // The canvas as RGB (uncovered pixels light grey), for drawing over.
  std::vector<std::uint8_t> to_rgb() const;
};

// Drawing on an RGB image (width * 3 bytes a row), clipped to it; positions in canvas pixels.
struct RgbColour {
  std::uint8_t r, g, b;
};
void draw_line(std::vector<std::uint8_t>& rgb, int width, int height, const Vec2d& a, const Vec2d& b, RgbColour colour, double thickness = 1.0);
void draw_disc(std::vector<std::uint8_t>& rgb, int width, int height, const Vec2d& centre, double radius, RgbColour colour);
void draw_ring(std::vector<std::uint8_t>& rgb, int width, int height, const Vec2d& centre, double radius, RgbColour colour, double thickness = 1.0);

}  // namespace qnav::tools
