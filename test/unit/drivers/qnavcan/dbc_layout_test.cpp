// docs/qnav.dbc is the interface control document; the codec's tables must say exactly what it says.
// The DBC is parsed, every message and signal is matched against the codec, and the codec's bit
// placement is checked against an independent reading of the DBC bit numbering (cantools' msb0
// conversion for Motorola signals), so a wrong start bit, length or byte order fails here. The
// value tables (VAL_) and signal comments (CM_ SG_), which the bounded reader skips, are read here
// line by line: every enumeration and flag has names, and they are the codec's names.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <utility>

#include "drivers/qnavcan/dbc.hpp"
#include "drivers/qnavcan/messages.hpp"
#include "nav/core/assert.hpp"

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

std::string dbc_text() { return read_file(std::string(QNAV_SOURCE_DIR) + "/docs/qnav.dbc"); }

// VAL_ <id> <signal> <raw> "<name>" ... ; -> {(id, signal) -> {raw -> name}}.
using ValueTables = std::map<std::pair<std::uint32_t, std::string>, std::map<long, std::string>>;
ValueTables value_tables(const std::string& text, std::string& error) {
  ValueTables out;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.rfind("VAL_ ", 0) != 0) continue;
    std::istringstream in(line.substr(5));
    std::uint32_t id = 0;
    std::string sig;
    if (!(in >> id >> sig)) {
      error = "bad VAL_ line: " + line;
      return out;
    }
    std::map<long, std::string>& table = out[{id, sig}];
    std::string tok;
    while (in >> tok && tok != ";") {
      const long raw = std::stol(tok);
      std::string name;
      in >> std::ws;
      if (in.get() != '"' || !std::getline(in, name, '"')) {
        error = "bad VAL_ entry: " + line;
        return out;
      }
      table[raw] = name;
    }
    if (tok != ";") error = "VAL_ line without ';': " + line;
  }
  return out;
}

bool has_signal_comment(const std::string& text, std::uint32_t id, const char* sig) {
  return text.find("CM_ SG_ " + std::to_string(id) + " " + sig + " \"") != std::string::npos;
}

