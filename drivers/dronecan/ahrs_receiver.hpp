// DroneCanAhrsReceiver: a standard DroneCAN AHRS as qnav's attitude source. Feeds CAN frames through
// the Reassembler (Solution + RawIMU only), decodes complete transfers and validates them.
// Rejections, one counter each (plus the reassembler's: crc, toggle, missed_start, length, timeout..):
//   decode (payload does not parse), range (NaN/inf, |q| outside [0.9, 1.1], |rate| > 35 rad/s,
//   |accel| > 1000 m/s^2), stale (sender timestamp or transfer id repeated / not advancing).
// `node_filter` (0 = any) restricts to one AHRS node id. Per frame O(kMaxSessions + kMaxPayload);
// no heap.
#pragma once

#include <cstdint>

#include "drivers/dronecan/ahrs.hpp"
#include "drivers/dronecan/transfer.hpp"
#include "hal/core/can.hpp"

namespace qnav::drivers::dronecan {

enum class AhrsCounter : std::uint8_t { kDecode, kRange, kStale, kOtherNode, kCount };
inline constexpr const char* kAhrsCounterNames[] = {"decode", "range", "stale", "other_node"};

struct StampedSolution {
  AhrsSolution value;
  hal::SampleStamp stamp;
  std::uint8_t source_node = 0;
  bool present = false;
};
struct StampedRawImu {
  RawImu value;
  hal::SampleStamp stamp;
  std::uint8_t source_node = 0;
  bool present = false;
};

enum class AhrsUpdate : std::uint8_t { kNone, kSolution, kRawImu };

class DroneCanAhrsReceiver {
 public:
  explicit DroneCanAhrsReceiver(std::uint8_t node_filter = 0) noexcept;
  AhrsUpdate on_frame(const hal::CanRxFrame& rx) noexcept;
  const StampedSolution& solution() const noexcept { return solution_; }
  const StampedRawImu& raw_imu() const noexcept { return raw_; }
  const CounterSet<AhrsCounter>& counters() const noexcept { return counters_; }
  const Reassembler& reassembler() const noexcept { return reasm_; }
  std::uint32_t solutions() const noexcept { return n_solutions_; }
  std::uint32_t raw_imus() const noexcept { return n_raw_; }

 private:
  static const DataTypeSpec kTypes[2];
  Reassembler reasm_;
  std::uint8_t node_filter_;
  Transfer transfer_;
  StampedSolution solution_;
  StampedRawImu raw_;
  CounterSet<AhrsCounter> counters_{kAhrsCounterNames};
  std::uint32_t n_solutions_ = 0;
  std::uint32_t n_raw_ = 0;
  std::uint8_t last_tid_solution_ = 0xFF;
  std::uint8_t last_tid_raw_ = 0xFF;
};

}  // namespace qnav::drivers::dronecan
