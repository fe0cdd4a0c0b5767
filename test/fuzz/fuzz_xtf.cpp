// Any byte string as an XTF file through the reader (records, counted skips or a clear error; it
// must terminate: every step consumes input), and the pure packet decoders on the same bytes.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "drivers/sidescan/xtf_reader.hpp"
#include "test/fuzz/fuzz_support.hpp"
#include "test/fuzz/sonar_seeds.hpp"

int qnav_fuzz_xtf(const std::uint8_t* data, std::size_t size) {
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
  for (std::size_t guard = 0;; ++guard) {
    if (guard > size + 2) __builtin_trap();  // the reader must consume input on every call
    const Result<bool> r = reader.next(rec, Span<float>(port.data(), port.size()), Span<float>(stbd.data(), stbd.size()));
    if (r.is_ok() && !r.value()) break;
  }
  (void)parse_xtf_packet_header(Span<const std::uint8_t>(data, size));
  (void)parse_xtf_attitude(Span<const std::uint8_t>(data, size));
  (void)parse_xtf_navigation(Span<const std::uint8_t>(data, size));
  return 0;
}

static void seeds_xtf(qnav::fuzz::Seeds& out) {
  qnav::fuzz::add_real_xtf_seeds(out, 3);
  out.push_back(qnav::fuzz::Seed{"synthetic-4-pings.xtf", qnav::fuzz::synthetic_xtf(4, 64)});
}
QNAV_FUZZ_TARGET(xtf, 60)
