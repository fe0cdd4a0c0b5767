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
  owned_.reset(new (std::nothrow) char[capacity + line_max]);
  if (!owned_) return Status(StatusCode::kCapacityExceeded, "cannot allocate the log ring");
  return open(Span<char>(owned_.get(), capacity + line_max), line_max);
}

Status LogRing::open(Span<char> memory, std::size_t line_max) {
  if (file_ != nullptr) return Status(StatusCode::kInvalidArgument, "log ring already open");
  if (line_max < 64 || memory.size() < 256 + line_max) return Status(StatusCode::kInvalidArgument, "log ring too small");
  const std::size_t capacity = memory.size() - line_max;
  ring_ = memory.data();
  stdio_buf_ = memory.data() + capacity;
  cap_ = capacity;
  cookie_io_functions_t io{};
  io.write = [](void* c, const char* d, std::size_t n) -> ssize_t { return cookie_write(c, d, n); };
  file_ = fopencookie(this, "w", io);
  if (file_ == nullptr) return Status(StatusCode::kIoError, "fopencookie failed");
  if (setvbuf(file_, stdio_buf_, _IOLBF, line_max) != 0) return Status(StatusCode::kIoError, "setvbuf failed");
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
  std::copy(data, data + first, ring_ + at);
  std::copy(data + first, data + size, ring_);
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
    const ssize_t w = ::write(fd, ring_ + at, n);
    if (w < 0) {
      if (errno == EAGAIN || errno == EINTR) return total;
      return -1;
    }
    tail_.store(tail + static_cast<std::size_t>(w), std::memory_order_release);
    total += w;
  }
}

}  // namespace qnav::hal
