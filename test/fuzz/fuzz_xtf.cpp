// libFuzzer: any byte string as an XTF file. The reader must return records, counted skips or a
// clear error, and must terminate (every step consumes input).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "drivers/sidescan/xtf_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace qnav;
  using namespace qnav::sidescan;
  static XtfReader reader;
  static bool ready = false;
  if (!ready) {
    XtfReaderConfig c;
    c.max_packet_bytes = 1u << 16;
    if (!reader.init(c)) return 0;
    ready = true;
  }
  static std::vector<float> port(2048), stbd(2048);
  MemorySource src(Span<const std::uint8_t>(data, size));
  if (!reader.open(src)) return 0;
  XtfRecord rec;
  for (std::size_t guard = 0; guard <= size + 1; ++guard) {
    const Result<bool> r = reader.next(rec, Span<float>(port.data(), port.size()), Span<float>(stbd.data(), stbd.size()));
    if (r.is_ok() && !r.value()) break;
  }
  // Pure entry points directly on the same bytes.
  (void)parse_xtf_packet_header(Span<const std::uint8_t>(data, size));
  (void)parse_xtf_attitude(Span<const std::uint8_t>(data, size));
  (void)parse_xtf_navigation(Span<const std::uint8_t>(data, size));
  return 0;
}
