#include "firmware/tools/raster_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "firmware/tools/plot_font.hpp"
#include "firmware/tools/png_writer.hpp"

namespace qnav::tools {
namespace {

// An RGB canvas, white at start; every drawing call clips to it.
class Canvas {
 public:
  Canvas(int w, int h, int text_scale)
      : w_(w), h_(h), s_(text_scale), px_(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 3, 255) {}
  int width() const { return w_; }
  int height() const { return h_; }
  int char_w() const { return kPlotFontWidth * s_; }
  int char_h() const { return kPlotFontHeight * s_; }
  const std::uint8_t* data() const { return px_.data(); }

  void blend(int x, int y, int grey, int alpha) {
    if (x < 0 || y < 0 || x >= w_ || y >= h_ || alpha <= 0) return;
    std::uint8_t* p = px_.data() + (static_cast<std::size_t>(y) * static_cast<std::size_t>(w_) + static_cast<std::size_t>(x)) * 3;
    for (int k = 0; k < 3; ++k) p[k] = static_cast<std::uint8_t>((p[k] * (255 - alpha) + grey * alpha + 127) / 255);
  }
  void set(int x, int y, int grey) { blend(x, y, grey, 255); }
  void fill(int x0, int y0, int w, int h, int grey) {
    for (int y = y0; y < y0 + h; ++y)
      for (int x = x0; x < x0 + w; ++x) set(x, y, grey);
  }
  void set_rgb(int x, int y, const std::uint8_t* rgb) {
    if (x < 0 || y < 0 || x >= w_ || y >= h_) return;
    std::uint8_t* p = px_.data() + (static_cast<std::size_t>(y) * static_cast<std::size_t>(w_) + static_cast<std::size_t>(x)) * 3;
    p[0] = rgb[0];
    p[1] = rgb[1];
    p[2] = rgb[2];
  }
  // Black text; left edge x, top y. rotated: reads bottom to top, (x, y) is then the bottom-left.
  void text(int x, int y, const std::string& t, bool rotated = false) {
    for (std::size_t i = 0; i < t.size(); ++i) {
      int code = static_cast<unsigned char>(t[i]);
      if (code < kPlotFontFirst || code >= kPlotFontFirst + kPlotFontGlyphs) code = '?';
      const auto& g = kPlotFontCoverage[code - kPlotFontFirst];
      const int off = static_cast<int>(i) * char_w();
      for (int gy = 0; gy < kPlotFontHeight * s_; ++gy)
        for (int gx = 0; gx < kPlotFontWidth * s_; ++gx) {
          const int a = g[gy / s_][gx / s_];
          if (rotated) blend(x + gy, y - off - gx, 0, a);
          else blend(x + off + gx, y + gy, 0, a);
        }
    }
  }
  int text_w(const std::string& t) const { return static_cast<int>(t.size()) * char_w(); }

