// IEEE 754 binary16 <-> float (DSDL float16). Round-to-nearest-even on encode, overflow -> inf,
// NaN preserved; subnormals handled both ways. O(1), no heap, no host-endianness dependence.
#pragma once

#include <cstdint>

namespace qnav::drivers::dronecan {

float half_to_float(std::uint16_t h) noexcept;
std::uint16_t float_to_half(float f) noexcept;

}  // namespace qnav::drivers::dronecan
