// StereoPairer: matches left and right frames by sample time. A frame pairs with the opposite
// side's queued frame closest in time when |t_left - t_right| <= tolerance_ns; queued frames older
// than that partner are dropped (they can no longer pair). A frame that finds no partner waits in
// its side's queue (kDepth); frames that can never pair are dropped and counted `unmatched`; a frame
// older than its side's previous one is rejected and counted `out_of_order`.
// The pairer moves only small FrameRefs (slot index + stamps); pixels stay in the caller's slots.
// Worst case per push: O(kDepth). No heap.
#pragma once

#include <cstdint>

#include "hal/core/stamp.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/ring_buffer.hpp"

namespace qnav::drivers::camera {

enum class Side : std::uint8_t { kLeft = 0, kRight = 1 };

struct FrameRef {
  std::uint32_t sequence = 0;
  hal::SampleStamp stamp;
  std::uint8_t slot = 0;
};

struct PairRef {
  FrameRef left;
  FrameRef right;
  std::int64_t skew_ns = 0;  // right - left sample time
};

enum class PairCounter : std::uint8_t { kUnmatched, kOutOfOrder, kCount };
inline constexpr const char* kPairCounterNames[] = {"unmatched", "out_of_order"};

class StereoPairer {
 public:
  static constexpr std::size_t kDepth = 4;
  explicit StereoPairer(std::int64_t tolerance_ns) noexcept : tolerance_ns_(tolerance_ns) {}

  // Returns true when `out` holds a new pair. `dropped_slots` receives the slot ids of frames the
  // call dropped (so the caller can reuse them); its capacity must be >= kDepth + 1.
  bool push(Side side, const FrameRef& f, PairRef& out, std::uint8_t* dropped_slots, std::size_t& n_dropped) noexcept;
  // Slots currently waiting in the queues (bit i = slot i of that side).
  std::uint32_t queued_slots(Side side) const noexcept;
  const CounterSet<PairCounter>& counters() const noexcept { return counters_; }
  std::uint32_t pairs() const noexcept { return pairs_; }

 private:
  std::int64_t tolerance_ns_;
  RingBuffer<FrameRef, kDepth> q_[2];
  bool have_last_[2] = {false, false};
  std::int64_t last_ns_[2] = {0, 0};
  CounterSet<PairCounter> counters_{kPairCounterNames};
  std::uint32_t pairs_ = 0;
};

}  // namespace qnav::drivers::camera
