// PD6 text: the input split into lines, fed to one parser (state carries across lines).
#include <cmath>

#include "drivers/dvl/pd6_parser.hpp"
#include "test/fuzz/fuzz_support.hpp"


int qnav_fuzz_pd6(const std::uint8_t* data, std::size_t size) {
  using namespace qnav::drivers::dvl;
  Pd6Parser p;
  Pd6Ensemble e;
  std::size_t start = 0;
  for (std::size_t i = 0; i <= size; ++i) {
    if (i == size || data[i] == '\n') {
      auto r = p.parse_line(reinterpret_cast<const char*>(data + start), i - start, static_cast<std::int64_t>(i), e);
      if (r.is_ok() && r.value() == Pd6Result::kEnsemble && (!std::isfinite(e.velocity.vx_mps) || e.velocity.altitude_m < 0))
        __builtin_trap();
      start = i + 1;
    }
  }
  return 0;
}

static void seeds_pd6(qnav::fuzz::Seeds& out) {
  out.push_back(qnav::fuzz::Seed{"ensemble", ":SA, +0.00, +0.00,  0.00\n:TS,22020812061800, 0.0, +0.0,   0.0,1475.0,  0\n"
                                             ":BI,  +123,  -420, +2000,    +0,A\n:BD,       +0.00,       +0.00,       +0.00,   5.32,  0.00\n"});
}
QNAV_FUZZ_TARGET(pd6, 1000)
