// The daemon's live side-scan input: a JSF byte stream through drivers/sonar_stream's JsfStreamDriver
// (framer + ping assembler) from a serial port that splits the stream at random points (the first
// 4 bytes seed the split sizes, 1..byte 5 x 64 bytes each). Every delivered ping must have equal sides.
#include <cstddef>
#include <cstdint>

#include "drivers/sonar_stream/jsf_stream_driver.hpp"
#include "test/fuzz/fuzz_support.hpp"
#include "test/fuzz/sonar_seeds.hpp"
#include "test/fuzz/split_port.hpp"

namespace {
void sink(void* ctx, const qnav::sonar::SonarPing& ping, const qnav::hal::SampleStamp&) {
  if (ping.port.size() != ping.stbd.size()) __builtin_trap();
  float sum = 0.0f;  // every sample readable (ASan checks the spans)
  for (std::size_t i = 0; i < ping.port.size(); ++i) sum += ping.port[i] + ping.stbd[i];
  *static_cast<float*>(ctx) += sum;
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
  float sum = 0.0f;
  std::uint64_t before = 0;
  for (int polls = 0; !port.finished(); ++polls) {
    if (!driver.poll(port, 0, sink, &sum)) break;
    if (driver.bytes() == before || polls > 1000000) __builtin_trap();  // every poll reads the port
    before = driver.bytes();
  }
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
