#include "hal/sim/pgm_sequence_camera.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <new>

namespace qnav::hal {

namespace {
bool is_space(std::uint8_t c) noexcept { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }
// Reads one header integer, skipping whitespace and '#' comments.
bool header_int(const std::uint8_t* p, std::size_t n, std::size_t& i, int& v) noexcept {
  for (;;) {
    while (i < n && is_space(p[i])) ++i;
    if (i < n && p[i] == '#') {
      while (i < n && p[i] != '\n') ++i;
      continue;
    }
    break;
  }
  long long x = 0;
  int digits = 0;
  while (i < n && p[i] >= '0' && p[i] <= '9' && digits < 9) x = x * 10 + (p[i++] - '0'), ++digits;
  if (digits == 0 || (i < n && p[i] >= '0' && p[i] <= '9')) return false;
  v = static_cast<int>(x);
  return true;
}
}  // namespace

bool expand_sequence_pattern(const char* pattern, int index, char* out, std::size_t cap) noexcept {
  if (pattern == nullptr || out == nullptr || cap == 0 || index < 0) return false;
  std::size_t k = 0;
  bool done = false;
  for (const char* p = pattern; *p; ++p) {
    if (*p != '%') {
      if (k + 1 >= cap) return false;
      out[k++] = *p;
      continue;
    }
    ++p;
    if (*p == '%') {
      if (k + 1 >= cap) return false;
      out[k++] = '%';
      continue;
    }
    if (done) return false;  // exactly one conversion
    bool zero = false;
    if (*p == '0') zero = true, ++p;
    int width = 0;
    while (*p >= '0' && *p <= '9' && width < 20) width = width * 10 + (*p++ - '0');
    if (*p != 'd') return false;
    char digits[12];
    int nd = 0;
    int v = index;
    do {
      digits[nd++] = static_cast<char>('0' + v % 10);
      v /= 10;
    } while (v > 0 && nd < 11);
    for (int pad = nd; pad < width; ++pad) {
      if (k + 1 >= cap) return false;
      out[k++] = zero ? '0' : ' ';
    }
    while (nd > 0) {
      if (k + 1 >= cap) return false;
      out[k++] = digits[--nd];
    }
    done = true;
  }
  out[k] = '\0';
  return done;
}

Status parse_pgm_header(const std::uint8_t* p, std::size_t n, int& width, int& height, std::size_t& offset) noexcept {
  if (p == nullptr || n < 2 || p[0] != 'P' || p[1] != '5') return Status(StatusCode::kCorrupt, "not a binary PGM (P5)");
  std::size_t i = 2;
  int maxval = 0;
  if (!header_int(p, n, i, width) || !header_int(p, n, i, height) || !header_int(p, n, i, maxval))
    return Status(StatusCode::kCorrupt, "bad PGM header");
  if (i >= n || !is_space(p[i])) return Status(StatusCode::kCorrupt, "PGM header not terminated");
  if (maxval != 255) return Status(StatusCode::kUnsupported, "only 8-bit PGM (maxval 255)");
  if (width <= 0 || height <= 0 || width > kMaxImageSide || height > kMaxImageSide)
    return Status(StatusCode::kCorrupt, "PGM size out of range");
  offset = i + 1;
  return Status::ok();
}

Result<std::size_t> PgmSequenceCamera::read_file(int index) noexcept {
  char path[512];
  if (!expand_sequence_pattern(config_.pattern, config_.first + index, path, sizeof path))
    return Status(StatusCode::kInvalidArgument, "bad sequence pattern or path too long");
  const int fd = ::open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return Status(StatusCode::kNotFound, "sequence file missing");
  std::size_t got = 0;
  while (got < cap_) {
    const ssize_t r = ::read(fd, buf_.get() + got, cap_ - got);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) break;
    got += static_cast<std::size_t>(r);
  }
  ::close(fd);
  return got;
}

Status PgmSequenceCamera::open(const PgmSequenceConfig& c) {
  if (c.pattern == nullptr || c.count <= 0) return Status(StatusCode::kInvalidArgument, "pattern and count required");
  if (!c.stamps.empty() && c.stamps.size() < static_cast<std::size_t>(c.count))
    return Status(StatusCode::kInvalidArgument, "fewer stamps than frames");
  config_ = c;
  next_ = 0;
  stats_ = CameraStats{};
  cap_ = 4096;  // enough for any header
  buf_.reset(new (std::nothrow) std::uint8_t[cap_]);
  if (!buf_) return Status(StatusCode::kCapacityExceeded, "no memory");
  auto r = read_file(0);
  if (!r.is_ok()) return r.status();
  int wdt = 0, hgt = 0;
  std::size_t off = 0;
  QNAV_RETURN_IF_ERROR(parse_pgm_header(buf_.get(), r.value(), wdt, hgt, off));
  format_ = CameraFormat{wdt, hgt, PixelFormat::kGrey, wdt};
  cap_ = 4096 + static_cast<std::size_t>(wdt) * static_cast<std::size_t>(hgt);
  buf_.reset(new (std::nothrow) std::uint8_t[cap_]);
  if (!buf_) return Status(StatusCode::kCapacityExceeded, "no memory");
  return Status::ok();
}

Result<CameraFrameInfo> PgmSequenceCamera::capture(ImageView<std::uint8_t> out, int /*timeout_ms*/) noexcept {
  if (!buf_) return Status(StatusCode::kNotReady, "sequence not open");
  if (next_ >= config_.count) return Status(StatusCode::kEmpty, "end of sequence");
  const int i = next_++;
  CameraFrameInfo info;
  info.sequence = static_cast<std::uint32_t>(i);
  info.stamp.sample_ns = config_.stamps.empty() ? config_.start_ns + config_.period_ns * i : config_.stamps[static_cast<std::size_t>(i)];
  info.stamp.arrival_ns = info.stamp.sample_ns;
  auto r = read_file(i);
  if (!r.is_ok()) {
    ++stats_.corrupt;
    return r.status();
  }
  int wdt = 0, hgt = 0;
  std::size_t off = 0;
  const Status h = parse_pgm_header(buf_.get(), r.value(), wdt, hgt, off);
  if (!h.is_ok() || wdt != format_.width || hgt != format_.height ||
      r.value() < off + static_cast<std::size_t>(wdt) * static_cast<std::size_t>(hgt)) {
    ++stats_.corrupt;
    return h.is_ok() ? Status(StatusCode::kCorrupt, "PGM size differs from the sequence or file truncated") : h;
  }
  if (out.width() != wdt || out.height() != hgt) return Status(StatusCode::kInvalidArgument, "output view has another size");
  for (int y = 0; y < hgt; ++y) std::memcpy(out.row(y), buf_.get() + off + static_cast<std::size_t>(y) * static_cast<std::size_t>(wdt), static_cast<std::size_t>(wdt));
  ++stats_.frames;
  return info;
}

}  // namespace qnav::hal
