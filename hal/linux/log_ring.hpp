// LogRing: the log stream of a thread that must never block on its output (qnavd's io and nav
// threads). stream() is a FILE* (glibc fopencookie) for ordinary fprintf calls, line-buffered in a
// buffer sized at open(); its write callback copies each line into a single-producer single-consumer
// byte ring and returns at once. drain(fd), called by another thread (qnavd's main thread), writes
// what the ring holds to fd, only as much as fd takes without blocking (poll POLLOUT, chunks of at
// most PIPE_BUF). A line that does not fit in the ring is dropped whole and counted
// (dropped_lines()): a full journald pipe costs log lines, never a deadline.
// Memory: open() allocates the ring, the stdio buffer and the FILE; writing and draining allocate
// nothing. One producer thread per LogRing (the FILE's own lock serialises a shared use anyway).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>

#include "nav/core/span.hpp"

#include "nav/core/status.hpp"

namespace qnav::hal {

class LogRing {
 public:
  LogRing() noexcept = default;
  ~LogRing();
  LogRing(const LogRing&) = delete;
  LogRing& operator=(const LogRing&) = delete;

  // capacity: bytes the ring holds (a power of two is not required); line_max: the stdio buffer (a
  // longer line is handed over in pieces).
  Status open(std::size_t capacity, std::size_t line_max = 4096);
  // The same over caller memory (qnavd: its static block) that outlives the ring: the ring takes
  // memory.size() - line_max bytes, the stdio buffer line_max. Only the FILE is allocated (by glibc).
  Status open(Span<char> memory, std::size_t line_max);
  FILE* stream() const noexcept { return file_; }
  // Consumer side: writes pending bytes to fd without blocking; returns the bytes written. -1 on a
  // write error (the bytes stay in the ring).
  long drain(int fd) noexcept;
  std::size_t pending() const noexcept;
  std::uint64_t dropped_lines() const noexcept { return dropped_.load(std::memory_order_relaxed); }

 private:
  static long cookie_write(void* self, const char* data, std::size_t size) noexcept;
  long push(const char* data, std::size_t size) noexcept;

  std::unique_ptr<char[]> owned_;  // open(capacity, ...): the ring + the stdio buffer
  char* ring_ = nullptr;
  char* stdio_buf_ = nullptr;
  std::size_t cap_ = 0;
  std::atomic<std::size_t> head_{0};  // total bytes written (producer)
  std::atomic<std::size_t> tail_{0};  // total bytes drained (consumer)
  std::atomic<std::uint64_t> dropped_{0};
  FILE* file_ = nullptr;
};

}  // namespace qnav::hal
