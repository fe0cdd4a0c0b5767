// Named error counters. DESIGN.md: every rejected input (bad checksum, out-of-range field, stale
// sample, NaN) increments a named counter that health telemetry publishes. A component declares an
// enum of its counters and a matching table of names; CounterSet stores the counts in a fixed array.
// Counts saturate at UINT32_MAX instead of wrapping. O(1), no heap.
//
//   enum class XtfCounter : std::uint8_t { kBadMagic, kTruncated, kCount };
//   constexpr const char* kXtfCounterNames[] = {"bad_magic", "truncated"};
//   CounterSet<XtfCounter> counters{kXtfCounterNames};
//   counters.increment(XtfCounter::kTruncated);
#pragma once

#include <cstddef>
#include <cstdint>

namespace qnav {

template <typename Enum>
class CounterSet {
 public:
  static constexpr std::size_t kSize = static_cast<std::size_t>(Enum::kCount);

  explicit constexpr CounterSet(const char* const (&names)[kSize]) noexcept : names_(names) {}

  void increment(Enum e, std::uint32_t by = 1) noexcept {
    std::uint32_t& c = counts_[static_cast<std::size_t>(e)];
    c = (c > UINT32_MAX - by) ? UINT32_MAX : c + by;
  }
  std::uint32_t get(Enum e) const noexcept { return counts_[static_cast<std::size_t>(e)]; }
  std::uint32_t count_at(std::size_t i) const noexcept { return i < kSize ? counts_[i] : 0u; }
  const char* name_at(std::size_t i) const noexcept { return i < kSize ? names_[i] : ""; }
  static constexpr std::size_t size() noexcept { return kSize; }
  std::uint64_t total() const noexcept {
    std::uint64_t t = 0;
    for (std::uint32_t c : counts_) t += c;
    return t;
  }
  void reset() noexcept {
    for (std::uint32_t& c : counts_) c = 0;
  }

 private:
  const char* const* names_;
  std::uint32_t counts_[kSize]{};
};

}  // namespace qnav
