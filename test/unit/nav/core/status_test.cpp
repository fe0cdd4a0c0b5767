#include "nav/core/status.hpp"

#include <gtest/gtest.h>

#include <memory>

namespace qnav {
namespace {

Status fails() { return Status(StatusCode::kCorrupt, "bad crc"); }
Status propagates() {
  QNAV_RETURN_IF_ERROR(fails());
  return Status::ok();
}

TEST(Status, DefaultIsOkAndCarriesNoMessage) {
  const Status s;
  EXPECT_TRUE(s.is_ok());
  EXPECT_TRUE(static_cast<bool>(s));
  EXPECT_STREQ(s.message(), "ok");
}

TEST(Status, ErrorKeepsCodeAndMessage) {
  const Status s = fails();
  EXPECT_FALSE(s.is_ok());
  EXPECT_EQ(s.code(), StatusCode::kCorrupt);
  EXPECT_STREQ(s.message(), "bad crc");
  EXPECT_TRUE(s == StatusCode::kCorrupt);
}

TEST(Status, ReturnIfErrorPropagatesTheFirstError) {
  const Status s = propagates();
  EXPECT_EQ(s.code(), StatusCode::kCorrupt);
}

TEST(Status, EveryCodeHasAName) {
  for (int c = 0; c <= static_cast<int>(StatusCode::kNotReady); ++c) {
    EXPECT_STRNE(to_string(static_cast<StatusCode>(c)), "unknown") << c;
  }
}

TEST(Result, HoldsValue) {
  Result<int> r = 42;
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(r.value(), 42);
  EXPECT_EQ(*r, 42);
  EXPECT_TRUE(r.status().is_ok());
}

TEST(Result, HoldsError) {
  Result<int> r = Status(StatusCode::kTruncated, "short");
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), StatusCode::kTruncated);
  EXPECT_EQ(r.value_or(7), 7);
}

TEST(Result, OkStatusWithoutValueBecomesAnError) {
  Result<int> r = Status::ok();
  EXPECT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
}

TEST(Result, MoveOnlyValuesAreMovedAndDestroyedOnce) {
  auto counter = std::make_shared<int>(0);
  {
    Result<std::shared_ptr<int>> r = counter;
    EXPECT_EQ(counter.use_count(), 2);
    Result<std::shared_ptr<int>> moved = std::move(r);
    EXPECT_EQ(counter.use_count(), 2);
    Result<std::shared_ptr<int>> copy = moved;
    EXPECT_EQ(counter.use_count(), 3);
    copy = Status(StatusCode::kEmpty, "reset");
    EXPECT_EQ(counter.use_count(), 2);
  }
  EXPECT_EQ(counter.use_count(), 1);
}

TEST(ResultDeathTest, ValueOfErrorTraps) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  Result<int> r = Status(StatusCode::kEmpty, "none");
  EXPECT_DEATH(
      {
        volatile int v = r.value();
        (void)v;
      },
      "");
}

}  // namespace
}  // namespace qnav
