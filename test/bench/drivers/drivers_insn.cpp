// drivers_insn KIND N: runs one driver parser N times on a fixed valid input and prints a checksum
// of the results (so nothing is optimised away). KIND: candump | qnavcan | dronecan | wl | pd6.
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "drivers/dronecan/ahrs_receiver.hpp"
#include "drivers/dvl/pd6_parser.hpp"
#include "drivers/dvl/wl_parser.hpp"
#include "drivers/qnavcan/receiver.hpp"
#include "hal/core/candump.hpp"

using namespace qnav;

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: drivers_insn candump|qnavcan|dronecan|wl|pd6 N\n");
    return 2;
  }
  const char* kind = argv[1];
  const long n = std::strtol(argv[2], nullptr, 10);
  double acc = 0;
  if (std::strcmp(kind, "candump") == 0) {
    const char* line = "(1436509052.249713) vcan0 1F334455#1122334455667788";
    const std::size_t len = std::strlen(line);
    hal::CanLogRecord r;
    for (long i = 0; i < n; ++i) acc += hal::parse_can_log_line(line, len, r).is_ok() ? r.frame.data[7] : -1;
  } else if (std::strcmp(kind, "qnavcan") == 0) {
    drivers::qnavcan::QnavCanReceiver rx;
    hal::CanRxFrame f;
    drivers::qnavcan::AttitudeIn a{-0.1, 0.05, 3.0, 0, true};
    if (!drivers::qnavcan::encode(a, f.frame).is_ok()) return 1;
    for (long i = 0; i < n; ++i) {
      f.frame.data[6] = static_cast<std::uint8_t>(i);  // the rolling counter
      f.stamp.sample_ns = (i + 1) * 20000000LL;
      acc += rx.on_frame(f).is_ok() ? 1 : 0;
    }
  } else if (std::strcmp(kind, "dronecan") == 0) {
    namespace dc = drivers::dronecan;
    dc::AhrsSolution s;
    s.orientation_xyzw[3] = 1;
    std::uint8_t payload[dc::kSolutionMaxBytes];
    const std::size_t len = dc::encode_solution(s, true, payload, sizeof payload);
    hal::CanFrame frames[32][16];
    std::size_t k = 0;
    for (int t = 0; t < 32; ++t) k = dc::split_transfer(dc::kSolutionSignature, dc::make_message_id(16, 1000, 42),
                                                        static_cast<std::uint8_t>(t), payload, len, frames[t], 16);
    dc::DroneCanAhrsReceiver rx;
    for (long i = 0; i < n; ++i)
      for (std::size_t j = 0; j < k; ++j) {
        hal::CanRxFrame f;
        f.frame = frames[i % 32][j];
        f.stamp.sample_ns = i * 1000000LL + static_cast<long>(j);
        acc += static_cast<double>(rx.on_frame(f));
      }
  } else if (std::strcmp(kind, "wl") == 0) {
    drivers::dvl::WlParser p;
    drivers::dvl::WlMessage m;
    const char* line = "wrz,0.120,-0.400,2.000,y,1.30,1.855,1e-07;0;1.4;0;1.2;0;0.2;0;1e+09,7,14,123.00,1*50";
    const std::size_t len = std::strlen(line);
    for (long i = 0; i < n; ++i) {
      drivers::dvl::WlParser fresh;  // same input each time: a fresh parser avoids the stale check
      acc += fresh.parse_line(line, len, 0, m).is_ok() ? m.velocity.vx_mps : -1;
    }
    (void)p;
  } else if (std::strcmp(kind, "pd6") == 0) {
    static const char* kLines[] = {":SA, +0.00, +0.00,  0.00", ":TS,22020812061800, 0.0, +0.0,   0.0,1475.0,  0",
                                   ":WI,    +0,    +0,    +0,    +0,V", ":WS,    +0,    +0,    +0,V", ":WE,    +0,    +0,    +0,V",
                                   ":WD,       +0.00,       +0.00,       +0.00,   0.00,  0.00",
                                   ":BI,  +123,  -420, +2000,    +0,A", ":BS,  -420,  +123, +2000,A", ":BE,    +0,    +0,    +0,V",
                                   ":BD,       +0.00,       +0.00,       +0.00,   5.32,  0.00"};
    drivers::dvl::Pd6Ensemble e;
    for (long i = 0; i < n; ++i) {
      drivers::dvl::Pd6Parser p;  // fresh parser: the same :TS would otherwise be stale
      for (const char* l : kLines) {
        auto r = p.parse_line(l, std::strlen(l), 0, e);
        acc += r.is_ok() ? static_cast<double>(r.value()) : -1;
      }
    }
  } else {
    std::fprintf(stderr, "unknown kind %s\n", kind);
    return 2;
  }
  std::printf("%s x %ld: %.3f\n", kind, n, acc);
  return 0;
}
