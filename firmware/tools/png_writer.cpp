#include "firmware/tools/png_writer.hpp"

#include <png.h>

#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <string>
#include <vector>

namespace qnav::tools {
namespace {

struct PngErrorState {
  std::jmp_buf jump;
};

void on_png_error(png_structp png, png_const_charp) {
  auto* st = static_cast<PngErrorState*>(png_get_error_ptr(png));
  std::longjmp(st->jump, 1);
}
void on_png_warning(png_structp, png_const_charp) {}

// rows[i] points at row i; color_type PNG_COLOR_TYPE_GRAY or PNG_COLOR_TYPE_RGB.
Status write_rows(const char* path, const std::uint8_t* const* rows, int width, int height, int color_type) noexcept {
  if (path == nullptr || width <= 0 || height <= 0) return Status(StatusCode::kInvalidArgument, "png: bad arguments");
  const std::string tmp = std::string(path) + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (f == nullptr) return Status(StatusCode::kIoError, "png: cannot open output file");
  PngErrorState st;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &st, on_png_error, on_png_warning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (png == nullptr || info == nullptr) {
    png_destroy_write_struct(&png, &info);
    std::fclose(f);
    std::remove(tmp.c_str());
    return Status(StatusCode::kIoError, "png: cannot create writer");
  }
  if (setjmp(st.jump)) {
    png_destroy_write_struct(&png, &info);
    std::fclose(f);
    std::remove(tmp.c_str());
    return Status(StatusCode::kIoError, "png: write failed");
  }
  png_init_io(png, f);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), 8, color_type,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < height; ++y) png_write_row(png, rows[y]);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  if (std::fclose(f) != 0) {
    std::remove(tmp.c_str());
    return Status(StatusCode::kIoError, "png: close failed");
  }
  if (std::rename(tmp.c_str(), path) != 0) {
    std::remove(tmp.c_str());
    return Status(StatusCode::kIoError, "png: rename failed");
  }
  return Status::ok();
}

}  // namespace

Status write_png_gray8(const char* path, ConstImageViewU8 image) noexcept {
  if (image.empty()) return Status(StatusCode::kInvalidArgument, "png: empty image");
  std::vector<const std::uint8_t*> rows(static_cast<std::size_t>(image.height()));
  for (int y = 0; y < image.height(); ++y) rows[static_cast<std::size_t>(y)] = image.row(y);
  return write_rows(path, rows.data(), image.width(), image.height(), PNG_COLOR_TYPE_GRAY);
}

Status write_png_rgb8(const char* path, const std::uint8_t* rgb, int width, int height, int stride_bytes) noexcept {
  if (rgb == nullptr || width <= 0 || height <= 0 || stride_bytes < width * 3)
    return Status(StatusCode::kInvalidArgument, "png: bad rgb buffer");
  std::vector<const std::uint8_t*> rows(static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y)
    rows[static_cast<std::size_t>(y)] = rgb + static_cast<std::ptrdiff_t>(y) * stride_bytes;
  return write_rows(path, rows.data(), width, height, PNG_COLOR_TYPE_RGB);
}

std::vector<std::uint8_t> gray8_from_float(ConstImageViewF32 image, float lo, float hi) {
  std::vector<std::uint8_t> px;
  if (image.empty() || !(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi)) return px;
  const std::size_t w = static_cast<std::size_t>(image.width());
  px.resize(w * static_cast<std::size_t>(image.height()));
  const float scale = 255.0f / (hi - lo);
  for (int y = 0; y < image.height(); ++y) {
    const float* s = image.row(y);
    std::uint8_t* d = px.data() + static_cast<std::size_t>(y) * w;
    for (std::size_t x = 0; x < w; ++x) {
      float v = std::isnan(s[x]) ? 0.0f : (s[x] - lo) * scale;
      v = v < 0.0f ? 0.0f : (v > 255.0f ? 255.0f : v);
      d[x] = static_cast<std::uint8_t>(v + 0.5f);
    }
  }
  return px;
}

Status write_png_float(const char* path, ConstImageViewF32 image, float lo, float hi) noexcept {
  if (image.empty()) return Status(StatusCode::kInvalidArgument, "png: empty image");
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi))
    return Status(StatusCode::kInvalidArgument, "png: bad range");
  const std::vector<std::uint8_t> px = gray8_from_float(image, lo, hi);
  auto view = ConstImageViewU8::make(px.data(), image.width(), image.height());
  if (!view) return view.status();
  return write_png_gray8(path, *view);
}

}  // namespace qnav::tools
