// QNAV_ASSERT (nav/core/assert.hpp): a broken invariant goes to the installed handler with its
// message and place, the macro still yields the condition (so the call site can leave the path in a
// defined state), and with no handler it traps: a test cannot pass over a software bug.
#include <gtest/gtest.h>

#include <cstring>

#include "nav/core/assert.hpp"

namespace qnav {
namespace {

int g_calls = 0;
const char* g_what = nullptr;
int g_line = 0;
void count(const char* what, const char*, int line) noexcept {
  ++g_calls;
  g_what = what;
  g_line = line;
}

class AssertTest : public ::testing::Test {
 protected:
  void SetUp() override {
    saved_ = assert_handler();
    g_calls = 0;
  }
  void TearDown() override { set_assert_handler(saved_); }
  AssertHandler saved_ = nullptr;
};

TEST_F(AssertTest, HoldingInvariantCallsNothingAndYieldsTrue) {
  set_assert_handler(&count);
  const int n = 3;
  EXPECT_TRUE(QNAV_ASSERT(n == 3, "three"));
  EXPECT_EQ(g_calls, 0);
}

TEST_F(AssertTest, BrokenInvariantReachesTheHandlerWithItsPlaceAndYieldsFalse) {
  set_assert_handler(&count);
  const int n = 3;
  const int line = __LINE__ + 1;
  const bool ok = QNAV_ASSERT(n == 4, "n is four");
  EXPECT_FALSE(ok);
  EXPECT_EQ(g_calls, 1);
  ASSERT_NE(g_what, nullptr);
  EXPECT_STREQ(g_what, "n is four");
  EXPECT_EQ(g_line, line);
}

#if GTEST_HAS_DEATH_TEST
TEST_F(AssertTest, WithoutAHandlerABrokenInvariantTraps) {
  set_assert_handler(nullptr);
  const int n = 3;
  EXPECT_DEATH(static_cast<void>(QNAV_ASSERT(n == 4, "traps")), "");
}
#endif

}  // namespace
}  // namespace qnav
