// Images: ImageView<T> is a non-owning view (pointer, width, height, stride in elements) over pixels
// someone else owns; Image<T> owns its pixels, allocated once (at start-up) from the heap or from
// an Arena, and never reallocated. nav/ stages take views, so the same code runs on driver buffers,
// file buffers and arena buffers. Pixel types: std::uint8_t (8-bit grey) and float.
// make() validates dimensions and stride and returns an error rather than a view that lies.
// Coordinates: x = column (0..width-1), y = row (0..height-1), row-major, origin top-left.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <type_traits>

#include "nav/core/arena.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/status.hpp"

namespace qnav {

// Largest accepted image side, pixels. Guards size arithmetic on 32-bit targets and absurd inputs.
constexpr int kMaxImageSide = 16384;

template <typename T>
class ImageView {
 public:
  ImageView() noexcept = default;

  static Result<ImageView> make(T* data, int width, int height, std::ptrdiff_t stride) noexcept {
    if (data == nullptr) return Status(StatusCode::kInvalidArgument, "image data is null");
    if (width <= 0 || height <= 0) return Status(StatusCode::kInvalidArgument, "image has zero or negative size");
    if (width > kMaxImageSide || height > kMaxImageSide)
      return Status(StatusCode::kInvalidArgument, "image side too large");
    if (stride < width) return Status(StatusCode::kInvalidArgument, "image stride smaller than width");
    return ImageView(data, width, height, stride);
  }
  static Result<ImageView> make(T* data, int width, int height) noexcept { return make(data, width, height, width); }

  T* data() const noexcept { return data_; }
  int width() const noexcept { return width_; }
  int height() const noexcept { return height_; }
  std::ptrdiff_t stride() const noexcept { return stride_; }
  bool empty() const noexcept { return data_ == nullptr; }
  std::size_t pixel_count() const noexcept {
    return static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
  }
  bool contains(int x, int y) const noexcept { return x >= 0 && y >= 0 && x < width_ && y < height_; }

  T* row(int y) const noexcept { return data_ + static_cast<std::ptrdiff_t>(y) * stride_; }
  // Unchecked access for validated loops.
  T& operator()(int x, int y) const noexcept { return row(y)[x]; }
  // Checked access: nullptr outside the image.
  T* at(int x, int y) const noexcept { return contains(x, y) ? &row(y)[x] : nullptr; }

  // A view of a rectangle inside this image (the rectangle is clipped to the image first).
  Result<ImageView> sub(RectI r) const noexcept {
    const RectI c = r.intersect(RectI{0, 0, width_, height_});
    if (c.empty()) return Status(StatusCode::kOutOfRange, "sub-image outside the image");
    return ImageView(data_ + static_cast<std::ptrdiff_t>(c.y) * stride_ + c.x, c.width, c.height, stride_);
  }

  // Read-only view of the same pixels.
  // U is deduced from the target type, so it is pinned to T: a view converts only to the read-only
  // view of the same pixel type (never, say, u8 to const float), and a const view has no conversion.
  template <typename U, typename = std::enable_if_t<std::is_same<U, T>::value && !std::is_const<U>::value>>
  operator ImageView<const U>() const noexcept {  // NOLINT
    return ImageView<const U>::unchecked(data_, width_, height_, stride_);
  }

  // For conversions and sub-views whose arguments are already validated.
  static ImageView unchecked(T* data, int width, int height, std::ptrdiff_t stride) noexcept {
    return ImageView(data, width, height, stride);
  }

 private:
  ImageView(T* data, int width, int height, std::ptrdiff_t stride) noexcept
      : data_(data), width_(width), height_(height), stride_(stride) {}
  T* data_ = nullptr;
  int width_ = 0;
  int height_ = 0;
  std::ptrdiff_t stride_ = 0;
};

// Owning image, tightly packed (stride == width). Move-only. Allocated once.
template <typename T>
class Image {
 public:
  Image() noexcept = default;
  Image(Image&&) noexcept = default;
  Image& operator=(Image&&) noexcept = default;
  Image(const Image&) = delete;
  Image& operator=(const Image&) = delete;

  // One heap allocation (start-up only). Pixels are zero-initialised.
  static Result<Image> allocate(int width, int height) noexcept {
    const Status s = check_size(width, height);
    if (!s) return s;
    const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    std::unique_ptr<T[]> mem(new (std::nothrow) T[n]());
    if (!mem) return Status(StatusCode::kCapacityExceeded, "out of memory for image");
    Image img;
    img.view_ = ImageView<T>::unchecked(mem.get(), width, height, width);
    img.heap_ = std::move(mem);
    return img;
  }
  // From an arena: no heap at all. Pixels are zero-initialised.
  static Result<Image> allocate(Arena& arena, int width, int height) noexcept {
    const Status s = check_size(width, height);
    if (!s) return s;
    Span<T> px = arena.allocate<T>(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
    if (px.empty()) return Status(StatusCode::kCapacityExceeded, "arena too small for image");
    Image img;
    img.view_ = ImageView<T>::unchecked(px.data(), width, height, width);
    return img;
  }

  ImageView<T> view() noexcept { return view_; }
  ImageView<const T> view() const noexcept { return ImageView<const T>(view_); }
  int width() const noexcept { return view_.width(); }
  int height() const noexcept { return view_.height(); }
  T* data() noexcept { return view_.data(); }
  const T* data() const noexcept { return view_.data(); }
  T& operator()(int x, int y) noexcept { return view_(x, y); }
  const T& operator()(int x, int y) const noexcept { return view_(x, y); }
  bool empty() const noexcept { return view_.empty(); }

 private:
  static Status check_size(int width, int height) noexcept {
    if (width <= 0 || height <= 0) return Status(StatusCode::kInvalidArgument, "image has zero or negative size");
    if (width > kMaxImageSide || height > kMaxImageSide)
      return Status(StatusCode::kInvalidArgument, "image side too large");
    return Status::ok();
  }
  ImageView<T> view_;
  std::unique_ptr<T[]> heap_;
};

using ImageViewU8 = ImageView<std::uint8_t>;
using ConstImageViewU8 = ImageView<const std::uint8_t>;
using ImageViewF32 = ImageView<float>;
using ConstImageViewF32 = ImageView<const float>;
using ImageU8 = Image<std::uint8_t>;
using ImageF32 = Image<float>;

// Copies pixels between views of the same size. Returns kInvalidArgument on a size mismatch.
template <typename T>
Status copy_pixels(ImageView<const T> src, ImageView<T> dst) noexcept {
  if (src.width() != dst.width() || src.height() != dst.height())
    return Status(StatusCode::kInvalidArgument, "image sizes differ");
  for (int y = 0; y < src.height(); ++y) {
    const T* s = src.row(y);
    T* d = dst.row(y);
    for (int x = 0; x < src.width(); ++x) d[x] = s[x];
  }
  return Status::ok();
}

}  // namespace qnav
