#include "nav/core/byte_order.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>

namespace qnav {
namespace {

// The same byte arrays must decode to the same numbers on little- and big-endian hosts; the leon3
// test run is the big-endian check.
TEST(ByteOrder, LittleAndBigEndianLoadsAreHostIndependent) {
  const std::uint8_t b[8] = {0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08};
  EXPECT_EQ(load_le_u16(b), 0x0201u);
  EXPECT_EQ(load_be_u16(b), 0x0102u);
  EXPECT_EQ(load_le_u32(b), 0x04030201u);
  EXPECT_EQ(load_be_u32(b), 0x01020304u);
  EXPECT_EQ(load_le_u64(b), 0x0807060504030201ull);
  EXPECT_EQ(load_be_u64(b), 0x0102030405060708ull);
  const std::uint8_t neg[4] = {0xFE, 0xFF, 0xFF, 0xFF};
  EXPECT_EQ(load_le_i16(neg), -2);
  EXPECT_EQ(load_le_i32(neg), -2);
  EXPECT_EQ(load_be_i16(neg), -257);
}

TEST(ByteOrder, FloatsDecodeFromIeeeBitPatterns) {
  const std::uint8_t one_le[4] = {0x00, 0x00, 0x80, 0x3F};  // 1.0f
  const std::uint8_t one_be[4] = {0x3F, 0x80, 0x00, 0x00};
  EXPECT_EQ(load_le_f32(one_le), 1.0f);
  EXPECT_EQ(load_be_f32(one_be), 1.0f);
  const std::uint8_t pi_le[8] = {0x18, 0x2D, 0x44, 0x54, 0xFB, 0x21, 0x09, 0x40};  // 3.141592653589793
  EXPECT_DOUBLE_EQ(load_le_f64(pi_le), 3.141592653589793);
}

TEST(ByteOrder, StoresRoundTrip) {
  std::uint8_t buf[8];
  store_le_u32(buf, 0xDEADBEEFu);
  EXPECT_EQ(buf[0], 0xEF);
  EXPECT_EQ(load_le_u32(buf), 0xDEADBEEFu);
  store_be_u32(buf, 0xDEADBEEFu);
  EXPECT_EQ(buf[0], 0xDE);
  EXPECT_EQ(load_be_u32(buf), 0xDEADBEEFu);
  store_le_u16(buf, 0xBEEF);
  EXPECT_EQ(load_le_u16(buf), 0xBEEF);
  store_be_u16(buf, 0xBEEF);
  EXPECT_EQ(load_be_u16(buf), 0xBEEF);
  store_le_u64(buf, 0x0123456789ABCDEFull);
  EXPECT_EQ(load_le_u64(buf), 0x0123456789ABCDEFull);
  store_le_f32(buf, -2.5f);
  EXPECT_EQ(load_le_f32(buf), -2.5f);
  store_le_f64(buf, 1e-300);
  EXPECT_EQ(load_le_f64(buf), 1e-300);
}

TEST(ByteOrder, ReportsHost) {
  // Not an assertion about the decoders (they are host-independent), a record of where we ran.
  std::printf("host is %s-endian\n", host_is_big_endian() ? "big" : "little");
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
  EXPECT_TRUE(host_is_big_endian());
#else
  EXPECT_FALSE(host_is_big_endian());
#endif
}

}  // namespace
}  // namespace qnav
