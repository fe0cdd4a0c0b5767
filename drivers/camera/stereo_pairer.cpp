#include "drivers/camera/stereo_pairer.hpp"
#include "nav/core/assert.hpp"

namespace qnav::drivers::camera {

std::uint32_t StereoPairer::queued_slots(Side side) const noexcept {
  std::uint32_t m = 0;
  const auto& q = q_[static_cast<int>(side)];
  for (std::size_t i = 0; i < q.size(); ++i) m |= 1u << q.at(i)->slot;
  return m;
}

bool StereoPairer::push(Side side, const FrameRef& f, PairRef& out, std::uint8_t* dropped, std::size_t& n_dropped) noexcept {
  n_dropped = 0;
  const int s = static_cast<int>(side);
  const int o = 1 - s;
  if (have_last_[s] && f.stamp.sample_ns <= last_ns_[s]) {
    counters_.increment(PairCounter::kOutOfOrder);
    dropped[n_dropped++] = f.slot;
    return false;
  }
  have_last_[s] = true;
  last_ns_[s] = f.stamp.sample_ns;
  auto& other = q_[o];
  // Closest partner in the other queue.
  std::size_t best = other.size();
  std::int64_t best_dt = 0;
  for (std::size_t i = 0; i < other.size(); ++i) {
    std::int64_t dt = other.at(i)->stamp.sample_ns - f.stamp.sample_ns;
    if (dt < 0) dt = -dt;
    if (dt <= tolerance_ns_ && (best == other.size() || dt < best_dt)) {
      best = i;
      best_dt = dt;
    }
  }
  if (best < other.size()) {
    FrameRef partner;
    for (std::size_t i = 0; i < best; ++i) {  // older than the partner: can never pair now
      FrameRef old;
      other.pop(old).ignore();
      dropped[n_dropped++] = old.slot;
      counters_.increment(PairCounter::kUnmatched);
    }
    other.pop(partner).ignore();
    out.left = side == Side::kLeft ? f : partner;
    out.right = side == Side::kLeft ? partner : f;
    out.skew_ns = out.right.stamp.sample_ns - out.left.stamp.sample_ns;
    ++pairs_;
    return true;
  }
  // No partner: frames on the other side older than f - tolerance can never pair (this side only
  // gets later frames from now on).
  while (!other.empty() && other.at(0)->stamp.sample_ns < f.stamp.sample_ns - tolerance_ns_) {
    FrameRef old;
    other.pop(old).ignore();
    dropped[n_dropped++] = old.slot;
    counters_.increment(PairCounter::kUnmatched);
  }
  auto& mine = q_[s];
  if (mine.full()) {
    FrameRef old;
    mine.pop(old).ignore();
    dropped[n_dropped++] = old.slot;
    counters_.increment(PairCounter::kUnmatched);
  }
  QNAV_ASSERT(mine.push(f).is_ok(), "stereo pairer: push on a side queue just made non-full");
  return false;
}

}  // namespace qnav::drivers::camera
