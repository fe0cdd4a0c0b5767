// DBC signal codec: the bit-level rules of a DBC file, table-driven, so the code and docs/qnav.dbc
// describe one layout (test/unit/drivers/qnavcan parses the DBC and compares every signal).
//  - Intel (@1, little-endian): bit i of the raw value sits at frame bit start+i, where frame bit
//    b = byte (b / 8), bit (b % 8), LSB = bit 0.
//  - Motorola (@0, big-endian): `start` is the MSB in the same numbering; following bits walk down
//    inside a byte and continue at bit 7 of the next byte (the DBC "sawtooth").
//  - physical = raw * factor + offset; signed raw values are two's complement of `length` bits.
// extract/insert: O(length) <= 64 steps, no heap. encode_signal rejects a physical value outside
// [min, max] (kOutOfRange) or NaN (kInvalidArgument) and never writes outside the signal's bits.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::drivers::qnavcan {

struct SignalDef {
  const char* name;
  std::uint16_t start_bit;
  std::uint8_t length;  // 1..64
  bool big_endian;      // @0
  bool is_signed;       // '-'
  double factor;
  double offset;
  double min;
  double max;
  const char* unit;
};

struct MessageDef {
  const char* name;
  std::uint32_t id;  // 11-bit
  std::uint8_t dlc;
  const char* transmitter;
  Span<const SignalDef> signals;
  std::uint32_t cycle_ms;
};

// True when every bit of the signal lies inside `dlc` bytes.
bool signal_fits(const SignalDef& s, std::size_t dlc) noexcept;
std::uint64_t extract_raw(const std::uint8_t* data, const SignalDef& s) noexcept;
void insert_raw(std::uint8_t* data, const SignalDef& s, std::uint64_t raw) noexcept;
// Raw -> physical (sign-extends signed signals).
double raw_to_physical(const SignalDef& s, std::uint64_t raw) noexcept;
Status encode_signal(std::uint8_t* data, const SignalDef& s, double physical) noexcept;
// Decodes and checks [min, max]; kOutOfRange leaves `physical` set to the decoded value.
Status decode_signal(const std::uint8_t* data, const SignalDef& s, double& physical) noexcept;
// The frame bit index of the signal's k-th bit counted from its LSB (k < length).
std::uint16_t signal_bit_position(const SignalDef& s, std::uint8_t k) noexcept;

}  // namespace qnav::drivers::qnavcan
