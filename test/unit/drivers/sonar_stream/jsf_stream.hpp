// Builds a JSF byte stream of side-scan pings (port + starboard message 80 each) for the tests.
#pragma once

#include <vector>

#include "drivers/sidescan/jsf_parser.hpp"

namespace qnav_test {
inline std::vector<std::uint8_t> jsf_stream(int pings, int samples, bool garbage_between) {
  std::vector<std::uint8_t> out;
  std::vector<float> s(static_cast<std::size_t>(samples));
  std::vector<std::uint8_t> msg(qnav::sidescan::jsf_sonar_message_bytes(static_cast<std::size_t>(samples)));
  for (int p = 0; p < pings; ++p) {
    for (int ch = 0; ch < 2; ++ch) {
      for (int i = 0; i < samples; ++i) s[static_cast<std::size_t>(i)] = static_cast<float>(100 * ch + p + i % 7);
      qnav::sidescan::JsfWriteSonar w;
      w.subsystem = 20;
      w.channel = static_cast<std::uint8_t>(ch);
      w.ping_number = static_cast<std::uint32_t>(1000 + p);
      w.stamp_ns = 1700000000000000000ULL + static_cast<std::uint64_t>(p) * 100000000ULL;
      w.altitude_m = 10.0f;
      w.samples = qnav::Span<const float>(s.data(), s.size());
      auto n = qnav::sidescan::encode_jsf_sonar_message(qnav::Span<std::uint8_t>(msg.data(), msg.size()), w);
      if (!n.is_ok()) return {};
      out.insert(out.end(), msg.begin(), msg.begin() + static_cast<std::ptrdiff_t>(n.value()));
    }
    if (garbage_between && p % 3 == 1) {
      const std::uint8_t junk[] = {0x01, 0x16, 0xFF, 0x00, 0x42, 0x16, 0x01, 0x13};
      out.insert(out.end(), junk, junk + sizeof junk);
    }
  }
  return out;
}
}  // namespace qnav_test
