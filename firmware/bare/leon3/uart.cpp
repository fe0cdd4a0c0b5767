// uart.cpp: polled output on the LEON3 APBUART at 0x80000100 (GRLIB: data +0, status +4,
// control +8). Status bit 2 (TE) = transmitter FIFO empty; we wait for it before each byte
// (bounded, so a missing UART cannot hang the program). qemu's leon3_generic maps the first
// APBUART to -serial (stdio with -nographic).
#include "bare.hpp"

namespace qnav::bare {
namespace {

constexpr std::uintptr_t kUartBase = 0x80000100u;
volatile std::uint32_t* reg(std::uintptr_t off) noexcept {
  return reinterpret_cast<volatile std::uint32_t*>(kUartBase + off);
}
constexpr std::uint32_t kStatusTxEmpty = 1u << 2;
constexpr std::uint32_t kControlTxEnable = 1u << 1;

void put_digits(std::uint64_t v, unsigned base, int min_digits) noexcept {
  char buf[24];
  int n = 0;
  do {
    // 64-bit division by a small constant through 32-bit halves (no libgcc __udivdi3 needed).
    const std::uint32_t hi = static_cast<std::uint32_t>(v >> 32), lo = static_cast<std::uint32_t>(v);
    const std::uint32_t qhi = hi / base, rhi = hi % base;
    const std::uint64_t mid = (static_cast<std::uint64_t>(rhi) << 16) | (lo >> 16);
    const std::uint32_t qmid = static_cast<std::uint32_t>(mid) / base, rmid = static_cast<std::uint32_t>(mid) % base;
    const std::uint32_t low = (rmid << 16) | (lo & 0xffffu);
    const std::uint32_t qlo = low / base, d = low % base;
    v = (static_cast<std::uint64_t>(qhi) << 32) | (static_cast<std::uint64_t>(qmid) << 16) | qlo;
    buf[n++] = "0123456789abcdef"[d];
  } while (v != 0 || n < min_digits);
  while (n > 0) put_char(buf[--n]);
}

}  // namespace

void put_char(char c) noexcept {
  static bool enabled = false;
  if (!enabled) {
    *reg(8) = *reg(8) | kControlTxEnable;
    enabled = true;
  }
  for (int spin = 0; spin < 1000000 && (*reg(4) & kStatusTxEmpty) == 0; ++spin) {
  }
  *reg(0) = static_cast<std::uint8_t>(c);
}

void put_str(const char* s) noexcept {
  while (*s != '\0') put_char(*s++);
}
void put_u32(std::uint32_t v) noexcept { put_digits(v, 10, 1); }
void put_i32(std::int32_t v) noexcept {
  if (v < 0) {
    put_char('-');
    put_digits(0u - static_cast<std::uint32_t>(v), 10, 1);
  } else {
    put_digits(static_cast<std::uint32_t>(v), 10, 1);
  }
}
void put_u64(std::uint64_t v) noexcept { put_digits(v, 10, 1); }
void put_hex32(std::uint32_t v) noexcept { put_digits(v, 16, 8); }
void put_hex64(std::uint64_t v) noexcept { put_digits(v, 16, 16); }

}  // namespace qnav::bare
