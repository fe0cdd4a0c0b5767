// Allocation guard for tests: proves "no heap after init" (DESIGN.md, fixed allocation).
// Linking qnav_test_support replaces global operator new/delete (all forms) and, on dynamically
// linked glibc hosts without sanitizers, malloc/calloc/realloc/free (not posix_memalign/aligned_alloc),
// with versions that count every call before forwarding to the real allocator. Counting covers all
// threads.
//
//   qnav::test::AllocationGuard guard;          // snapshot the counters
//   pipeline.step(frame);                        // the region under test
//   EXPECT_EQ(guard.allocations(), 0u) << guard.report();
//
// or QNAV_EXPECT_NO_ALLOC(statement);
// malloc_counted() tells whether malloc-level counting is active in this build (it is not under
// ASan, which owns malloc, nor in static builds such as leon3, where glibc's malloc cannot be
// interposed); operator new is counted everywhere.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#ifdef EIGEN_RUNTIME_NO_MALLOC
#include <Eigen/Core>
#endif

namespace qnav::test {

// While one exists, Eigen's own run-time check (EIGEN_RUNTIME_NO_MALLOC, compiled into Debug builds)
// asserts on any Eigen heap allocation, in every thread; a no-op in builds without the check.
#ifdef EIGEN_RUNTIME_NO_MALLOC
class EigenMallocForbidden {
 public:
  EigenMallocForbidden() noexcept : was_(Eigen::internal::is_malloc_allowed()) { Eigen::internal::set_is_malloc_allowed(false); }
  ~EigenMallocForbidden() { Eigen::internal::set_is_malloc_allowed(was_); }
  EigenMallocForbidden(const EigenMallocForbidden&) = delete;
  EigenMallocForbidden& operator=(const EigenMallocForbidden&) = delete;

 private:
  bool was_;
};
#else
class EigenMallocForbidden {
 public:
  EigenMallocForbidden() noexcept {}  // user-provided: an instance is not an "unused variable"
  ~EigenMallocForbidden() {}
  EigenMallocForbidden(const EigenMallocForbidden&) = delete;
  EigenMallocForbidden& operator=(const EigenMallocForbidden&) = delete;
};
#endif

struct AllocationCounts {
  std::uint64_t news = 0;     // operator new / new[] calls
  std::uint64_t deletes = 0;  // operator delete / delete[] calls with a non-null pointer
  std::uint64_t mallocs = 0;  // malloc / calloc / realloc / aligned allocations (when counted)
  std::uint64_t frees = 0;
};

AllocationCounts allocation_counts() noexcept;
// Bytes asked of operator new so far (every form, every thread).
std::size_t new_bytes() noexcept;
// Counts, from now on, the operator new calls of exactly n bytes (0 = off): a test that a block of a
// known size was allocated once.
void watch_new_size(std::size_t n) noexcept;
std::size_t watched_new_count() noexcept;
bool malloc_counted() noexcept;

class AllocationGuard {
 public:
  AllocationGuard() noexcept : start_(allocation_counts()) {}
  // Allocations (new + malloc) since construction.
  std::uint64_t allocations() const noexcept;
  std::uint64_t deallocations() const noexcept;
  std::string report() const;

 private:
  AllocationCounts start_;
};

}  // namespace qnav::test

#define QNAV_EXPECT_NO_ALLOC(statement)                                                                         \
  do {                                                                                                          \
    ::qnav::test::AllocationGuard qnav_alloc_guard_;                                                            \
    {                                                                                                           \
      ::qnav::test::EigenMallocForbidden qnav_no_eigen_malloc_;                                                 \
      statement;                                                                                                \
    }                                                                                                           \
    const auto qnav_allocs_ = qnav_alloc_guard_.allocations();                                                  \
    EXPECT_EQ(qnav_allocs_, 0u) << "heap allocation in: " #statement " (" << qnav_alloc_guard_.report() << ")"; \
  } while (0)
