// QNAV_ASSERT: software-bug asserts for every layer (nav/, drivers/, hal/), after F Prime's asserts
// beside its events. A broken invariant inside qnav (an index a stage computed itself out of range, a
// buffer the stage sized itself too small, a state that cannot be reached) is a software fault; an
// input fault (bad checksum, out-of-range field, stale sample) is NOT: it stays a counted event in the
// receiving driver's CounterSet, and never reaches QNAV_ASSERT.
//   if (!QNAV_ASSERT(i < n, "tile index past the builder's ring")) return Status(...);
// The macro evaluates to cond, so the caller still leaves the code path in a defined state.
// What a failure does is set once at start-up, before any thread runs, by set_assert_handler():
//  - qnavd installs SoftwareFaults::record (firmware/qnavd/software_fault.hpp): counted, FaultSoftware
//    raised in QNAV_NAV_STATUS / QNAV_HEALTH, logged; the daemon continues;
//  - with no handler (unit tests, the freestanding LEON3 image) a failure traps at once
//    (__builtin_trap: no libc needed), so a test cannot pass over a bug.
// Freestanding: no OS, no heap, no atomics; O(1).
#pragma once

namespace qnav {

using AssertHandler = void (*)(const char* what, const char* file, int line) noexcept;

namespace detail {
inline AssertHandler g_assert_handler = nullptr;
}  // namespace detail

// Installs the handler (nullptr: trap). Call before starting threads; not thread-safe by design.
inline void set_assert_handler(AssertHandler h) noexcept { detail::g_assert_handler = h; }
inline AssertHandler assert_handler() noexcept { return detail::g_assert_handler; }

[[gnu::cold, gnu::noinline]] inline void assert_failed(const char* what, const char* file, int line) noexcept {
  const AssertHandler h = detail::g_assert_handler;
  if (h == nullptr) __builtin_trap();
  h(what, file, line);
}

}  // namespace qnav

// Evaluates to cond; a false cond is a software fault (see above).
#define QNAV_ASSERT(cond, what) ((cond) ? true : (::qnav::assert_failed((what), __FILE__, __LINE__), false))
