// SpscQueue<T, N>: wait-free single-producer single-consumer queue connecting two pipeline stages
// (DESIGN.md "static pipeline"). Exactly one thread calls try_push, exactly one calls try_pop.
// Capacity N must be a power of two; all N slots are usable (indices run freely, wrap by mask).
// try_push on a full queue returns kCapacityExceeded (the producer counts the drop); nothing
// blocks, nothing allocates. O(1) per call. Holds T by value: T should be small or an index into a
// pool owned by the stages.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/span.hpp"
#include "nav/core/spsc_ring.hpp"
#include "nav/core/status.hpp"

namespace qnav {

template <typename T, std::size_t N>
class SpscQueue {
  static_assert(N >= 2 && (N & (N - 1)) == 0, "SpscQueue capacity must be a power of two");

 public:
  SpscQueue() noexcept { static_cast<void>(ring_.init(Span<T>(items_, N))); }  // cannot fail: N is checked above
  SpscQueue(const SpscQueue&) = delete;
  SpscQueue& operator=(const SpscQueue&) = delete;
  static constexpr std::size_t capacity() noexcept { return N; }

  Status try_push(const T& v) noexcept { return ring_.try_push(v); }
  Status try_pop(T& out) noexcept { return ring_.try_pop(out); }
  // Approximate when called concurrently; exact when both sides are quiet.
  std::size_t size() const noexcept { return ring_.size(); }
  bool empty() const noexcept { return size() == 0; }

 private:
  T items_[N]{};
  SpscRing<T> ring_;  // the indices (on their own cache lines) over items_
};

}  // namespace qnav
