// A raster as a person reads it: the tool's one way to draw an image with its axes (every command
// that writes a picture for a person calls this; the bare rasters stay write_png_* in png_writer.hpp).
// The image is copied pixel for pixel into a white frame; around it, outside the data, go the title,
// ticks with values on both axes and their labels (units in the label), and as asked: a scale bar
// (axes in metres at one scale), a north arrow (image up is north) and a colour bar (grey level means
// a value: lo at black, hi at white). Nothing is drawn over the data. Text is DejaVu Sans Mono 11 px
// (plot_font.hpp), twice that for images over 1500 px a side. Host-side only; allocates the canvas.
#pragma once

#include <cstdint>
#include <string>

#include "nav/core/image.hpp"
#include "nav/core/status.hpp"

namespace qnav::tools {

// One axis: the value at the centre of pixel 0 (column 0 / row 0) and the change per pixel
// (negative when the value falls along the axis, e.g. north down the rows of a north-up raster).
struct PlotAxis {
  double first = 0.0;
  double per_px = 1.0;
  std::string label;  // with the unit, e.g. "east m"
};

// How a value maps to colour in the colour bar (and in the image, where the caller paints with it).
enum class PlotColourMap : std::uint8_t {
  kGrey,          // black (lo) .. white (hi)
  kBlueGreenRed,  // blue (lo) .. green .. red (hi): points painted over a grey image
};
// The colour of t in [0, 1] (clamped) under `map`, as 8-bit RGB.
void plot_colour(PlotColourMap map, double t, std::uint8_t rgb[3]) noexcept;

struct RasterPlot {
  std::string title;
  PlotAxis x, y;
  bool scale_bar = false;   // x in metres (and y at the same scale): a scale bar under the image
  bool north_arrow = false; // the image is north-up: an arrow to the right of the image
  bool colour_bar = false;  // grey level means a value: a bar from colour_lo (black) to colour_hi (white)
  double colour_lo = 0.0, colour_hi = 1.0;
  std::string colour_label;
  PlotColourMap colour_map = PlotColourMap::kGrey;
};

// A "nice" tick step (1, 2 or 5 x 10^k) giving about `target` intervals over `span` (> 0).
double nice_step(double span, int target) noexcept;
// The tick label of `value` on a grid of `step`: as many decimals as the step needs, no "-0".
std::string tick_label(double value, double step);

// Writes the annotated raster as an 8-bit RGB PNG (atomically, like write_png_rgb8).
Status write_raster_plot_png(const char* path, ConstImageViewU8 image, const RasterPlot& plot);
// The same for an RGB image (width * 3 bytes a row, row stride in bytes given).
Status write_raster_plot_png_rgb(const char* path, const std::uint8_t* rgb, int width, int height, int stride_bytes,
                                 const RasterPlot& plot);

}  // namespace qnav::tools
