#include "nav/vision/downsample.hpp"

namespace qnav::vision {

namespace {

template <typename T>
Status check(ImageView<const T> src, int factor, ImageView<T> dst) noexcept {
  if (src.empty() || dst.empty()) return Status(StatusCode::kInvalidArgument, "downsample: empty image");
  if (factor < 1 || factor > 16) return Status(StatusCode::kInvalidArgument, "downsample: factor must be 1..16");
  if (src.width() < factor || src.height() < factor)
    return Status(StatusCode::kInvalidArgument, "downsample: source smaller than the factor");
  if (dst.width() != src.width() / factor || dst.height() != src.height() / factor)
    return Status(StatusCode::kInvalidArgument, "downsample: destination size must be source / factor");
  return Status::ok();
}

}  // namespace

Status downsample(ConstImageViewU8 src, int factor, ImageViewU8 dst) noexcept {
  QNAV_RETURN_IF_ERROR(check(src, factor, dst));
  const int ow = dst.width(), oh = dst.height();
  const unsigned n = static_cast<unsigned>(factor * factor);
  const unsigned half = n / 2;
  if (factor == 1) return copy_pixels(src, dst);
  if (factor == 2) {
    for (int y = 0; y < oh; ++y) {
      const std::uint8_t* __restrict a = src.row(2 * y);
      const std::uint8_t* __restrict b = src.row(2 * y + 1);
      std::uint8_t* __restrict o = dst.row(y);
      for (int x = 0; x < ow; ++x)
        o[x] = static_cast<std::uint8_t>((a[2 * x] + a[2 * x + 1] + b[2 * x] + b[2 * x + 1] + 2u) >> 2);
    }
    return Status::ok();
  }
  // General factor: per output row, sum the factor source rows into column sums (vectorisable, in
  // chunks of kChunk source columns on the stack), then sum groups of factor columns.
  // Sums fit in 16 bits: 16 * 16 * 255 < 65536.
  constexpr int kChunk = 1024;
  std::uint16_t col[kChunk];
  const int per_chunk = (kChunk / factor) * factor;  // whole blocks per chunk
  for (int y = 0; y < oh; ++y) {
    std::uint8_t* __restrict o = dst.row(y);
    for (int c0 = 0; c0 < ow * factor; c0 += per_chunk) {
      const int n_src = (ow * factor - c0) < per_chunk ? (ow * factor - c0) : per_chunk;
      const std::uint8_t* __restrict r0 = src.row(y * factor) + c0;
      for (int i = 0; i < n_src; ++i) col[i] = r0[i];
      for (int j = 1; j < factor; ++j) {
        const std::uint8_t* __restrict rj = src.row(y * factor + j) + c0;
        for (int i = 0; i < n_src; ++i) col[i] = static_cast<std::uint16_t>(col[i] + rj[i]);
      }
      const int x0 = c0 / factor, nx = n_src / factor;
      if (factor == 4) {
        for (int x = 0; x < nx; ++x)
          o[x0 + x] = static_cast<std::uint8_t>((col[4 * x] + col[4 * x + 1] + col[4 * x + 2] + col[4 * x + 3] + 8u) >> 4);
      } else {
        for (int x = 0; x < nx; ++x) {
          unsigned sum = 0;
          for (int i = 0; i < factor; ++i) sum += col[x * factor + i];
          o[x0 + x] = static_cast<std::uint8_t>((sum + half) / n);
        }
      }
    }
  }
  return Status::ok();
}

Status downsample(ConstImageViewF32 src, int factor, ImageViewF32 dst) noexcept {
  QNAV_RETURN_IF_ERROR(check(src, factor, dst));
  const float inv = 1.0f / static_cast<float>(factor * factor);
  for (int y = 0; y < dst.height(); ++y) {
    float* o = dst.row(y);
    for (int x = 0; x < dst.width(); ++x) {
      float s = 0.0f;
      for (int j = 0; j < factor; ++j) {
        const float* r = src.row(y * factor + j) + x * factor;
        for (int i = 0; i < factor; ++i) s += r[i];
      }
      o[x] = s * inv;
    }
  }
  return Status::ok();
}

Status ImagePyramid::init(const PyramidConfig& config, Arena& arena) noexcept {
  ready_ = false;
  if (config.max_width < 8 || config.max_height < 8 || config.max_width > kMaxImageSide ||
      config.max_height > kMaxImageSide)
    return Status(StatusCode::kInvalidArgument, "pyramid: max size out of range");
  if (config.levels < 1 || config.levels > kMaxLevels) return Status(StatusCode::kInvalidArgument, "pyramid: levels must be 1..8");
  for (int i = 0; i < kMaxLevels; ++i) storage_[i] = Span<std::uint8_t>();
  for (int i = 0; i < config.levels; ++i) {
    const int w = config.max_width >> i, h = config.max_height >> i;
    if (w < 8 || h < 8) break;
    storage_[i] = arena.allocate<std::uint8_t>(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
    if (storage_[i].empty()) return Status(StatusCode::kCapacityExceeded, "pyramid: arena too small");
  }
  config_ = config;
  ready_ = true;
  built_ = 0;
  return Status::ok();
}

Status ImagePyramid::build(ConstImageViewU8 image) noexcept {
  built_ = 0;
  if (!ready_) return Status(StatusCode::kNotReady, "pyramid: build before init");
  if (image.empty()) return Status(StatusCode::kInvalidArgument, "pyramid: empty image");
  if (image.width() > config_.max_width || image.height() > config_.max_height)
    return Status(StatusCode::kInvalidArgument, "pyramid: image larger than configured");
  for (int i = 0; i < config_.levels; ++i) {
    const int w = image.width() >> i, h = image.height() >> i;
    if (w < 8 || h < 8 || storage_[i].empty()) break;
    views_[i] = ImageViewU8::unchecked(storage_[i].data(), w, h, w);
    if (i == 0) {
      QNAV_RETURN_IF_ERROR(copy_pixels(image, views_[0]));
    } else {
      // Level i-1 may be one pixel wider/taller than 2 * level i (odd sizes): downsample a sub-view.
      const ConstImageViewU8 prev = ConstImageViewU8::unchecked(views_[i - 1].data(), 2 * w, 2 * h, views_[i - 1].stride());
      QNAV_RETURN_IF_ERROR(downsample(prev, 2, views_[i]));
    }
    built_ = i + 1;
  }
  return Status::ok();
}

ConstImageViewU8 ImagePyramid::level(int i) const noexcept {
  if (i < 0 || i >= built_) return ConstImageViewU8();
  return ConstImageViewU8(views_[i]);
}

}  // namespace qnav::vision
