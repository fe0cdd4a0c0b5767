// SpscQueue<T, N>: wait-free single-producer single-consumer queue connecting two pipeline stages
// (DESIGN.md "static pipeline"). Exactly one thread calls try_push, exactly one calls try_pop.
// Capacity N must be a power of two; all N slots are usable (indices run freely, wrap by mask).
// try_push on a full queue returns kCapacityExceeded (the producer counts the drop); nothing
// blocks, nothing allocates. O(1) per call. Holds T by value: T should be small or an index into a
// pool owned by the stages.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>

#include "nav/core/status.hpp"

namespace qnav {

template <typename T, std::size_t N>
class SpscQueue {
  static_assert(N >= 2 && (N & (N - 1)) == 0, "SpscQueue capacity must be a power of two");

 public:
  static constexpr std::size_t capacity() noexcept { return N; }

  Status try_push(const T& v) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    const std::size_t head = head_.load(std::memory_order_acquire);
    if (tail - head == N) return Status(StatusCode::kCapacityExceeded, "queue full");
    items_[tail & (N - 1)] = v;
    tail_.store(tail + 1, std::memory_order_release);
    return Status::ok();
  }
  Status try_pop(T& out) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    const std::size_t tail = tail_.load(std::memory_order_acquire);
    if (tail == head) return Status(StatusCode::kEmpty, "queue empty");
    out = items_[head & (N - 1)];
    head_.store(head + 1, std::memory_order_release);
    return Status::ok();
  }
  // Approximate when called concurrently; exact when both sides are quiet.
  std::size_t size() const noexcept {
    return tail_.load(std::memory_order_acquire) - head_.load(std::memory_order_acquire);
  }
  bool empty() const noexcept { return size() == 0; }

 private:
  // Separate cache lines for the two indices so producer and consumer do not false-share.
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
  T items_[N]{};
};

}  // namespace qnav
