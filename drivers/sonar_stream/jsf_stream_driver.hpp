// JsfStreamDriver: reads an EdgeTech JSF message stream from a hal::SerialPort (a serial link, or
// TcpClientPort for the sonar's TCP data port), frames it (sidescan::JsfFramer: resync, oversize
// skip, counters) and pairs port/starboard records into sonar::SonarPing (sidescan::JsfPingAssembler),
// handing each complete ping to a sink -- the tile builder -- inside poll().
// poll(): waits at most timeout_ms for the first chunk, then reads at most kMaxReadsPerPoll chunks of
// kChunkBytes without waiting. The ping's spans are valid only during the sink call.
// Stamps: arrival_ns = monotonic time of the read that completed the ping; sample_ns = the ping's JSF
// time (the sonar's wall clock, passed on in SonarPing::stamp_ns untouched) mapped onto the monotonic
// clock by hal::SensorClockMap (the smallest arrival - sonar offset seen), so that pings a lagging
// reader gets in one read keep their spacing; a ping without a time is stamped with its arrival.
// init() allocates the framer and assembler buffers; nothing allocates afterwards.
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivers/sidescan/jsf_framer.hpp"
#include "hal/core/clock_map.hpp"
#include "hal/core/serial.hpp"
#include "hal/core/stamp.hpp"

namespace qnav::drivers::sonar_stream {

struct JsfStreamConfig {
  std::size_t max_message_bytes = 256 * 1024;
  std::size_t max_samples_per_side = 16384;
  int subsystem = -1;  // 20 low / 21 high frequency side-scan; -1 = the first seen
};

using PingSink = void (*)(void* ctx, const sonar::SonarPing& ping, const hal::SampleStamp& stamp);

class JsfStreamDriver {
 public:
  static constexpr std::size_t kChunkBytes = 4096;
  static constexpr int kMaxReadsPerPoll = 64;

  Status init(const JsfStreamConfig& config) noexcept;
  // Returns the number of pings delivered to `sink` by this call.
  Result<int> poll(hal::SerialPort& port, int timeout_ms, PingSink sink, void* ctx) noexcept;

  const CounterSet<sidescan::JsfCounter>& framer_counters() const noexcept { return framer_.counters(); }
  const CounterSet<sidescan::JsfPingCounter>& ping_counters() const noexcept { return assembler_.counters(); }
  std::uint64_t bytes() const noexcept { return bytes_; }
  std::uint32_t pings() const noexcept { return pings_; }
  // Times the sonar's clock stepped (a restarted sonar, a replayed recording) and the map restarted.
  std::uint32_t clock_restarts() const noexcept { return clock_.restarts(); }

 private:
  sidescan::JsfFramer framer_;
  sidescan::JsfPingAssembler assembler_;
  std::uint8_t chunk_[kChunkBytes] = {};
  hal::SensorClockMap clock_;
  bool ready_ = false;
  std::uint64_t bytes_ = 0;
  std::uint32_t pings_ = 0;
};

}  // namespace qnav::drivers::sonar_stream
