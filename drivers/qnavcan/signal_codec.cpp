#include "drivers/qnavcan/signal_codec.hpp"

#include <cmath>

namespace qnav::drivers::qnavcan {

std::uint16_t signal_bit_position(const SignalDef& s, std::uint8_t k) noexcept {
  if (!s.big_endian) return static_cast<std::uint16_t>(s.start_bit + k);
  // Walk from the MSB (start_bit) down `length - 1 - k` steps in sawtooth order.
  std::uint32_t pos = s.start_bit;
  const std::uint32_t steps = static_cast<std::uint32_t>(s.length - 1 - k);
  for (std::uint32_t i = 0; i < steps; ++i) pos = (pos % 8 == 0) ? pos + 15 : pos - 1;
  return static_cast<std::uint16_t>(pos);
}

bool signal_fits(const SignalDef& s, std::size_t dlc) noexcept {
  if (s.length == 0 || s.length > 64) return false;
  const std::size_t bits = dlc * 8;
  // The LSB and MSB positions bound the signal in both byte orders.
  return signal_bit_position(s, 0) < bits && signal_bit_position(s, static_cast<std::uint8_t>(s.length - 1)) < bits;
}

std::uint64_t extract_raw(const std::uint8_t* data, const SignalDef& s) noexcept {
  std::uint64_t v = 0;
  if (!s.big_endian) {
    for (std::uint8_t k = 0; k < s.length; ++k) {
      const unsigned b = s.start_bit + k;
      v |= static_cast<std::uint64_t>((data[b / 8] >> (b % 8)) & 1u) << k;
    }
  } else {
    unsigned pos = s.start_bit;
    for (std::uint8_t i = 0; i < s.length; ++i) {  // MSB first
      v = (v << 1) | ((data[pos / 8] >> (pos % 8)) & 1u);
      pos = (pos % 8 == 0) ? pos + 15 : pos - 1;
    }
  }
  return v;
}

void insert_raw(std::uint8_t* data, const SignalDef& s, std::uint64_t raw) noexcept {
  if (!s.big_endian) {
    for (std::uint8_t k = 0; k < s.length; ++k) {
      const unsigned b = s.start_bit + k;
      const std::uint8_t m = static_cast<std::uint8_t>(1u << (b % 8));
      if ((raw >> k) & 1u) data[b / 8] |= m; else data[b / 8] &= static_cast<std::uint8_t>(~m);
    }
  } else {
    unsigned pos = s.start_bit;
    for (int i = s.length - 1; i >= 0; --i) {
      const std::uint8_t m = static_cast<std::uint8_t>(1u << (pos % 8));
      if ((raw >> i) & 1u) data[pos / 8] |= m; else data[pos / 8] &= static_cast<std::uint8_t>(~m);
      pos = (pos % 8 == 0) ? pos + 15 : pos - 1;
    }
  }
}

double raw_to_physical(const SignalDef& s, std::uint64_t raw) noexcept {
  double r;
  if (s.is_signed && s.length < 64 && ((raw >> (s.length - 1)) & 1u)) {
    r = static_cast<double>(static_cast<std::int64_t>(raw | (~std::uint64_t{0} << s.length)));
  } else if (s.is_signed) {
    r = static_cast<double>(static_cast<std::int64_t>(raw));
  } else {
    r = static_cast<double>(raw);
  }
  return r * s.factor + s.offset;
}

Status encode_signal(std::uint8_t* data, const SignalDef& s, double physical) noexcept {
  if (std::isnan(physical)) return Status(StatusCode::kInvalidArgument, "NaN signal value");
  // Range check with half a step of slack so values that round to the limit are accepted.
  const double half = 0.5 * std::fabs(s.factor);
  if (physical < s.min - half || physical > s.max + half) return Status(StatusCode::kOutOfRange, "signal value outside its DBC range");
  const double rawf = std::nearbyint((physical - s.offset) / s.factor);
  const double lo = s.is_signed ? -std::ldexp(1.0, s.length - 1) : 0.0;
  const double hi = s.is_signed ? std::ldexp(1.0, s.length - 1) - 1.0 : std::ldexp(1.0, s.length) - 1.0;
  if (rawf < lo || rawf > hi) return Status(StatusCode::kOutOfRange, "signal value does not fit its bits");
  std::uint64_t raw = s.is_signed ? static_cast<std::uint64_t>(static_cast<std::int64_t>(rawf)) : static_cast<std::uint64_t>(rawf);
  if (s.length < 64) raw &= (std::uint64_t{1} << s.length) - 1u;
  insert_raw(data, s, raw);
  return Status::ok();
}

Status decode_signal(const std::uint8_t* data, const SignalDef& s, double& physical) noexcept {
  physical = raw_to_physical(s, extract_raw(data, s));
  const double half = 0.5 * std::fabs(s.factor);
  if (physical < s.min - half || physical > s.max + half) return Status(StatusCode::kOutOfRange, "signal value outside its DBC range");
  return Status::ok();
}

}  // namespace qnav::drivers::qnavcan
