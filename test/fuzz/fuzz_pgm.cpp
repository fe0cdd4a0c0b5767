// PGM headers (the replay camera's file format).
#include "hal/sim/pgm_sequence_camera.hpp"
#include "test/fuzz/fuzz_support.hpp"


int qnav_fuzz_pgm(const std::uint8_t* data, std::size_t size) {
  int w = 0, h = 0;
  std::size_t off = 0;
  if (qnav::hal::parse_pgm_header(data, size, w, h, off).is_ok() && (off > size || w <= 0 || h <= 0)) __builtin_trap();
  return 0;
}

static void seeds_pgm(qnav::fuzz::Seeds& out) {
  out.push_back(qnav::fuzz::Seed{"header", std::string("P5\n# c\n12 7\n255\n\x01\x02")});
  out.push_back(qnav::fuzz::Seed{"inline", "P5 1 1 255 x"});
}
QNAV_FUZZ_TARGET(pgm, 1000)
