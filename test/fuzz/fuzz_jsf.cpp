// libFuzzer: any byte string as a JSF stream, fed in chunks whose sizes come from the input.
#include <cstddef>
#include <cstdint>

#include "drivers/sidescan/jsf_framer.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
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
      while (framer.next(m)) (void)pings.add(m);
      if (used == 0 && !c.empty()) __builtin_trap();  // the framer must always make progress
    }
  }
  return 0;
}