 private:
  int w_, h_, s_;
  std::vector<std::uint8_t> px_;
};

struct Tick {
  int pos;  // canvas column (x axis) or row (y axis)
  std::string label;
};

// Ticks of an axis over n pixels starting at canvas coordinate `start`.
std::vector<Tick> ticks_of(const PlotAxis& a, int n, int start, int target) {
  std::vector<Tick> out;
  if (n <= 0 || !(a.per_px != 0.0) || !std::isfinite(a.per_px) || !std::isfinite(a.first)) return out;
  const double v0 = a.first - 0.5 * a.per_px, v1 = a.first + (n - 0.5) * a.per_px;
  const double lo = std::min(v0, v1), hi = std::max(v0, v1);
  const double step = nice_step(hi - lo, target);
  for (double k = std::ceil(lo / step); k * step <= hi + 1e-9 * step; k += 1.0) {
    const double v = k * step;
    const int p = static_cast<int>(std::floor((v - a.first) / a.per_px + 0.5));
    if (p < 0 || p >= n) continue;
    out.push_back(Tick{start + p, tick_label(v, step)});
  }
  return out;
}

}  // namespace

double nice_step(double span, int target) noexcept {
  if (!(span > 0.0) || !std::isfinite(span)) return 1.0;
  const double raw = span / std::max(1, target);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / mag;
  return (f < 1.5 ? 1.0 : f < 3.5 ? 2.0 : f < 7.5 ? 5.0 : 10.0) * mag;
}

std::string tick_label(double value, double step) {
  int decimals = 0;
  if (step > 0.0 && std::isfinite(step)) decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
  if (decimals > 6) decimals = 6;
  const double unit = std::pow(10.0, -decimals);
  if (std::fabs(value) < 0.5 * unit) value = 0.0;  // no "-0"
  char b[48];
  std::snprintf(b, sizeof b, "%.*f", decimals, value);
  return b;
}

namespace {

// The plot around a w x h image whose pixel (c, r) is rgb_at(c, r) (3 bytes).
template <typename RgbAt>
Status write_plot(const char* path, int w, int h, RgbAt rgb_at, const RasterPlot& plot) {
  const int s = std::max(w, h) > 1500 ? 2 : 1;
  const int cw = kPlotFontWidth * s, ch = kPlotFontHeight * s, tick = 5 * s, pad = 8 * s;

  // Ticks first (their labels size the margins), at canvas offset 0; shifted once the margins are known.
  std::vector<Tick> xt = ticks_of(plot.x, w, 0, std::max(3, w / (90 * s)));
  std::vector<Tick> yt = ticks_of(plot.y, h, 0, std::max(3, h / (60 * s)));
  int ylab_w = 0;
  for (const Tick& t : yt) ylab_w = std::max(ylab_w, static_cast<int>(t.label.size()) * cw);
  const bool colour = plot.colour_bar && plot.colour_hi > plot.colour_lo;
  std::vector<std::string> clabels;
  double cstep = 1.0;
  int clab_w = 0;
  const int arrow_h = plot.north_arrow ? ch + 30 * s + pad : 0;  // "N" over the arrow, then a gap
  const int bar_h = h - arrow_h;
  if (colour && bar_h > 2 * ch) {
    cstep = nice_step(plot.colour_hi - plot.colour_lo, std::max(2, bar_h / (60 * s)));
    for (double k = std::ceil(plot.colour_lo / cstep); k * cstep <= plot.colour_hi + 1e-9 * cstep; k += 1.0)
      clab_w = std::max(clab_w, static_cast<int>(tick_label(k * cstep, cstep).size()) * cw);
  }
  const bool draw_bar = colour && bar_h > 2 * ch;
  int right = pad;
  if (plot.north_arrow) right = std::max(right, pad + std::max(cw, 14 * s) + pad);
  if (draw_bar) right = std::max(right, pad + 16 * s + tick + 3 * s + clab_w + pad + (plot.colour_label.empty() ? 0 : ch + pad));
  const int left = pad + (plot.y.label.empty() ? 0 : ch + pad) + ylab_w + 3 * s + tick;
  const int top = pad + (plot.title.empty() ? 0 : ch + pad);
  const int scale_h = plot.scale_bar ? ch + 6 * s + pad : 0;
  const int bottom = tick + 3 * s + ch + (plot.x.label.empty() ? 0 : pad + ch) + scale_h + pad;
  // Labels longer than the image side run on into the margins: the canvas grows to hold them.
  const int title_w = static_cast<int>(plot.title.size()) * cw;
  const int xlab_w = static_cast<int>(plot.x.label.size()) * cw;
  // (The x label goes under the ends of rotated labels longer than the image is high.)
  const int xlab_x = std::max(left, left + (w - xlab_w) / 2);
  const int ylab_len = static_cast<int>(plot.y.label.size()) * cw;
  const int clab_len = draw_bar ? static_cast<int>(plot.colour_label.size()) * cw : 0;
  const int xlab_y = std::max({top + h + 1 + tick + 3 * s + ch + pad, top + ylab_len + pad, top + arrow_h + clab_len + pad});
  const int W = std::max({left + w + right, pad + title_w + pad, xlab_x + xlab_w + pad});
  const int H = std::max(top + h + bottom, xlab_y + (plot.x.label.empty() ? 0 : ch) + scale_h + pad);
  Canvas cv(W, H, s);
  const int x0 = left, y0 = top;

  if (!plot.title.empty()) cv.text(pad, pad, plot.title);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) cv.set_rgb(x0 + c, y0 + r, rgb_at(c, r));
  // Frame just outside the data.
  cv.fill(x0 - 1, y0 - 1, w + 2, 1, 0);
  cv.fill(x0 - 1, y0 + h, w + 2, 1, 0);
  cv.fill(x0 - 1, y0 - 1, 1, h + 2, 0);
  cv.fill(x0 + w, y0 - 1, 1, h + 2, 0);
  // x ticks and labels (a label that would overlap the previous one is left out).
  int last_end = -1000000;
  for (const Tick& t : xt) {
    const int x = x0 + t.pos;
    cv.fill(x, y0 + h + 1, s, tick, 0);
    const int lx = std::min(std::max(x - cv.text_w(t.label) / 2, 0), W - cv.text_w(t.label));
    if (lx <= last_end + cw) continue;
    cv.text(lx, y0 + h + 1 + tick + 3 * s, t.label);
    last_end = lx + cv.text_w(t.label);
  }
  if (!plot.x.label.empty())
    cv.text(xlab_x, xlab_y, plot.x.label);
  int last_row = -1000000;
  for (const Tick& t : yt) {
    const int y = y0 + t.pos;
    cv.fill(x0 - 1 - tick, y, tick, s, 0);
    const int ly = std::min(std::max(y - ch / 2, 0), H - ch);
    if (std::abs(ly - last_row) < ch) continue;
    cv.text(x0 - 1 - tick - 3 * s - cv.text_w(t.label), ly, t.label);
    last_row = ly;
  }
  if (!plot.y.label.empty())
    cv.text(pad, y0 + std::max(ylab_len, (h + ylab_len) / 2) - 1, plot.y.label, true);
  // Scale bar: under the x label, left-aligned with the image, about a fifth of its width.
  if (plot.scale_bar && plot.x.per_px != 0.0) {
    const double m_per_px = std::fabs(plot.x.per_px);
    const double want = 0.2 * w * m_per_px;
    double len = nice_step(want, 1);
    if (len > want) len = nice_step(want / 2.0, 1);
    const int bar = static_cast<int>(std::lround(len / m_per_px));
    const int by = H - pad - ch;
    cv.fill(x0, by + ch / 2 - 2 * s, bar, 4 * s, 0);
    cv.fill(x0, by + 2 * s, s, ch - 4 * s, 0);
    cv.fill(x0 + bar - s, by + 2 * s, s, ch - 4 * s, 0);
    cv.text(x0 + bar + 4 * s, by, tick_label(len, len) + " m");
  }
  const int rx = x0 + w + 1 + pad;  // the right-hand column
  if (plot.north_arrow) {
    const int ax = rx + std::max(cw, 14 * s) / 2;
    cv.text(ax - cw / 2, y0, "N");
    const int tip = y0 + ch + 2 * s, len = 30 * s, head = 10 * s;
    for (int dy = 0; dy < head; ++dy) {
      const int half = dy * 6 * s / head;
      cv.fill(ax - half, tip + dy, 2 * half + 1, 1, 0);
    }
    cv.fill(ax - s, tip + head, 2 * s + 1, len - head, 0);
  }
  if (draw_bar) {
    const int by = y0 + arrow_h, bw = 16 * s;
    for (int r = 0; r < bar_h; ++r) {
      const double t = 1.0 - static_cast<double>(r) / std::max(1, bar_h - 1);
      std::uint8_t col[3];
      if (plot.colour_map == PlotColourMap::kGrey) {
        const std::uint8_t g = static_cast<std::uint8_t>(std::lround(255.0 * t));
        col[0] = col[1] = col[2] = g;
      } else {
        plot_colour(plot.colour_map, t, col);
      }
      for (int x = 0; x < bw; ++x) cv.set_rgb(rx + x, by + r, col);
    }
    cv.fill(rx - 1, by - 1, bw + 2, 1, 0);
    cv.fill(rx - 1, by + bar_h, bw + 2, 1, 0);
    cv.fill(rx - 1, by - 1, 1, bar_h + 2, 0);
    cv.fill(rx + bw, by - 1, 1, bar_h + 2, 0);
    int last = -1000000;
    for (double k = std::ceil(plot.colour_lo / cstep); k * cstep <= plot.colour_hi + 1e-9 * cstep; k += 1.0) {
      const double f = (k * cstep - plot.colour_lo) / (plot.colour_hi - plot.colour_lo);
      const int y = by + static_cast<int>(std::lround((1.0 - f) * (bar_h - 1)));
      cv.fill(rx + bw + 1, y, tick, s, 0);
      const int ly = std::min(std::max(y - ch / 2, 0), H - ch);
      if (std::abs(ly - last) < ch) continue;
      cv.text(rx + bw + 1 + tick + 3 * s, ly, tick_label(k * cstep, cstep));
      last = ly;
    }
    if (!plot.colour_label.empty())
      cv.text(rx + bw + 1 + tick + 3 * s + clab_w + pad, by + std::max(clab_len, (bar_h + clab_len) / 2) - 1, plot.colour_label, true);
  }
  return write_png_rgb8(path, cv.data(), W, H, W * 3);
}

}  // namespace

