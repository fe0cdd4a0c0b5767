// SpscRing<T>: the runtime-sized form of SpscQueue (spsc_queue.hpp) for queues whose depth comes from
// the configuration: a wait-free single-producer single-consumer ring over caller-owned storage
// (sized once at start-up; a power of two). try_push on a full ring returns kCapacityExceeded and
// the producer counts the drop; nothing blocks, nothing allocates. O(1) per call.
#pragma once

#include <atomic>
#include <cstddef>

#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav {

template <typename T>
class SpscRing {
 public:
  // storage.size() must be a power of two >= 2.
  Status init(Span<T> storage) noexcept {
    const std::size_t n = storage.size();
    if (n < 2 || (n & (n - 1)) != 0) return Status(StatusCode::kInvalidArgument, "spsc ring: capacity must be a power of two >= 2");
    items_ = storage;
    mask_ = n - 1;
    head_.store(0, std::memory_order_relaxed);
    tail_.store(0, std::memory_order_relaxed);
    return Status::ok();
  }
  std::size_t capacity() const noexcept { return items_.size(); }
  Status try_push(const T& v) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    const std::size_t head = head_.load(std::memory_order_acquire);
    if (items_.size() == 0 || tail - head == items_.size()) return Status(StatusCode::kCapacityExceeded, "queue full");
    items_[tail & mask_] = v;
    tail_.store(tail + 1, std::memory_order_release);
    return Status::ok();
  }
  Status try_pop(T& out) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    const std::size_t tail = tail_.load(std::memory_order_acquire);
    if (tail == head) return Status(StatusCode::kEmpty, "queue empty");
    out = items_[head & mask_];
    head_.store(head + 1, std::memory_order_release);
    return Status::ok();
  }
  // Consumer only: the oldest item without removing it (nullptr when empty).
  const T* front() const noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    const std::size_t tail = tail_.load(std::memory_order_acquire);
    return tail == head ? nullptr : &items_[head & mask_];
  }
  // Approximate when called concurrently; exact when both sides are quiet.
  std::size_t size() const noexcept {
    const std::size_t head = head_.load(std::memory_order_acquire);  // head first: tail can only have grown since
    return tail_.load(std::memory_order_acquire) - head;
  }

 private:
  Span<T> items_;
  std::size_t mask_ = 0;
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
};

}  // namespace qnav
