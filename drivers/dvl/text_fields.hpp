// Helpers for comma-separated ASCII sentences: split into at most N fields (no copy), trim spaces,
// parse numbers from a bounded copy (fields longer than kMaxNumberChars are rejected, so strtod never
// sees unbounded input). O(line length), no heap.
#pragma once

#include <cstddef>
#include <cstdint>

namespace qnav::drivers::dvl {

constexpr std::size_t kMaxNumberChars = 31;

struct Field {
  const char* p = nullptr;
  std::size_t n = 0;
  bool equals(const char* s) const noexcept;
};

// Splits [p, p+n) on `sep` into out[0..cap); returns the field count, or cap+1 when there are more.
std::size_t split_fields(const char* p, std::size_t n, char sep, Field* out, std::size_t cap) noexcept;
Field trim(Field f) noexcept;
// Whole-field parses (after trimming); false on empty, junk, overflow or non-finite values.
bool parse_double(Field f, double& out) noexcept;
bool parse_int(Field f, long long& out) noexcept;

}  // namespace qnav::drivers::dvl
