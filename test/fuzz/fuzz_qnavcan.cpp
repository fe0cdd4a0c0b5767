// Arbitrary classic frames into the qnav receiver and every decoder; and DBC text into the reader.
#include <cmath>
#include <cstring>

#include "drivers/qnavcan/dbc.hpp"
#include "drivers/qnavcan/receiver.hpp"
#include "test/fuzz/fuzz_support.hpp"


int qnav_fuzz_qnavcan(const std::uint8_t* data, std::size_t size) {
  using namespace qnav;
  if (size < 3) return 0;
  if (data[0] & 0x80) {  // DBC reader
    static drivers::qnavcan::DbcFile dbc;
    drivers::qnavcan::parse_dbc(reinterpret_cast<const char*>(data + 1), size - 1, dbc).ignore();
    return 0;
  }
  static drivers::qnavcan::QnavCanReceiver rx;
  hal::CanRxFrame f;
  const std::uint32_t ids[] = {0x100, 0x101, 0x102, 0x110, 0x200, 0x201, 0x202, 0x203, 0x204, 0x205, 0x210, 0x2FF, 0x123};
  f.frame.id = ids[data[1] % (sizeof ids / sizeof ids[0])];
  f.frame.len = static_cast<std::uint8_t>(data[2] % 9);
  const std::size_t n = size - 3 < f.frame.len ? size - 3 : f.frame.len;
  std::memcpy(f.frame.data, data + 3, n);
  f.stamp.sample_ns = static_cast<std::int64_t>(data[0]) * 1000;
  rx.on_frame(f).ignore();
  const drivers::qnavcan::MessageDef* def = nullptr;
  double v[drivers::qnavcan::kMaxSignalsPerMessage];
  if (drivers::qnavcan::decode_generic(f.frame, def, v, drivers::qnavcan::kMaxSignalsPerMessage).is_ok())
    for (std::size_t i = 0; i < def->signals.size(); ++i)
      if (std::isnan(v[i])) __builtin_trap();
  return 0;
}

static void seeds_qnavcan(qnav::fuzz::Seeds& out) {
  out.push_back(qnav::fuzz::Seed{"frame", std::string("\x01\x00\x08", 3) + std::string("\x18\xFC\xF4\x01\x30\x75\x2A\x01", 8)});
  out.push_back(qnav::fuzz::Seed{"dbc-line", "\x80" "BO_ 258 QNAV_DEPTH_IN: 8 DEPTH\n SG_ Depth : 7|24@0+ (0.001,0) [0|11000] \"m\" QNAV\n"
                                             "BA_ \"GenMsgCycleTime\" BO_ 258 100;\n"});
  const std::string dbc = qnav::fuzz::read_prefix(qnav::fuzz::source_dir() + "/docs/qnav.dbc", 1u << 16);
  if (!dbc.empty()) out.push_back(qnav::fuzz::Seed{"qnav.dbc", "\x80" + dbc});
}
QNAV_FUZZ_TARGET(qnavcan, 1000)
