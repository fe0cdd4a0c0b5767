#include "hal/core/candump.hpp"

#include <gtest/gtest.h>

#include <cstring>

#include "test/support/alloc_guard.hpp"
#include "hal/core/serial.hpp"

using namespace qnav;
using namespace qnav::hal;

namespace {
Status parse(const char* s, CanLogRecord& r) { return parse_can_log_line(s, std::strlen(s), r); }
}  // namespace

TEST(CandumpLog, ParsesStandardFrameWithTimeAndInterface) {
  CanLogRecord r;
  ASSERT_TRUE(parse("(1436509052.249713) vcan0 123#DEADBEEF\n", r).is_ok());
  EXPECT_TRUE(r.has_time);
  EXPECT_EQ(r.time_us, 1436509052249713LL);
  EXPECT_STREQ(r.interface, "vcan0");
  EXPECT_EQ(r.frame.id, 0x123u);
  EXPECT_FALSE(r.frame.extended);
  ASSERT_EQ(r.frame.len, 4);
  EXPECT_EQ(r.frame.data[0], 0xDE);
  EXPECT_EQ(r.frame.data[3], 0xEF);
}

TEST(CandumpLog, ParsesExtendedRtrFdAndErrorFrames) {
  CanLogRecord r;
  ASSERT_TRUE(parse("1F334455#1122334455667788", r).is_ok());
  EXPECT_TRUE(r.frame.extended);
  EXPECT_EQ(r.frame.id, 0x1F334455u);
  EXPECT_EQ(r.frame.len, 8);
  ASSERT_TRUE(parse("123#R", r).is_ok());
  EXPECT_TRUE(r.frame.rtr);
  ASSERT_TRUE(parse("123##1DEADBEEF", r).is_ok());
  EXPECT_TRUE(r.frame.fd);
  EXPECT_TRUE(r.frame.brs);
  EXPECT_FALSE(r.frame.esi);
  EXPECT_EQ(r.frame.len, 4);
  // candump -l of a bus-off error frame: CAN_ERR_FLAG | CAN_ERR_BUSOFF.
  ASSERT_TRUE(parse("(1.000000) can0 20000040#0000000000000000", r).is_ok());
  EXPECT_TRUE(r.frame.error);
  EXPECT_EQ(r.frame.id, can_error::kBusOff);
  ASSERT_TRUE(parse("123#11.22.33", r).is_ok());
  EXPECT_EQ(r.frame.len, 3);
}

TEST(CandumpLog, RejectsMalformedLines) {
  CanLogRecord r;
  EXPECT_EQ(parse("12#00", r), StatusCode::kCorrupt);           // 2-digit id
  EXPECT_EQ(parse("800#00", r), StatusCode::kOutOfRange);       // > 0x7FF
  EXPECT_EQ(parse("123#0", r), StatusCode::kTruncated);         // odd hex
  EXPECT_EQ(parse("123#001122334455667788", r), StatusCode::kOutOfRange);  // 9 bytes classic
  EXPECT_EQ(parse("123##1001122334455667788", r), StatusCode::kOutOfRange);  // FD 9 bytes: not a DLC size
  EXPECT_EQ(parse("123#ZZ", r), StatusCode::kCorrupt);
  EXPECT_EQ(parse("(12.34) can0 123#00", r), StatusCode::kCorrupt);  // 2 fraction digits
  EXPECT_EQ(parse("123", r), StatusCode::kTruncated);
  char longline[400];
  std::memset(longline, 'A', sizeof longline);
  EXPECT_EQ(parse_can_log_line(longline, sizeof longline, r), StatusCode::kTruncated);
}

TEST(CandumpLog, FormatRoundTripsWithoutHeap) {
  const char* lines[] = {"(1436509052.249713) vcan0 123#DEADBEEF", "(0.000001) can1 1F334455#1122334455667788",
                         "(5.500000) can0 123##300112233445566778899AABBCCDDEEFF", "(7.000000) can0 20000004#0004000000000000"};
  for (const char* l : lines) {
    CanLogRecord r;
    char out[kMaxCanLogLine];
    std::size_t n = 0;
    QNAV_EXPECT_NO_ALLOC({
      ASSERT_TRUE(parse(l, r).is_ok());
      n = format_can_log_line(r, out, sizeof out);
    });
    ASSERT_GT(n, 0u);
    EXPECT_STREQ(out, l);
  }
}

TEST(CanFrame, FilterMatchesLikeTheKernel) {
  CanFilter f;
  f.id = 0x123;
  f.mask = kCanSffMask;
  CanFrame a;
  a.id = 0x123;
  EXPECT_TRUE(can_filter_matches(f, a));
  CanFrame ext;
  ext.id = 0x1ABCD123;
  ext.extended = true;
  EXPECT_FALSE(can_filter_matches(f, ext));  // exact-ID fast path: no alias on extended ids
  f.match_ide_rtr = false;
  EXPECT_TRUE(can_filter_matches(f, ext));   // without IDE in the mask it does alias (can.rst)
  f.match_ide_rtr = true;
  f.invert = true;
  EXPECT_FALSE(can_filter_matches(f, a));
}

