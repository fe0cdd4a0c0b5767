// The daemon's live side-scan input: a JSF byte stream through drivers/sonar_stream's JsfStreamDriver
// (framer + ping assembler) from a serial port that splits the stream at random points (the first
// 4 bytes seed the split sizes, 1..byte 5 x 64 bytes each). Every delivered ping must have equal sides,
// and the driver must deliver the same pings (numbers, in order) as the framer and assembler fed the
// whole stream at once: where a stream is cut never changes what is read from it.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "drivers/sonar_stream/jsf_stream_driver.hpp"
#include "test/fuzz/fuzz_support.hpp"
#include "test/fuzz/sonar_seeds.hpp"
#include "test/fuzz/split_port.hpp"

namespace {
struct Seen {
  std::vector<std::uint32_t> pings;
  float sum = 0.0f;
};

void sink(void* ctx, const qnav::sonar::SonarPing& ping, const qnav::hal::SampleStamp&) {
  if (ping.port.size() != ping.stbd.size()) __builtin_trap();
  Seen& seen = *static_cast<Seen*>(ctx);
  for (std::size_t i = 0; i < ping.port.size(); ++i) seen.sum += ping.port[i] + ping.stbd[i];  // every sample readable
  seen.pings.push_back(ping.ping_number);
}

// The reference: the same framer and assembler settings, the whole stream in one piece.
std::vector<std::uint32_t> reference_pings(const std::uint8_t* data, std::size_t size, const qnav::drivers::sonar_stream::JsfStreamConfig& c) {
  using namespace qnav;
  std::vector<std::uint32_t> out;
  sidescan::JsfFramer framer;
  sidescan::JsfPingAssembler pings;
  if (!framer.init(c.max_message_bytes) || !pings.init(c.max_samples_per_side, c.subsystem)) return out;
  Span<const std::uint8_t> rest(data, size);
  for (;;) {
    const std::size_t used = framer.feed(rest);
    rest = rest.subspan(used, rest.size() - used);
    bool delivered = false;
    sidescan::JsfMessageView m;
    while (framer.next(m)) {
      delivered = true;
      if (pings.add(m)) out.push_back(pings.ping().ping_number);
    }
    if (used == 0 && !delivered) break;
  }
  return out;
}
}  // namespace

int qnav_fuzz_jsf_stream(const std::uint8_t* data, std::size_t size) {
  using namespace qnav;
  fuzz::Cursor in(data, size);
  const std::uint32_t seed = in.u16() | static_cast<std::uint32_t>(in.u16()) << 16;
  const std::size_t max_piece = 1 + static_cast<std::size_t>(in.u8()) * 64;
  fuzz::SplitPort port(in.here(), in.remaining(), seed, max_piece);
  drivers::sonar_stream::JsfStreamConfig c;
  c.max_message_bytes = 64u << 10;
  c.max_samples_per_side = 2048;
  drivers::sonar_stream::JsfStreamDriver driver;
  if (!driver.init(c)) return 0;
  Seen seen;
  std::uint64_t before = 0;
  for (int polls = 0; !port.finished(); ++polls) {
    if (!driver.poll(port, 0, sink, &seen)) break;
    if (driver.bytes() == before || polls > 1000000) __builtin_trap();  // every poll reads the port
    before = driver.bytes();
  }
  if (seen.pings != reference_pings(in.here(), in.remaining(), c)) __builtin_trap();
  return 0;
}

static void seeds_jsf_stream(qnav::fuzz::Seeds& out) {
  const std::string jsf = qnav::fuzz::synthetic_jsf(3, 64);
  out.push_back(qnav::fuzz::Seed{"synthetic-3-pings-small-pieces", std::string("\x11\x22\x33\x44\x00", 5) + jsf});
  out.push_back(qnav::fuzz::Seed{"synthetic-3-pings-big-pieces", std::string("\x55\x66\x77\x08\x20", 5) + jsf});
  // Garbage before the stream and a torn message in the middle.
  out.push_back(qnav::fuzz::Seed{"resync", std::string("\x01\x02\x03\x04\x03", 5) + "xx\x01\x16" + jsf.substr(0, 300) + jsf});
}
QNAV_FUZZ_TARGET(jsf_stream, 40)
