// Explicit byte-order loads and stores. File formats and bus protocols have a fixed byte order
// (XTF and JSF are little-endian, network and some DVL fields big-endian); the host may be either
// (SPARC/LEON is big-endian). Every decoder in qnav reads multi-byte fields through these functions,
// never by casting a pointer, so the same code is correct on both kinds of host and has no
// alignment faults. Floats are IEEE-754 bit patterns. O(1), no heap.
#pragma once

#include <cstdint>
#include <cstring>

namespace qnav {

inline std::uint16_t load_le_u16(const std::uint8_t* p) noexcept {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
inline std::uint32_t load_le_u32(const std::uint8_t* p) noexcept {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}
inline std::uint64_t load_le_u64(const std::uint8_t* p) noexcept {
  return static_cast<std::uint64_t>(load_le_u32(p)) | (static_cast<std::uint64_t>(load_le_u32(p + 4)) << 32);
}
inline std::uint16_t load_be_u16(const std::uint8_t* p) noexcept {
  return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}
inline std::uint32_t load_be_u32(const std::uint8_t* p) noexcept {
  return (static_cast<std::uint32_t>(p[0]) << 24) | (static_cast<std::uint32_t>(p[1]) << 16) |
         (static_cast<std::uint32_t>(p[2]) << 8) | static_cast<std::uint32_t>(p[3]);
}
inline std::uint64_t load_be_u64(const std::uint8_t* p) noexcept {
  return (static_cast<std::uint64_t>(load_be_u32(p)) << 32) | static_cast<std::uint64_t>(load_be_u32(p + 4));
}
inline std::int16_t load_le_i16(const std::uint8_t* p) noexcept { return static_cast<std::int16_t>(load_le_u16(p)); }
inline std::int32_t load_le_i32(const std::uint8_t* p) noexcept { return static_cast<std::int32_t>(load_le_u32(p)); }
inline std::int64_t load_le_i64(const std::uint8_t* p) noexcept { return static_cast<std::int64_t>(load_le_u64(p)); }
inline std::int16_t load_be_i16(const std::uint8_t* p) noexcept { return static_cast<std::int16_t>(load_be_u16(p)); }
inline std::int32_t load_be_i32(const std::uint8_t* p) noexcept { return static_cast<std::int32_t>(load_be_u32(p)); }

inline float load_le_f32(const std::uint8_t* p) noexcept {
  const std::uint32_t u = load_le_u32(p);
  float f;
  std::memcpy(&f, &u, sizeof f);
  return f;
}
inline double load_le_f64(const std::uint8_t* p) noexcept {
  const std::uint64_t u = load_le_u64(p);
  double d;
  std::memcpy(&d, &u, sizeof d);
  return d;
}
inline float load_be_f32(const std::uint8_t* p) noexcept {
  const std::uint32_t u = load_be_u32(p);
  float f;
  std::memcpy(&f, &u, sizeof f);
  return f;
}
inline double load_be_f64(const std::uint8_t* p) noexcept {
  const std::uint64_t u = load_be_u64(p);
  double d;
  std::memcpy(&d, &u, sizeof d);
  return d;
}

inline void store_le_u16(std::uint8_t* p, std::uint16_t v) noexcept {
  p[0] = static_cast<std::uint8_t>(v);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
inline void store_le_u32(std::uint8_t* p, std::uint32_t v) noexcept {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
inline void store_le_u64(std::uint8_t* p, std::uint64_t v) noexcept {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
inline void store_be_u16(std::uint8_t* p, std::uint16_t v) noexcept {
  p[0] = static_cast<std::uint8_t>(v >> 8);
  p[1] = static_cast<std::uint8_t>(v);
}
inline void store_be_u32(std::uint8_t* p, std::uint32_t v) noexcept {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (24 - 8 * i));
}
inline void store_le_f32(std::uint8_t* p, float f) noexcept {
  std::uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  store_le_u32(p, u);
}
inline void store_le_f64(std::uint8_t* p, double d) noexcept {
  std::uint64_t u;
  std::memcpy(&u, &d, sizeof u);
  store_le_u64(p, u);
}

// True on big-endian hosts (SPARC/LEON). Decoders never need this; tests report it.
inline bool host_is_big_endian() noexcept {
  const std::uint16_t one = 1;
  std::uint8_t b[2];
  std::memcpy(b, &one, 2);
  return b[0] == 0;
}

}  // namespace qnav
