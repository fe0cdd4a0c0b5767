// PGM headers (the replay camera's file format).
#include "fuzz_entry.hpp"
#include "hal/sim/pgm_sequence_camera.hpp"

int qnav_fuzz_pgm(const std::uint8_t* data, std::size_t size) {
  int w = 0, h = 0;
  std::size_t off = 0;
  if (qnav::hal::parse_pgm_header(data, size, w, h, off).is_ok() && (off > size || w <= 0 || h <= 0)) __builtin_trap();
  return 0;
}
QNAV_FUZZ_ENTRY(pgm)
