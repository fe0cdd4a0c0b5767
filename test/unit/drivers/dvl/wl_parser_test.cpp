#include "drivers/dvl/wl_parser.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "recorded.hpp"
#include "test/support/alloc_guard.hpp"

using namespace qnav;
using namespace qnav::drivers::dvl;

namespace {
Status parse(WlParser& p, const std::string& s, WlMessage& m, std::int64_t arrival = 1000000000) {
  return p.parse_line(s.data(), s.size(), arrival, m);
}
std::string with_crc(const char* body) {
  char buf[300];
  const std::size_t n = wl_with_checksum(body, buf, sizeof buf);
  return std::string(buf, n);
}
}  // namespace

TEST(WlChecksum, Crc8CheckValueAndVendorSentences) {
  const char* check = "123456789";
  EXPECT_EQ(crc8_07(reinterpret_cast<const std::uint8_t*>(check), 9), 0xF4);
  EXPECT_EQ(with_crc("wrz,0.120,-0.400,2.000,y,1.30,1.855,1e-07;0;1.4;0;1.2;0;0.2;0;1e+09,7,14,123.00,1"),
            std::string(qnav_test::kWlWrz) + "\n");
}

TEST(WlParser, VendorVelocityReport) {
  WlParser p;
  WlMessage m;
  const std::size_t len = std::strlen(qnav_test::kWlWrz);
  QNAV_EXPECT_NO_ALLOC(ASSERT_TRUE(p.parse_line(qnav_test::kWlWrz, len, 1000000000, m).is_ok()));
  ASSERT_EQ(m.kind, WlKind::kVelocity);
  EXPECT_DOUBLE_EQ(m.velocity.vx_mps, 0.120);
  EXPECT_DOUBLE_EQ(m.velocity.vy_mps, -0.400);
  EXPECT_DOUBLE_EQ(m.velocity.vz_mps, 2.000);
  EXPECT_TRUE(m.velocity.bottom_lock);
  EXPECT_DOUBLE_EQ(m.velocity.altitude_m, 1.30);
  EXPECT_DOUBLE_EQ(m.velocity.fom_mps, 1.855);
  EXPECT_DOUBLE_EQ(m.covariance[0], 1e-07);
  EXPECT_DOUBLE_EQ(m.covariance[8], 1e+09);
  EXPECT_EQ(m.velocity.device_time_us, 7);
  EXPECT_EQ(m.time_of_transmission_us, 14);
  EXPECT_EQ(m.status, 1);
  // Sample time = arrival - the DVL's own latency (14 - 7 us).
  EXPECT_EQ(m.velocity.stamp.sample_ns, 1000000000 - 7000);
  EXPECT_EQ(p.counters().total(), 0u);
}

TEST(WlParser, VendorTransducerDeadReckoningAndOtherReports) {
  WlParser p;
  WlMessage m;
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(parse(p, qnav_test::kWlWru[i], m).is_ok()) << i;
    EXPECT_EQ(m.kind, WlKind::kTransducer);
    EXPECT_EQ(m.transducer.id, i);
    EXPECT_TRUE(m.transducer.locked);
  }
  EXPECT_DOUBLE_EQ(m.transducer.velocity_mps, 1.8);
  EXPECT_DOUBLE_EQ(m.transducer.distance_m, 1.35);
  ASSERT_TRUE(parse(p, qnav_test::kWlWrp[0], m).is_ok());
  EXPECT_EQ(m.kind, WlKind::kDeadReckoning);
  EXPECT_DOUBLE_EQ(m.dead_reckoning.time_s, 49056.809);
  EXPECT_DOUBLE_EQ(m.dead_reckoning.z_m, 1.23);
  EXPECT_DOUBLE_EQ(m.dead_reckoning.yaw_deg, 19.3);
  EXPECT_EQ(m.dead_reckoning.status, 0);
  ASSERT_TRUE(parse(p, qnav_test::kWlWrp[2], m).is_ok());
  EXPECT_EQ(m.dead_reckoning.status, 1);  // position not valid
  ASSERT_TRUE(parse(p, qnav_test::kWlWrx, m).is_ok());  // deprecated format: checksum ok, not decoded
  EXPECT_EQ(m.kind, WlKind::kOther);
  EXPECT_EQ(m.type, 'x');
  EXPECT_EQ(p.counters().total(), 0u);
}

