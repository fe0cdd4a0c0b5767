#include "test/support/alloc_guard.hpp"

#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <vector>

#include "nav/core/fixed_vector.hpp"

namespace qnav {
namespace {

// The optimiser may delete a new/delete pair whose pointer never escapes (gcc does at -O2 and
// above); storing the pointer in a volatile keeps the allocation observable.
void* volatile g_escape = nullptr;

// The guard must catch an allocation, or the "no heap after init" tests built on it prove nothing.
TEST(AllocationGuard, CatchesOperatorNew) {
  test::AllocationGuard g;
  auto p = std::make_unique<int>(3);
  g_escape = p.get();
  EXPECT_EQ(g.allocations(), 1u) << g.report();
  p.reset();
  EXPECT_EQ(g.deallocations(), 1u);
}

TEST(AllocationGuard, CatchesContainerGrowth) {
  std::vector<int> v;
  test::AllocationGuard g;
  for (int i = 0; i < 100; ++i) v.push_back(i);
  EXPECT_GE(g.allocations(), 2u) << g.report();
}

TEST(AllocationGuard, CatchesMallocWhereMallocIsCounted) {
  if (!test::malloc_counted()) GTEST_SKIP() << "malloc is not interposable in this build (sanitizer or static)";
  test::AllocationGuard g;
  void* p = std::malloc(64);
  g_escape = p;
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(g.allocations(), 1u) << g.report();
  std::free(p);
  EXPECT_EQ(g.deallocations(), 1u);
}

TEST(AllocationGuard, FixedContainersDoNotAllocate) {
  FixedVector<int, 64> v;
  QNAV_EXPECT_NO_ALLOC({
    for (int i = 0; i < 100; ++i) v.push_back(i).ignore();
  });
  EXPECT_EQ(v.size(), 64u);
}

// The macro reports a failure when the region allocates (checked with a nested expectation).
TEST(AllocationGuard, NoAllocMacroFailsOnAllocation) {
  EXPECT_NONFATAL_FAILURE(QNAV_EXPECT_NO_ALLOC({
                            auto p = std::make_unique<double>(1.0);
                            g_escape = p.get();
                          }),
                          "heap allocation in");
}

}  // namespace
}  // namespace qnav

#ifdef EIGEN_RUNTIME_NO_MALLOC
// Debug builds compile Eigen's run-time check: a dynamic Eigen allocation inside a no-allocation
// region asserts (QNAV_EXPECT_NO_ALLOC regions use EigenMallocForbidden).
TEST(EigenMallocForbidden, DynamicEigenAllocationAsserts) {
  EXPECT_DEATH(
      {
        qnav::test::EigenMallocForbidden forbid;
        Eigen::MatrixXd m(64, 64);
        m.setZero();
      },
      "heap allocation is forbidden");
}
TEST(EigenMallocForbidden, FixedSizeEigenIsAllowed) {
  qnav::test::EigenMallocForbidden forbid;
  Eigen::Matrix3d a = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d b = a * a;
  EXPECT_DOUBLE_EQ(b(0, 0), 1.0);
}
#endif
