// RingBuffer<T, N>: fixed-capacity FIFO for one thread (history windows, belief windows, recent
// samples). push() on a full buffer returns kCapacityExceeded and changes nothing;
// push_overwrite() drops the oldest element instead and says so. All operations O(1), no heap.
// Index 0 is the oldest element.
#pragma once

#include <cstddef>

#include "nav/core/status.hpp"

namespace qnav {

template <typename T, std::size_t N>
class RingBuffer {
  static_assert(N > 0, "RingBuffer needs a capacity");

 public:
  static constexpr std::size_t capacity() noexcept { return N; }
  std::size_t size() const noexcept { return size_; }
  bool empty() const noexcept { return size_ == 0; }
  bool full() const noexcept { return size_ == N; }

  Status push(const T& v) noexcept {
    if (full()) return Status(StatusCode::kCapacityExceeded, "ring buffer full");
    items_[(head_ + size_) % N] = v;
    ++size_;
    return Status::ok();
  }
  // Returns true when an old element was overwritten.
  bool push_overwrite(const T& v) noexcept {
    if (full()) {
      items_[head_] = v;
      head_ = (head_ + 1) % N;
      return true;
    }
    items_[(head_ + size_) % N] = v;
    ++size_;
    return false;
  }
  Status pop(T& out) noexcept {
    if (empty()) return Status(StatusCode::kEmpty, "ring buffer empty");
    out = items_[head_];
    head_ = (head_ + 1) % N;
    --size_;
    return Status::ok();
  }
  // i-th element counted from the oldest; nullptr when i >= size().
  T* at(std::size_t i) noexcept { return i < size_ ? &items_[(head_ + i) % N] : nullptr; }
  const T* at(std::size_t i) const noexcept { return i < size_ ? &items_[(head_ + i) % N] : nullptr; }
  T* newest() noexcept { return empty() ? nullptr : at(size_ - 1); }
  void clear() noexcept { head_ = size_ = 0; }

 private:
  T items_[N]{};
  std::size_t head_ = 0;
  std::size_t size_ = 0;
};

}  // namespace qnav
