#include "hal/linux/log_ring.hpp"

#include <errno.h>
#include <limits.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <new>

namespace qnav::hal {

LogRing::~LogRing() {
  if (file_ != nullptr) std::fclose(file_);
}

Status LogRing::open(std::size_t capacity, std::size_t line_max) {
  if (capacity < 256 || line_max < 64) return Status(StatusCode::kInvalidArgument, "log ring too small");
  ring_.reset(new (std::nothrow) char[capacity]);
  stdio_buf_.reset(new (std::nothrow) char[line_max]);
  if (!ring_ || !stdio_buf_) return Status(StatusCode::kCapacityExceeded, "cannot allocate the log ring");
  cap_ = capacity;
  cookie_io_functions_t io{};
  io.write = [](void* c, const char* d, std::size_t n) -> ssize_t { return cookie_write(c, d, n); };
  file_ = fopencookie(this, "w", io);
  if (file_ == nullptr) return Status(StatusCode::kIoError, "fopencookie failed");
  if (setvbuf(file_, stdio_buf_.get(), _IOLBF, line_max) != 0) return Status(StatusCode::kIoError, "setvbuf failed");
  return Status::ok();
}

long LogRing::cookie_write(void* self, const char* data, std::size_t size) noexcept {
  return static_cast<LogRing*>(self)->push(data, size);
}

long LogRing::push(const char* data, std::size_t size) noexcept {
  const std::size_t head = head_.load(std::memory_order_relaxed);
  const std::size_t tail = tail_.load(std::memory_order_acquire);
  if (size > cap_ - (head - tail)) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return static_cast<long>(size);  // dropped, but stdio must not see an error (it would stop writing)
  }
  const std::size_t at = head % cap_;
  const std::size_t first = std::min(size, cap_ - at);
  std::copy(data, data + first, ring_.get() + at);
  std::copy(data + first, data + size, ring_.get());
  head_.store(head + size, std::memory_order_release);
  return static_cast<long>(size);
}

std::size_t LogRing::pending() const noexcept {
  return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_relaxed);
}

long LogRing::drain(int fd) noexcept {
  long total = 0;
  for (;;) {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    const std::size_t head = head_.load(std::memory_order_acquire);
    if (head == tail) return total;
    pollfd p{fd, POLLOUT, 0};
    if (::poll(&p, 1, 0) <= 0 || !(p.revents & POLLOUT)) return total;  // would block: next time
    const std::size_t at = tail % cap_;
    const std::size_t n = std::min<std::size_t>({head - tail, cap_ - at, static_cast<std::size_t>(PIPE_BUF)});
    const ssize_t w = ::write(fd, ring_.get() + at, n);
    if (w < 0) {
      if (errno == EAGAIN || errno == EINTR) return total;
      return -1;
    }
    tail_.store(tail + static_cast<std::size_t>(w), std::memory_order_release);
    total += w;
  }
}

}  // namespace qnav::hal
