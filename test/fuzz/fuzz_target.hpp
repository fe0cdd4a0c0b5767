// Declares the fuzz entry points; each returns 0 and must never crash, hang or read out of bounds
// on any input. QNAV_FUZZ_ENTRY(name) defines LLVMFuzzerTestOneInput in the libFuzzer build.
#pragma once

#include <cstddef>
#include <cstdint>

int qnav_fuzz_candump(const std::uint8_t* data, std::size_t size);
int qnav_fuzz_qnavcan(const std::uint8_t* data, std::size_t size);
int qnav_fuzz_dronecan(const std::uint8_t* data, std::size_t size);
int qnav_fuzz_wl(const std::uint8_t* data, std::size_t size);
int qnav_fuzz_pd6(const std::uint8_t* data, std::size_t size);
int qnav_fuzz_pgm(const std::uint8_t* data, std::size_t size);

#ifdef QNAV_FUZZ_MAIN
#define QNAV_FUZZ_ENTRY(name)                                                          \
  extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) { \
    return qnav_fuzz_##name(data, size);                                               \
  }
#else
#define QNAV_FUZZ_ENTRY(name)
#endif
