#include "drivers/dvl/pd6_parser.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "recorded.hpp"
#include "test/support/alloc_guard.hpp"

using namespace qnav;
using namespace qnav::drivers::dvl;

namespace {
// Feeds text line by line; returns the number of ensembles and keeps the last one.
int feed(Pd6Parser& p, const std::string& text, Pd6Ensemble& last, std::int64_t t0 = 0) {
  int n = 0;
  std::size_t pos = 0;
  std::int64_t t = t0;
  while (pos < text.size()) {
    std::size_t e = text.find('\n', pos);
    if (e == std::string::npos) e = text.size();
    auto r = p.parse_line(text.data() + pos, e - pos, t, last);
    if (r.is_ok() && r.value() == Pd6Result::kEnsemble) ++n;
    pos = e + 1;
    t += 1000000;
  }
  return n;
}
std::string replace(std::string s, const std::string& from, const std::string& to) {
  const std::size_t i = s.find(from);
  EXPECT_NE(i, std::string::npos) << from;
  if (i != std::string::npos) s.replace(i, from.size(), to);
  return s;
}
}  // namespace

TEST(Pd6Parser, VendorEnsemble) {
  Pd6Parser p;
  Pd6Ensemble e;
  int n = 0;
  const std::string text = qnav_test::kPd6Ensemble;
  QNAV_EXPECT_NO_ALLOC(n = feed(p, text, e, 5000));
  ASSERT_EQ(n, 1);
  EXPECT_DOUBLE_EQ(e.velocity.vx_mps, 0.123);
  EXPECT_DOUBLE_EQ(e.velocity.vy_mps, -0.420);
  EXPECT_DOUBLE_EQ(e.velocity.vz_mps, 2.0);
  EXPECT_TRUE(e.velocity.bottom_lock);
  EXPECT_DOUBLE_EQ(e.velocity.altitude_m, 5.32);
  EXPECT_DOUBLE_EQ(e.sound_speed_mps, 1475.0);
  EXPECT_TRUE(e.has_attitude);
  EXPECT_EQ(e.velocity.source, DvlSource::kPd6);
  EXPECT_EQ(e.velocity.stamp.sample_ns, 5000);                  // first line of the ensemble
  EXPECT_EQ(e.velocity.stamp.arrival_ns, 5000 + 9 * 1000000);   // the :BD line
  EXPECT_EQ(e.velocity.device_time_us, ((12LL * 60 + 6) * 60 + 18) * 1000000);  // 12:06:18.00
  EXPECT_EQ(p.counters().total(), 0u);
}

TEST(Pd6Parser, BottomLockFollowsStatusAndBadMarker) {
  Pd6Parser p;
  Pd6Ensemble e;
  ASSERT_EQ(feed(p, replace(qnav_test::kPd6Ensemble, ":BI,  +123,  -420, +2000,    +0,A", ":BI,  +123,  -420, +2000,    +0,V"), e), 1);
  EXPECT_FALSE(e.velocity.bottom_lock);
  Pd6Parser p2;
  ASSERT_EQ(feed(p2, replace(qnav_test::kPd6Ensemble, "+123,  -420, +2000,    +0,A", "-32768,-32768,-32768,-32768,A"), e), 1);
  EXPECT_FALSE(e.velocity.bottom_lock);
  EXPECT_EQ(e.velocity.vx_mps, 0.0);
  EXPECT_EQ(p2.counters().get(DvlCounter::kNoLock), 1u);
}

TEST(Pd6Parser, EveryRejectedKindIsCounted) {
  Pd6Ensemble e;
  {
    Pd6Parser p;  // :BI with a missing field, so the :BD that follows has no :BI either
    EXPECT_EQ(feed(p, replace(qnav_test::kPd6Ensemble, ":BI,  +123,  -420, +2000,    +0,A", ":BI,  +123,  -420, +2000,A"), e), 0);
    EXPECT_EQ(p.counters().get(DvlCounter::kFormat), 2u);
  }
  {
    Pd6Parser p;  // 23.456 m/s
    EXPECT_EQ(feed(p, replace(qnav_test::kPd6Ensemble, "+123,  -420", "+23456,  -420"), e), 0);
    EXPECT_EQ(p.counters().get(DvlCounter::kRange), 1u);
  }
  {
    Pd6Parser p;  // range to bottom 1e300 m (issue #19): a damaged field, not an altitude
    EXPECT_EQ(feed(p, replace(qnav_test::kPd6Ensemble, "   5.32,", " 1e300,"), e), 0);
    EXPECT_EQ(p.counters().get(DvlCounter::kRange), 1u);
  }
  {
    Pd6Parser p;  // 12:06:19 then 12:06:18 again
    EXPECT_EQ(feed(p, replace(qnav_test::kPd6Ensemble, "22020812061800", "22020812061900"), e), 1);
    EXPECT_EQ(feed(p, qnav_test::kPd6Ensemble, e), 0);
    EXPECT_EQ(p.counters().get(DvlCounter::kStale), 1u);
  }
  {
    Pd6Parser p;
    std::string longline = ":BI," + std::string(150, '1');
    EXPECT_EQ(p.parse_line(longline.data(), longline.size(), 0, e).status(), StatusCode::kTruncated);
    EXPECT_EQ(p.counters().get(DvlCounter::kLength), 1u);
    EXPECT_EQ(p.parse_line(":XX,1,2", 7, 0, e).status(), StatusCode::kCorrupt);
    EXPECT_EQ(p.parse_line("BI,1,2,3,4,A", 12, 0, e).status(), StatusCode::kCorrupt);
    EXPECT_EQ(p.counters().get(DvlCounter::kFormat), 2u);
  }
}
