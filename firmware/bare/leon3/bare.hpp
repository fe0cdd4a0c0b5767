// bare.hpp: the freestanding LEON3 runtime's interface (firmware/bare/leon3). No OS, no libc:
// output goes to the APBUART, memory comes from the static heap after the image (leon3.ld).
// The program defines `int main()`; crt0.S calls it through bare_main_entry() and powers off after.
#pragma once

#include <cstddef>
#include <cstdint>

namespace qnav::bare {

// APBUART (GRLIB) output, polled. Strings are written byte by byte ('\n' -> "\r\n" is not done).
void put_char(char c) noexcept;
void put_str(const char* s) noexcept;
void put_u32(std::uint32_t v) noexcept;          // decimal
void put_i32(std::int32_t v) noexcept;           // decimal, signed
void put_u64(std::uint64_t v) noexcept;          // decimal
void put_hex32(std::uint32_t v) noexcept;        // 8 hex digits, no prefix
void put_hex64(std::uint64_t v) noexcept;        // 16 hex digits, no prefix

// Static heap behind operator new (bump allocation, delete is a no-op).
std::size_t heap_used() noexcept;       // bytes handed out so far (including alignment padding)
std::size_t heap_capacity() noexcept;   // bytes between __heap_start and __heap_end
std::size_t heap_failed() noexcept;     // requests that did not fit (operator new then aborts)

// Prints "ABORT: <why>" and powers the machine off.
[[noreturn]] void fail(const char* why) noexcept;

}  // namespace qnav::bare

extern "C" [[noreturn]] void bare_shutdown(int code) noexcept;
