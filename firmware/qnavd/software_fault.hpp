// The daemon's channel for software bugs, apart from input faults (F Prime's asserts vs events).
// An input fault (bad checksum, stale sample, out-of-range field) is expected in the field and goes
// to a driver's named counter. A software fault is a broken invariant inside qnav (a stage refusing
// an input the pipeline already validated, an arena sized too small, a queue slot that is not ours):
// QNAVD_CHECK(cond, what) records it (count, first and last message, file:line), raises the
// FaultSoftware bit in QNAV_NAV_STATUS / QNAV_HEALTH, logs it, and lets the daemon continue in a
// defined state instead of aborting the vehicle's navigation. Tests turn any such record into a
// failure. Lock-free; no heap. The first/last records are separate atomics: with faults in two
// threads at once a record may mix their fields (the count is exact).
#pragma once

#include <atomic>
#include <cstdint>

namespace qnav::daemon {

struct SoftwareFaultRecord {
  const char* what = nullptr;
  const char* file = nullptr;
  int line = 0;
};

class SoftwareFaults {
 public:
  static void record(const char* what, const char* file, int line) noexcept;
  static std::uint32_t count() noexcept;
  static SoftwareFaultRecord first() noexcept;
  static SoftwareFaultRecord last() noexcept;
  static void reset_for_tests() noexcept;
};

}  // namespace qnav::daemon

// Evaluates to cond; records a software fault when it is false.
#define QNAVD_CHECK(cond, what) \
  ((cond) ? true : (::qnav::daemon::SoftwareFaults::record((what), __FILE__, __LINE__), false))
