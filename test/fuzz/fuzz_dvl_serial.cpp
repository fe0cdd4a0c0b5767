// The daemon's DVL input: a serial byte stream split at random points (SplitPort) through
// DvlSerialDriver: line assembler (over-long lines, CR/LF, empty lines) -> Water Linked or PD6 parser
// (byte 5 chooses) -> the sample queue. Every queued sample must be finite with a plausible altitude.
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "drivers/dvl/dvl_driver.hpp"
#include "test/fuzz/fuzz_support.hpp"
#include "test/fuzz/split_port.hpp"

int qnav_fuzz_dvl_serial(const std::uint8_t* data, std::size_t size) {
  using namespace qnav;
  using namespace qnav::drivers::dvl;
  fuzz::Cursor in(data, size);
  const std::uint32_t seed = in.u16() | static_cast<std::uint32_t>(in.u16()) << 16;
  const DvlProtocol protocol = (in.u8() & 1) != 0 ? DvlProtocol::kPd6 : DvlProtocol::kWaterLinked;
  fuzz::SplitPort port(in.here(), in.remaining(), seed, 300);
  DvlSerialDriver driver(port, protocol);
  for (int polls = 0; !port.finished(); ++polls) {
    if (!driver.poll(0) || polls > 1000000) break;
    DvlVelocity v;
    while (driver.pop(v)) {
      if (!std::isfinite(v.vx_mps) || !std::isfinite(v.vy_mps) || !std::isfinite(v.vz_mps) || !std::isfinite(v.altitude_m))
        __builtin_trap();
    }
  }
  return 0;
}

static void seeds_dvl_serial(qnav::fuzz::Seeds& out) {
  const std::string wl =
      "wrz,0.120,-0.400,2.000,y,1.30,1.855,1e-07;0;1.4;0;1.2;0;0.2;0;1e+09,7,14,123.00,1*50\r\n"
      "wru,0,0.070,1.10,-40,-95*9c\n"
      "wrp,49056.809,0.41,0.15,1.23,0.4,53.9,13.0,19.3,0*de\n"
      "wrz,0.120,-0.400,2.000,y,1.30,1.855,1e-07;0;1.4;0;1.2;0;0.2;0;1e+09,7,14,123.00,1*50\n";
  const std::string pd6 =
      ":SA, +0.00, +0.00,  0.00\r\n:TS,22020812061800, 0.0, +0.0,   0.0,1475.0,  0\r\n"
      ":BI,  +123,  -420, +2000,    +0,A\r\n:BD,       +0.00,       +0.00,       +0.00,   5.32,  0.00\r\n";
  out.push_back(qnav::fuzz::Seed{"waterlinked", std::string("\x12\x34\x56\x78\x00", 5) + wl});
  out.push_back(qnav::fuzz::Seed{"pd6", std::string("\x9a\xbc\xde\xf0\x01", 5) + pd6 + pd6});
  out.push_back(qnav::fuzz::Seed{"overlong-then-wl", std::string("\x01\x00\x00\x00\x00", 5) + std::string(400, 'w') + "\n" + wl});
}
QNAV_FUZZ_TARGET(dvl_serial, 300)