struct Loaded {
  std::unique_ptr<DbcFile> dbc = std::make_unique<DbcFile>();
  Status status;
};
Loaded load() {
  Loaded l;
  const std::string text = dbc_text();
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

TEST(QnavDbc, EveryEnumerationAndFlagHasAValueTableNamingEveryValue) {
  Loaded l = load();
  ASSERT_TRUE(l.status.is_ok()) << l.status.message();
  std::string error;
  const ValueTables tables = value_tables(dbc_text(), error);
  ASSERT_TRUE(error.empty()) << error;
  for (const auto& t : tables) {  // every table belongs to a signal that exists
    const DbcMessage* m = l.dbc->find(t.first.first);
    ASSERT_NE(m, nullptr) << "VAL_ for unknown message " << t.first.first;
    bool found = false;
    for (const DbcSignal& s : m->signals) found = found || t.first.second == s.name;
    EXPECT_TRUE(found) << "VAL_ for unknown signal " << m->name << "." << t.first.second;
  }
  const char* const kEnumerations[] = {"Mode", "State", "GuidanceStatus", "Side", "ModeReject"};
  int enumerations = 0, flags = 0;
  for (const DbcMessage& m : l.dbc->messages) {
    for (const DbcSignal& s : m.signals) {
      bool enumeration = s.length == 1;
      for (const char* e : kEnumerations) enumeration = enumeration || std::strcmp(s.name, e) == 0;
      const auto it = tables.find({m.id, s.name});
      if (!enumeration) {
        EXPECT_EQ(it, tables.end()) << m.name << "." << s.name << " is a number, not an enumeration";
        continue;
      }
      SCOPED_TRACE(std::string(m.name) + "." + s.name);
      ASSERT_NE(it, tables.end()) << "no VAL_ table: CAN tools would show integers";
      // Exactly the values the range allows, each named.
      EXPECT_EQ(it->second.size(), static_cast<std::size_t>(s.max - s.min) + 1);
      for (long v = static_cast<long>(s.min); v <= static_cast<long>(s.max); ++v) {
        const auto n = it->second.find(v);
        ASSERT_NE(n, it->second.end()) << "value " << v << " has no name";
        EXPECT_FALSE(n->second.empty());
      }
      if (s.length == 1)
        ++flags;
      else
        ++enumerations;
    }
  }
  EXPECT_EQ(enumerations,
            6);  // MODE_CMD.Mode, NAV_STATUS.State and .ModeReject, ROUTE_STATUS.GuidanceStatus and .Side, HEARTBEAT.State
  EXPECT_EQ(flags, 36);  // Valid, DepthValid, AltitudeValid, ResetNav, Reverse, Localised, 2 x 10 Fault*, Leak, BusOff, 8 MAP_STATUS flags
}

TEST(QnavDbc, RouteStatusValueNamesAreTheCodecNames) {
  std::string error;
  const ValueTables tables = value_tables(dbc_text(), error);
  ASSERT_TRUE(error.empty()) << error;
  const auto status = tables.find({kIdRouteStatus, "GuidanceStatus"});
  ASSERT_NE(status, tables.end());
  ASSERT_EQ(status->second.size(), 5u);
  for (const auto& v : status->second) EXPECT_EQ(v.second, to_string(static_cast<GuidanceState>(v.first))) << v.first;
  const auto side = tables.find({kIdRouteStatus, "Side"});
  ASSERT_NE(side, tables.end());
  ASSERT_EQ(side->second.size(), 4u);
  for (const auto& v : side->second) EXPECT_EQ(v.second, to_string(static_cast<SideOfRoute>(v.first))) << v.first;
  const auto reverse = tables.find({kIdModeCmd, "Reverse"});
  ASSERT_NE(reverse, tables.end());
  EXPECT_EQ(reverse->second.at(0), "Forward");
  EXPECT_EQ(reverse->second.at(1), "Reverse");
}

TEST(QnavDbc, FaultBitsAreCommentedOneBitSignalsAtTheWordsPositions) {
  Loaded l = load();
  ASSERT_TRUE(l.status.is_ok()) << l.status.message();
  const std::string text = dbc_text();
  const std::pair<std::uint32_t, int> words[] = {{kIdNavStatus, 32}, {kIdHealth, 0}};  // message, bit of word bit 0
  for (const auto& w : words) {
    const DbcMessage* m = l.dbc->find(w.first);
    ASSERT_NE(m, nullptr);
    SCOPED_TRACE(m->name);
    int found = 0;
    for (const DbcSignal& s : m->signals) {
      EXPECT_STRNE(s.name, "FaultFlags") << "the 16-bit word is sent as per-bit signals";
      for (int b = 0; b < fault::kBitCount; ++b) {
        if (std::strcmp(s.name, fault::kSignalNames[b]) != 0) continue;
        ++found;
        EXPECT_EQ(s.start_bit, w.second + b) << s.name;
        EXPECT_EQ(s.length, 1) << s.name;
        EXPECT_FALSE(s.big_endian);
        EXPECT_TRUE(has_signal_comment(text, m->id, s.name)) << s.name << " has no CM_ comment";
      }
      // Nothing else may use the reserved word bits 10..15.
      if (!s.big_endian)
        for (int k = 0; k < s.length; ++k) {
          const int bit = s.start_bit + k;
          EXPECT_FALSE(bit >= w.second + fault::kBitCount && bit < w.second + 16)
              << s.name << " uses reserved bit " << bit;
        }
    }
    EXPECT_EQ(found, fault::kBitCount);
  }
}

namespace {
int g_clamp_faults = 0;
void count_clamp_fault(const char*, const char*, int) noexcept { ++g_clamp_faults; }
}  // namespace

// The outputs' clamps take their ranges from the DBC table (clamp_to_signal), not from literals.
TEST(QnavDbc, OutputsAreClampedToTheDbcRangesFromTheOneTable) {
  using namespace qnav::drivers::qnavcan;
  EXPECT_DOUBLE_EQ(clamp_to_signal(kIdRouteGuidance, "CrossTrack", 1000.0), 327.0);
  EXPECT_DOUBLE_EQ(clamp_to_signal(kIdRouteGuidance, "CrossTrack", -1000.0), -327.0);
  EXPECT_DOUBLE_EQ(clamp_to_signal(kIdRouteGuidance, "CrossTrack", 12.5), 12.5);
  EXPECT_DOUBLE_EQ(clamp_to_signal(kIdRouteGuidance, "DistToNext", -3.0), 0.0);
  EXPECT_DOUBLE_EQ(clamp_to_signal(kIdNavStatus, "Confidence", 150.0), 100.0);
  EXPECT_DOUBLE_EQ(clamp_to_signal(kIdVoStep, "Dx", std::nan("")), 0.0);
  EXPECT_DOUBLE_EQ(clamp_to_signal(kIdMapPose, "X", 1e9), kMapPositionMax);
  // A name the table lacks is a software fault, not a silent literal.
  const qnav::AssertHandler saved = qnav::assert_handler();
  qnav::set_assert_handler(&count_clamp_fault);
  g_clamp_faults = 0;
  EXPECT_DOUBLE_EQ(clamp_to_signal(kIdRouteGuidance, "NoSuchSignal", 5.0), 0.0);
  EXPECT_DOUBLE_EQ(clamp_to_signal(0x7FF, "CrossTrack", 5.0), 0.0);
  EXPECT_EQ(g_clamp_faults, 2);
  qnav::set_assert_handler(saved);
}
