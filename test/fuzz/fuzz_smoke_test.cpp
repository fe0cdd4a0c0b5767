// Runs every fuzz entry point over seed inputs (vendor sentences, candump lines, the DBC) and a fixed
// set of deterministic mutations, in every build and on every target (the leon3 run included). A
// crash, trap or sanitizer report fails the test; the real fuzzing is the libFuzzer build.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_entry.hpp"

namespace {
using Entry = int (*)(const std::uint8_t*, std::size_t);

std::uint32_t next(std::uint32_t& s) {
  s ^= s << 13;
  s ^= s >> 17;
  s ^= s << 5;
  return s;
}

void run(Entry e, const std::vector<std::string>& seeds, int mutations) {
  std::uint32_t rng = 0x9E3779B9u;
  for (const std::string& s : seeds) {
    e(reinterpret_cast<const std::uint8_t*>(s.data()), s.size());
    for (int m = 0; m < mutations; ++m) {
      std::string x = s;
      const int edits = 1 + static_cast<int>(next(rng) % 4);
      for (int k = 0; k < edits && !x.empty(); ++k) {
        const std::size_t pos = next(rng) % x.size();
        switch (next(rng) % 5) {
          case 0: x[pos] = static_cast<char>(x[pos] ^ (1u << (next(rng) % 8))); break;
          case 1: x.erase(pos, 1 + next(rng) % 4); break;
          case 2: x.insert(pos, 1, static_cast<char>(next(rng) & 0xFF)); break;
          case 3: x.resize(pos); break;
          default: x.insert(pos, x.substr(0, next(rng) % (x.size() + 1))); break;
        }
      }
      e(reinterpret_cast<const std::uint8_t*>(x.data()), x.size());
    }
  }
}
}  // namespace

TEST(FuzzSmoke, Candump) {
  run(qnav_fuzz_candump, {"(1436509052.249713) vcan0 123#DEADBEEF", "1F334455#1122334455667788", "123##1DEADBEEF", "123#R",
                          "(1.000000) can0 20000040#0000000000000000"}, 500);
}
TEST(FuzzSmoke, QnavCan) {
  std::string frame = std::string("\x01\x00\x08", 3) + std::string("\x18\xFC\xF4\x01\x30\x75\x2A\x01", 8);
  std::string dbc = "\x80" "BO_ 258 QNAV_DEPTH_IN: 8 DEPTH\n SG_ Depth : 7|24@0+ (0.001,0) [0|11000] \"m\" QNAV\n"
                    "BA_ \"GenMsgCycleTime\" BO_ 258 100;\n";
  run(qnav_fuzz_qnavcan, {frame, dbc}, 1000);
}
TEST(FuzzSmoke, DroneCan) {
  std::string s(120, '\0');
  for (std::size_t i = 0; i < s.size(); ++i) s[i] = static_cast<char>(i * 37 + 11);
  run(qnav_fuzz_dronecan, {s}, 1000);
}
TEST(FuzzSmoke, WaterLinked) {
  run(qnav_fuzz_wl, {"wrz,0.120,-0.400,2.000,y,1.30,1.855,1e-07;0;1.4;0;1.2;0;0.2;0;1e+09,7,14,123.00,1*50",
                     "wru,0,0.070,1.10,-40,-95*9c", "wrp,49056.809,0.41,0.15,1.23,0.4,53.9,13.0,19.3,0*de",
                     "wrz,0.120,-0.400,2.000,y,1.30,1.855,1e-07;0;1.4;0;1.2;0;0.2;0;1e+09,7,14,123.00,1"}, 500);
}
TEST(FuzzSmoke, Pd6) {
  run(qnav_fuzz_pd6, {":SA, +0.00, +0.00,  0.00\n:TS,22020812061800, 0.0, +0.0,   0.0,1475.0,  0\n"
                      ":BI,  +123,  -420, +2000,    +0,A\n:BD,       +0.00,       +0.00,       +0.00,   5.32,  0.00\n"}, 1000);
}
TEST(FuzzSmoke, Pgm) {
  run(qnav_fuzz_pgm, {"P5\n# c\n12 7\n255\n\x01\x02", "P5 1 1 255 x"}, 1000);
}