void plot_colour(PlotColourMap map, double t, std::uint8_t rgb[3]) noexcept {
  t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
  if (map == PlotColourMap::kBlueGreenRed) {
    rgb[0] = static_cast<std::uint8_t>(255 * t);
    rgb[1] = static_cast<std::uint8_t>(255 * (1 - std::fabs(2 * t - 1)));
    rgb[2] = static_cast<std::uint8_t>(255 * (1 - t));
    return;
  }
  rgb[0] = rgb[1] = rgb[2] = static_cast<std::uint8_t>(std::lround(255.0 * t));
}

Status write_raster_plot_png(const char* path, ConstImageViewU8 image, const RasterPlot& plot) {
  if (image.empty()) return Status(StatusCode::kInvalidArgument, "plot: empty image");
  std::uint8_t px[3];
  return write_plot(path, image.width(), image.height(),
                    [&](int c, int r) {
                      px[0] = px[1] = px[2] = image.row(r)[c];
                      return static_cast<const std::uint8_t*>(px);
                    },
                    plot);
}

Status write_raster_plot_png_rgb(const char* path, const std::uint8_t* rgb, int width, int height, int stride_bytes,
                                 const RasterPlot& plot) {
  if (rgb == nullptr || width <= 0 || height <= 0 || stride_bytes < width * 3)
    return Status(StatusCode::kInvalidArgument, "plot: bad rgb buffer");
  return write_plot(path, width, height,
                    [&](int c, int r) { return rgb + static_cast<std::ptrdiff_t>(r) * stride_bytes + 3 * c; }, plot);
}

}  // namespace qnav::tools
