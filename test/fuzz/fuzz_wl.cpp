// Water Linked sentences: the raw input as one line, and with a correct checksum appended so the
// field parsing behind the CRC gets exercised too.
#include <cmath>
#include <cstring>

#include "drivers/dvl/wl_parser.hpp"
#include "fuzz_entry.hpp"

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
QNAV_FUZZ_ENTRY(wl)
