// A bounded reader for the subset of the DBC format qnav uses: `BO_` messages, `SG_` signals (no
// multiplexing), `BA_ "GenMsgCycleTime"`. Other lines (VERSION, NS_, BU_, CM_, VAL_, ...) are
// skipped. Input is text in memory; output goes into fixed tables (kMaxDbcMessages messages of
// kMaxDbcSignals signals, names up to 47 characters). Errors: kCorrupt with the 1-based line number
// in `error_line`, kCapacityExceeded when a table is full. O(text length), no heap.
// Byte order: @1 = little-endian (Intel), @0 = big-endian (Motorola) (cantools' reading; the 2007
// Vector PDF states the opposite and is wrong, see shared/reference/drivers.md §b).
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/fixed_vector.hpp"
#include "nav/core/status.hpp"

namespace qnav::drivers::qnavcan {

constexpr std::size_t kMaxDbcMessages = 32;
constexpr std::size_t kMaxDbcSignals = 24;
constexpr std::size_t kDbcNameLen = 48;

struct DbcSignal {
  char name[kDbcNameLen] = {};
  std::uint16_t start_bit = 0;
  std::uint8_t length = 0;
  bool big_endian = false;
  bool is_signed = false;
  double factor = 1, offset = 0, min = 0, max = 0;
  char unit[16] = {};
};

struct DbcMessage {
  std::uint32_t id = 0;  // without the extended flag
  bool extended = false;
  char name[kDbcNameLen] = {};
  std::uint8_t dlc = 0;
  char transmitter[kDbcNameLen] = {};
  std::uint32_t cycle_ms = 0;
  FixedVector<DbcSignal, kMaxDbcSignals> signals;
};

struct DbcFile {
  FixedVector<DbcMessage, kMaxDbcMessages> messages;
  std::size_t error_line = 0;
  const DbcMessage* find(std::uint32_t id) const noexcept;
};

Status parse_dbc(const char* text, std::size_t n, DbcFile& out) noexcept;

}  // namespace qnav::drivers::qnavcan
