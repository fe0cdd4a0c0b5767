#include "nav/core/crc.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>

namespace qnav {
namespace {

const std::uint8_t* bytes(const char* s) { return reinterpret_cast<const std::uint8_t*>(s); }

TEST(Crc, Crc32CheckValue) {
  EXPECT_EQ(crc32(bytes("123456789"), 9), 0xCBF43926u);
  EXPECT_EQ(crc32(bytes(""), 0), 0u);
}

TEST(Crc, Crc32ChainsAcrossBlocks) {
  const char* s = "The quick brown fox jumps over the lazy dog";
  const std::size_t n = std::strlen(s);
  EXPECT_EQ(crc32(bytes(s), n), 0x414FA339u);
  EXPECT_EQ(crc32(bytes(s) + 10, n - 10, crc32(bytes(s), 10)), 0x414FA339u);
}

TEST(Crc, Crc32DetectsASingleBitFlip) {
  std::uint8_t buf[64];
  for (int i = 0; i < 64; ++i) buf[i] = static_cast<std::uint8_t>(i * 7);
  const std::uint32_t good = crc32(buf, sizeof buf);
  for (int bit = 0; bit < 64 * 8; ++bit) {
    buf[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    EXPECT_NE(crc32(buf, sizeof buf), good) << bit;
    buf[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
  }
}

TEST(Crc, Crc16CcittFalseCheckValue) {
  EXPECT_EQ(crc16_ccitt_false(bytes("123456789"), 9), 0x29B1u);
  const std::uint16_t part = crc16_ccitt_false(bytes("1234"), 4);
  EXPECT_EQ(crc16_ccitt_false(bytes("56789"), 5, part), 0x29B1u);
}

}  // namespace
}  // namespace qnav