TEST(WlParser, EveryRejectedKindIsCounted) {
  WlParser p;
  WlMessage m;
  std::string bad = qnav_test::kWlWrz;
  bad[5] = '9';  // payload changed, checksum not
  EXPECT_EQ(parse(p, bad, m), StatusCode::kCorrupt);
  EXPECT_EQ(parse(p, "wrz,0.1,0.2", m), StatusCode::kCorrupt);  // no *xx
  EXPECT_EQ(p.counters().get(DvlCounter::kChecksum), 2u);
  EXPECT_EQ(parse(p, std::string(300, 'w'), m), StatusCode::kTruncated);
  EXPECT_EQ(p.counters().get(DvlCounter::kLength), 1u);
  EXPECT_EQ(parse(p, with_crc("wrz,0.1,0.2,0.3,y,1.0,0.1,0;0;0;0;0;0;0;0;0,7,14,1.0"), m), StatusCode::kCorrupt);  // 10 fields
  EXPECT_EQ(parse(p, with_crc("wrz,0.1,abc,0.3,y,1.0,0.1,0;0;0;0;0;0;0;0;0,7,14,1.0,0"), m), StatusCode::kCorrupt);
  EXPECT_EQ(parse(p, with_crc("wrz,0.1,0.2,0.3,y,1.0,0.1,0;0;0;0;0;0;0;0,7,14,1.0,0"), m), StatusCode::kCorrupt);  // 8 cov
  EXPECT_EQ(parse(p, with_crc("wrz,0.1,0.2,0.3,maybe,1.0,0.1,0;0;0;0;0;0;0;0;0,7,14,1.0,0"), m), StatusCode::kCorrupt);
  EXPECT_EQ(parse(p, with_crc("wrz,nan,0.2,0.3,y,1.0,0.1,0;0;0;0;0;0;0;0;0,7,14,1.0,0"), m), StatusCode::kCorrupt);
  EXPECT_EQ(parse(p, with_crc("xyz,1"), m), StatusCode::kCorrupt);
  EXPECT_EQ(p.counters().get(DvlCounter::kFormat), 6u);
  EXPECT_EQ(parse(p, with_crc("wrz,12.0,0.2,0.3,y,1.0,0.1,0;0;0;0;0;0;0;0;0,7,14,1.0,0"), m), StatusCode::kOutOfRange);
  EXPECT_EQ(parse(p, with_crc("wrz,0.1,0.2,0.3,y,1.0,0.1,0;0;0;0;0;0;0;0;0,14,7,1.0,0"), m), StatusCode::kOutOfRange);  // tx before validity
  EXPECT_EQ(parse(p, with_crc("wru,4,0.0,1.0,-40,-90"), m), StatusCode::kOutOfRange);
  EXPECT_EQ(p.counters().get(DvlCounter::kRange), 3u);
  ASSERT_TRUE(parse(p, with_crc("wrz,0.1,0.2,0.3,y,1.0,0.1,0;0;0;0;0;0;0;0;0,1000,1500,1.0,0"), m).is_ok());
  EXPECT_EQ(parse(p, with_crc("wrz,0.1,0.2,0.3,y,1.0,0.1,0;0;0;0;0;0;0;0;0,1000,1600,1.0,0"), m), StatusCode::kInvalidArgument);
  EXPECT_EQ(p.counters().get(DvlCounter::kStale), 1u);
  // No bottom lock: delivered (nav must see the DVL is up) but flagged and counted.
  ASSERT_TRUE(parse(p, with_crc("wrz,0.000,0.000,0.000,n,-1.00,2.707,0;0;0;0;0;0;0;0;0,2000,2100,1.0,1"), m).is_ok());
  EXPECT_FALSE(m.velocity.bottom_lock);
  EXPECT_EQ(p.counters().get(DvlCounter::kNoLock), 1u);
}

// Regression (issue #19): extreme integers made `tot - tov` overflow (UBSan), and an altitude of
// 1e300 m or a negative variance was passed on. Each is now a counted kRange rejection.
TEST(WlParser, AbsurdValuesAreRangeErrorsNotOverflows) {
  WlParser p;
  WlMessage m;
  const char* bad[] = {
      "wrz,0.1,0.2,0.3,y,1.0,0.1,0;0;0;0;0;0;0;0;0,-9223372036854775807,9223372036854775807,1.0,0",
      "wrz,0.1,0.2,0.3,y,1.0,0.1,0;0;0;0;0;0;0;0;0,9223372036854775807,9223372036854775807,1.0,0",
      "wrz,0.1,0.2,0.3,y,1e300,0.1,0;0;0;0;0;0;0;0;0,1000,1500,1.0,0",
      "wrz,0.1,0.2,0.3,n,1e300,0.1,0;0;0;0;0;0;0;0;0,1000,1500,1.0,0",
      "wrz,0.1,0.2,0.3,y,1.0,0.1,-1;0;0;0;0;0;0;0;0,1000,1500,1.0,0",
      "wrz,0.1,0.2,0.3,y,1.0,0.1,0;0;0;0;0;0;0;0;-0.5,1000,1500,1.0,0",
  };
  std::uint64_t n = 0;
  for (const char* b : bad) {
    EXPECT_EQ(parse(p, with_crc(b), m), StatusCode::kOutOfRange) << b;
    EXPECT_EQ(p.counters().get(DvlCounter::kRange), ++n) << b;
  }
  // The bounds do not reject real values: 999 m altitude, a current epoch in microseconds.
  EXPECT_TRUE(parse(p, with_crc("wrz,0.1,0.2,0.3,y,999.0,0.1,1e-07;0;0;0;1e-07;0;0;0;1e-07,1764000000000000,1764000000010000,1.0,0"), m).is_ok());
  EXPECT_EQ(m.velocity.device_time_us, 1764000000000000LL);
}
