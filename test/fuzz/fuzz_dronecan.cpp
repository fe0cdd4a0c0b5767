// A byte stream cut into extended CAN frames (id from the stream) through reassembly and decoding;
// also the DSDL decoders directly on the raw bytes.
#include <cstring>

#include "drivers/dronecan/ahrs_receiver.hpp"
#include "test/fuzz/fuzz_support.hpp"


int qnav_fuzz_dronecan(const std::uint8_t* data, std::size_t size) {
  using namespace qnav;
  using namespace qnav::drivers::dronecan;
  AhrsSolution s;
  decode_solution(data, size, true, s).ignore();
  RawImu m;
  decode_raw_imu(data, size, true, m).ignore();
  DroneCanAhrsReceiver rx;
  std::size_t i = 0;
  std::int64_t t = 0;
  while (i + 2 <= size) {
    hal::CanRxFrame f;
    const std::uint8_t ctl = data[i++];
    const std::uint8_t len = static_cast<std::uint8_t>(1 + (ctl & 7));
    f.frame.extended = true;
    f.frame.id = make_message_id(16, (ctl & 0x40) ? kRawImuId : kSolutionId, static_cast<std::uint8_t>(1 + (ctl >> 7)));
    const std::size_t n = size - i < len ? size - i : len;
    std::memcpy(f.frame.data, data + i, n);
    f.frame.len = static_cast<std::uint8_t>(n);
    i += n;
    t += (ctl & 0x08) ? 3000000000LL : 1000000LL;
    f.stamp.sample_ns = f.stamp.arrival_ns = t;
    rx.on_frame(f);
  }
  return 0;
}

static void seeds_dronecan(qnav::fuzz::Seeds& out) {
  std::string s(120, '\0');
  for (std::size_t i = 0; i < s.size(); ++i) s[i] = static_cast<char>(i * 37 + 11);
  out.push_back(qnav::fuzz::Seed{"ramp", s});
}
QNAV_FUZZ_TARGET(dronecan, 1000)
