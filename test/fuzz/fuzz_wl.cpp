// Water Linked sentences: the raw input as one line, and with a correct checksum appended so the
// field parsing behind the CRC gets exercised too.
#include <cmath>
#include <cstring>

#include "drivers/dvl/wl_parser.hpp"
#include "test/fuzz/fuzz_support.hpp"


int qnav_fuzz_wl(const std::uint8_t* data, std::size_t size) {
  using namespace qnav::drivers::dvl;
  static WlParser p;
  WlMessage m;
  p.parse_line(reinterpret_cast<const char*>(data), size, 0, m).ignore();
  if (size > 200) return 0;
  char body[256], line[300];
  std::memcpy(body, data, size);
  body[size] = '\0';
  if (std::strlen(body) != size) return 0;
  const std::size_t n = wl_with_checksum(body, line, sizeof line);
  if (n > 0 && p.parse_line(line, n, 0, m).is_ok() && m.kind == WlKind::kVelocity) {
    if (!std::isfinite(m.velocity.vx_mps) || !std::isfinite(m.velocity.altitude_m)) __builtin_trap();
  }
  return 0;
}

static void seeds_wl(qnav::fuzz::Seeds& out) {
  for (const char* s : {"wrz,0.120,-0.400,2.000,y,1.30,1.855,1e-07;0;1.4;0;1.2;0;0.2;0;1e+09,7,14,123.00,1*50",
                        "wru,0,0.070,1.10,-40,-95*9c", "wrp,49056.809,0.41,0.15,1.23,0.4,53.9,13.0,19.3,0*de",
                        "wrz,0.120,-0.400,2.000,y,1.30,1.855,1e-07;0;1.4;0;1.2;0;0.2;0;1e+09,7,14,123.00,1"})
    out.push_back(qnav::fuzz::Seed{"sentence" + std::to_string(out.size()), s});
}
QNAV_FUZZ_TARGET(wl, 500)
