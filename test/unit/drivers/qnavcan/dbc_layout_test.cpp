// docs/qnav.dbc is the interface control document; the codec's tables must say exactly what it says.
// The DBC is parsed, every message and signal is matched against the codec, and the codec's bit
// placement is checked against an independent reading of the DBC bit numbering (cantools' msb0
// conversion for Motorola signals), so a wrong start bit, length or byte order fails here.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include "drivers/qnavcan/dbc.hpp"
#include "drivers/qnavcan/messages.hpp"

using namespace qnav;
using namespace qnav::drivers::qnavcan;

namespace {
std::string read_file(const std::string& path) {
  std::string s;
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return s;
  char buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) s.append(buf, n);
  std::fclose(f);
  return s;
}

// Independent bit numbering: the frame bits a signal occupies, LSB of the raw value first.
void expected_positions(const DbcSignal& s, int* pos) {
  if (!s.big_endian) {
    for (int k = 0; k < s.length; ++k) pos[k] = s.start_bit + k;
    return;
  }
  const int msb0 = 8 * (s.start_bit / 8) + (7 - s.start_bit % 8);  // cantools kcd.py _start_bit
  for (int i = 0; i < s.length; ++i) {                               // i = 0 is the MSB
    const int q = msb0 + i;
    pos[s.length - 1 - i] = 8 * (q / 8) + (7 - q % 8);
  }
}

struct Loaded {
  std::unique_ptr<DbcFile> dbc = std::make_unique<DbcFile>();
  Status status;
};
Loaded load() {
  Loaded l;
  const std::string text = read_file(std::string(QNAV_SOURCE_DIR) + "/docs/qnav.dbc");
  if (text.empty()) {
    l.status = Status(StatusCode::kNotFound, "docs/qnav.dbc not readable");
    return l;
  }
  l.status = parse_dbc(text.data(), text.size(), *l.dbc);
  return l;
}
}  // namespace

TEST(QnavDbc, EveryDbcMessageAndSignalMatchesTheCodec) {
  Loaded l = load();
  ASSERT_TRUE(l.status.is_ok()) << l.status.message() << " at line " << l.dbc->error_line;
  const DbcFile& dbc = *l.dbc;
  ASSERT_EQ(dbc.messages.size(), all_messages().size());
  for (const MessageDef& m : all_messages()) {
    const DbcMessage* d = dbc.find(m.id);
    ASSERT_NE(d, nullptr) << m.name;
    EXPECT_STREQ(d->name, m.name);
    EXPECT_FALSE(d->extended);
    EXPECT_EQ(d->dlc, m.dlc) << m.name;
    EXPECT_STREQ(d->transmitter, m.transmitter) << m.name;
    EXPECT_EQ(d->cycle_ms, m.cycle_ms) << m.name;
    ASSERT_EQ(d->signals.size(), m.signals.size()) << m.name;
    for (std::size_t i = 0; i < m.signals.size(); ++i) {
      const SignalDef& c = m.signals[i];
      const DbcSignal& s = d->signals[i];
      SCOPED_TRACE(std::string(m.name) + "." + c.name);
      EXPECT_STREQ(s.name, c.name);
      EXPECT_EQ(s.start_bit, c.start_bit);
      EXPECT_EQ(s.length, c.length);
      EXPECT_EQ(s.big_endian, c.big_endian);
      EXPECT_EQ(s.is_signed, c.is_signed);
      EXPECT_DOUBLE_EQ(s.factor, c.factor);
      EXPECT_DOUBLE_EQ(s.offset, c.offset);
      EXPECT_DOUBLE_EQ(s.min, c.min);
      EXPECT_DOUBLE_EQ(s.max, c.max);
      EXPECT_STREQ(s.unit, c.unit);
    }
  }
}

TEST(QnavDbc, CodecPlacesEveryBitWhereTheDbcNumberingSays) {
  Loaded l = load();
  ASSERT_TRUE(l.status.is_ok()) << l.status.message();
  for (const DbcMessage& d : l.dbc->messages) {
    const MessageDef* m = find_message(d.id);
    ASSERT_NE(m, nullptr);
    std::uint8_t used[64] = {};
    for (std::size_t i = 0; i < d.signals.size(); ++i) {
      const DbcSignal& s = d.signals[i];
      SCOPED_TRACE(std::string(d.name) + "." + s.name);
      int pos[64];
      expected_positions(s, pos);
      for (int k = 0; k < s.length; ++k) {
        ASSERT_GE(pos[k], 0);
        ASSERT_LT(pos[k], 8 * d.dlc) << "signal leaves the DLC";
        EXPECT_EQ(used[pos[k] / 8] & (1u << (pos[k] % 8)), 0u) << "signals overlap at bit " << pos[k];
        used[pos[k] / 8] = static_cast<std::uint8_t>(used[pos[k] / 8] | (1u << (pos[k] % 8)));
        EXPECT_EQ(signal_bit_position(m->signals[i], static_cast<std::uint8_t>(k)), pos[k]);
      }
      // A walking one through the codec lands on exactly the expected frame bit.
      for (int k = 0; k < s.length; ++k) {
        std::uint8_t data[64] = {};
        insert_raw(data, m->signals[i], std::uint64_t{1} << k);
        for (int b = 0; b < 8 * d.dlc; ++b) {
          const bool set = (data[b / 8] >> (b % 8)) & 1u;
          ASSERT_EQ(set, b == pos[k]) << "raw bit " << k << " frame bit " << b;
        }
        EXPECT_EQ(extract_raw(data, m->signals[i]), std::uint64_t{1} << k);
      }
    }
  }
}

TEST(QnavDbc, ParserReportsTheBrokenLine) {
  const char bad[] = "BO_ 256 X: 8 A\n SG_ S : 0|16@2+ (1,0) [0|1] \"\" B\n";
  auto dbc = std::make_unique<DbcFile>();
  EXPECT_EQ(parse_dbc(bad, sizeof bad - 1, *dbc), StatusCode::kCorrupt);
  EXPECT_EQ(dbc->error_line, 2u);
  const char orphan[] = " SG_ S : 0|16@1+ (1,0) [0|1] \"\" B\n";
  EXPECT_EQ(parse_dbc(orphan, sizeof orphan - 1, *dbc), StatusCode::kCorrupt);
}