TEST(CanFrame, ValidateRejectsBadCombinations) {
  CanFrame f;
  f.len = 9;
  EXPECT_EQ(validate_can_frame(f), StatusCode::kOutOfRange);
  f.fd = true;
  f.len = 12;
  EXPECT_TRUE(validate_can_frame(f).is_ok());
  f.len = 13;
  EXPECT_EQ(validate_can_frame(f), StatusCode::kOutOfRange);
  f = CanFrame{};
  f.id = 0x800;
  EXPECT_EQ(validate_can_frame(f), StatusCode::kOutOfRange);
}

TEST(SerialConfig, ValidatesFraming) {
  SerialConfig c;
  EXPECT_TRUE(validate_serial_config(c).is_ok());
  c.baud = 12345;
  EXPECT_EQ(validate_serial_config(c), StatusCode::kUnsupported);
  c.baud = 9600;
  c.data_bits = 9;
  EXPECT_EQ(validate_serial_config(c), StatusCode::kInvalidArgument);
  c.data_bits = 7;
  c.stop_bits = 3;
  EXPECT_EQ(validate_serial_config(c), StatusCode::kInvalidArgument);
}

// candump's default screen format (`candump can0 > file`): read like the -l log.
TEST(CandumpScreen, ReadsTheDefaultScreenFormat) {
  CanLogRecord r;
  ASSERT_TRUE(parse("  can0  123   [2]  11 22", r).is_ok());
  EXPECT_FALSE(r.has_time);
  EXPECT_STREQ(r.interface, "can0");
  EXPECT_EQ(r.frame.id, 0x123u);
  EXPECT_FALSE(r.frame.extended);
  ASSERT_EQ(r.frame.len, 2);
  EXPECT_EQ(r.frame.data[0], 0x11);
  EXPECT_EQ(r.frame.data[1], 0x22);

  ASSERT_TRUE(parse("  vcan0  1F334455   [8]  01 02 03 04 05 06 07 08\n", r).is_ok());
  EXPECT_TRUE(r.frame.extended);
  EXPECT_EQ(r.frame.id, 0x1F334455u);
  ASSERT_EQ(r.frame.len, 8);
  EXPECT_EQ(r.frame.data[7], 0x08);

  ASSERT_TRUE(parse("  can0  321   [0]  ", r).is_ok());
  EXPECT_EQ(r.frame.len, 0);
}

TEST(CandumpScreen, ReadsTimestampsExtraColumnsRemoteFdAndAscii) {
  CanLogRecord r;
  ASSERT_TRUE(parse(" (1436509052.249713)  can0  123   [2]  11 22", r).is_ok());  // -t a
  EXPECT_TRUE(r.has_time);
  EXPECT_EQ(r.time_us, 1436509052249713LL);
  ASSERT_TRUE(parse("  can0  RX - -  123   [2]  11 22", r).is_ok());  // -x
  EXPECT_EQ(r.frame.id, 0x123u);
  ASSERT_TRUE(parse("  can0  123   [3]  41 42 43   'ABC'", r).is_ok());  // -a
  EXPECT_EQ(r.frame.len, 3);
  ASSERT_TRUE(parse("  can0  123   [4]  remote request", r).is_ok());
  EXPECT_TRUE(r.frame.rtr);
  EXPECT_EQ(r.frame.len, 4);
  ASSERT_TRUE(parse("  can0  123  [12]  00 11 22 33 44 55 66 77 88 99 AA BB", r).is_ok());
  EXPECT_TRUE(r.frame.fd);
  EXPECT_EQ(r.frame.len, 12);
}

TEST(CandumpScreen, RejectsDamagedScreenLines) {
  CanLogRecord r;
  EXPECT_FALSE(parse("  can0  123   [2]  11", r).is_ok());           // fewer bytes than [len]
  EXPECT_FALSE(parse("  can0  123   [2]  11 22 33", r).is_ok());     // more
  EXPECT_FALSE(parse("  can0  12345   [2]  11 22", r).is_ok());      // 5-digit id
  EXPECT_FALSE(parse("  can0  123   [9]  11 22", r).is_ok());        // classic length > 8
  EXPECT_FALSE(parse("  can0  123   [2]  1G 22", r).is_ok());        // bad hex
  EXPECT_FALSE(parse("  can0  800   [1]  11", r).is_ok());           // 11-bit id > 0x7FF
  EXPECT_FALSE(parse("Usage: see [the README]", r).is_ok());         // prose with a bracket
}
