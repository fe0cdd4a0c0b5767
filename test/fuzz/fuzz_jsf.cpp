// Any byte string as a JSF file: the framer fed in chunks of one size (from the first byte), the
// port/starboard ping assembler behind it, and the pure message decoders on the same bytes.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "drivers/sidescan/jsf_framer.hpp"
#include "test/fuzz/fuzz_support.hpp"
#include "test/fuzz/sonar_seeds.hpp"

int qnav_fuzz_jsf(const std::uint8_t* data, std::size_t size) {
  using namespace qnav;
  using namespace qnav::sidescan;
  if (size < 1) return 0;
  JsfFramer framer;
  JsfPingAssembler pings;
  if (!framer.init(1u << 16) || !pings.init(4096)) return 0;
  const std::size_t chunk = 1 + data[0] % 64;
  Span<const std::uint8_t> rest(data + 1, size - 1);
  while (!rest.empty()) {
    Span<const std::uint8_t> c = rest.subspan(0, chunk);
    rest = rest.subspan(c.size(), rest.size() - c.size());
    while (!c.empty()) {
      const std::size_t used = framer.feed(c);
      c = c.subspan(used, c.size() - used);
      JsfMessageView m;
      bool delivered = false;
      while (framer.next(m)) {
        (void)pings.add(m);
        delivered = true;
      }
      // Progress: bytes taken, or a message completed from bytes already held.
      if (used == 0 && !delivered && !c.empty()) __builtin_trap();
    }
  }
  const Span<const std::uint8_t> all(data + 1, size - 1);
  Result<JsfMessageHeader> h = parse_jsf_message_header(all);
  if (h && all.size() >= kJsfHeaderBytes) {
    static std::vector<float> samples(4096);
    JsfSonarData d;
    const std::size_t body = all.size() - kJsfHeaderBytes;
    (void)parse_jsf_sonar_data(h.value(), all.subspan(kJsfHeaderBytes, body), d, Span<float>(samples.data(), samples.size()));
  }
  return 0;
}

static void seeds_jsf(qnav::fuzz::Seeds& out) {
  out.push_back(qnav::fuzz::Seed{"synthetic-3-pings.jsf", std::string(1, '\x07') + qnav::fuzz::synthetic_jsf(3, 64)});
}
QNAV_FUZZ_TARGET(jsf, 100)
