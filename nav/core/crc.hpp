// Checksums used by qnav's own files and by device protocols.
//  - crc32(): IEEE 802.3 / zlib CRC-32 (reflected, poly 0xEDB88320, init and xorout 0xFFFFFFFF);
//    check value crc32("123456789") = 0xCBF43926. Used by the route file.
//  - crc16_ccitt_false(): poly 0x1021, init 0xFFFF, no reflection; check value 0x29B1. Used by the
//    DroneCAN transfer CRC.
// Table-driven, tables computed at compile time; O(n) time, no heap. crc32 can be chained:
// crc32(b, crc32(a)) == crc32(a||b).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace qnav {

namespace detail {
constexpr std::array<std::uint32_t, 256> make_crc32_table() noexcept {
  std::array<std::uint32_t, 256> t{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? (0xEDB88320u ^ (c >> 1)) : (c >> 1);
    t[i] = c;
  }
  return t;
}
constexpr std::array<std::uint16_t, 256> make_crc16_ccitt_table() noexcept {
  std::array<std::uint16_t, 256> t{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i << 8;
    for (int k = 0; k < 8; ++k) c = (c & 0x8000u) ? ((c << 1) ^ 0x1021u) : (c << 1);
    t[i] = static_cast<std::uint16_t>(c);
  }
  return t;
}
inline constexpr std::array<std::uint32_t, 256> kCrc32Table = make_crc32_table();
inline constexpr std::array<std::uint16_t, 256> kCrc16CcittTable = make_crc16_ccitt_table();
}  // namespace detail

// `previous` is the CRC of the bytes before these (0 for the first block).
inline std::uint32_t crc32(const std::uint8_t* data, std::size_t n, std::uint32_t previous = 0) noexcept {
  std::uint32_t c = previous ^ 0xFFFFFFFFu;
  for (std::size_t i = 0; i < n; ++i) c = detail::kCrc32Table[(c ^ data[i]) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

// `state` is the running CRC (0xFFFF to start).
inline std::uint16_t crc16_ccitt_false(const std::uint8_t* data, std::size_t n, std::uint16_t state = 0xFFFF) noexcept {
  std::uint16_t c = state;
  for (std::size_t i = 0; i < n; ++i)
    c = static_cast<std::uint16_t>((c << 8) ^ detail::kCrc16CcittTable[((c >> 8) ^ data[i]) & 0xFFu]);
  return c;
}

}  // namespace qnav
