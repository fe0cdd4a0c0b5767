// QnavCanPublisher: the output side of qnav's CAN interface. Holds the latest value of each output
// message (NAV_STATUS, ROUTE_GUIDANCE, ROUTE_STATUS, VO_STEP, MAP_POSE, MAP_STATUS, HEALTH, HEARTBEAT), and poll(now_ns)
// sends each one whose DBC period (GenMsgCycleTime) has elapsed, in that order (ROUTE_STATUS right
// after its companion ROUTE_GUIDANCE), filling the rolling Counter itself. A full TX queue
// (kCapacityExceeded from the bus) is counted as tx_busy and retried at the next poll; an encode
// failure (a value outside the DBC range) is counted as encode_error and the message is not sent.
// Messages never set are not sent. QNAV_VO_STEP is an increment, not a state: each set() value is
// sent once (at most one frame per DBC period; a later set() before it went out replaces it) and never
// repeated, so a receiver that sums the frames gets the whole path; vo_pending() says whether the
// last value is still waiting (the caller accumulates into it) or went out (the caller starts anew).
// QNAV_MAP_POSE and QNAV_MAP_STATUS are per-frame events (DBC cycle 0): each set() value is sent once
// at the next poll, MAP_POSE right before MAP_STATUS, never repeated (a later set() before it went
// out replaces it: the autopilot sees the gap in MAP_STATUS.FrameSeq).
// poll() is O(8 messages x signals); no heap.
#pragma once

#include <cstdint>

#include "drivers/qnavcan/messages.hpp"
#include "hal/core/can.hpp"
#include "nav/core/counters.hpp"

namespace qnav::drivers::qnavcan {

enum class TxCounter : std::uint8_t { kSent, kTxBusy, kEncodeError, kBusError, kCount };
inline constexpr const char* kTxCounterNames[] = {"sent", "tx_busy", "encode_error", "bus_error"};

class QnavCanPublisher {
 public:
  explicit QnavCanPublisher(hal::CanBus& bus) noexcept : bus_(bus) {}

  void set(const NavStatus& m) noexcept { nav_ = m, has_[kNav] = true; }
  void set(const RouteGuidance& m) noexcept { guidance_ = m, has_[kGuidance] = true; }
  void set(const RouteStatus& m) noexcept { route_status_ = m, has_[kRouteStatus] = true; }
  void set(const VoStep& m) noexcept { vo_ = m, has_[kVo] = true; }
  bool vo_pending() const noexcept { return has_[kVo]; }
  // A map frame's pair: MAP_POSE and MAP_STATUS carry one Counter, taken when the pose is set (a pair
  // replaced before it went out is skipped whole: the autopilot sees the Counter jump, never a pose
  // paired with another frame's status).
  void set(const MapPose& m) noexcept { map_pose_ = m, has_[kMapPose] = true, map_counter_ = map_next_counter_++; }
  void set(const MapStatus& m) noexcept { map_status_ = m, has_[kMapStatus] = true; }
  void set(const Health& m) noexcept { health_ = m, has_[kHealth] = true; }
  void set(const Heartbeat& m) noexcept { heartbeat_ = m, has_[kHeartbeat] = true; }

  // Sends what is due; returns the number of frames sent.
  int poll(std::int64_t now_ns) noexcept;
  const CounterSet<TxCounter>& counters() const noexcept { return counters_; }

 private:
  // Output slots, in sending order.
  enum Output : int { kNav, kGuidance, kRouteStatus, kVo, kMapPose, kMapStatus, kHealth, kHeartbeat };
  static constexpr int kOutputs = 8;
  static constexpr bool is_event(int i) noexcept { return i == kVo || i == kMapPose || i == kMapStatus; }
  Status encode_output(int i, hal::CanFrame& f) noexcept;
  hal::CanBus& bus_;
  NavStatus nav_;
  RouteGuidance guidance_;
  RouteStatus route_status_;
  VoStep vo_;
  MapPose map_pose_;
  MapStatus map_status_;
  Health health_;
  Heartbeat heartbeat_;
  bool has_[kOutputs] = {};
  bool sent_once_[kOutputs] = {};
  std::int64_t last_ns_[kOutputs] = {};
  std::uint8_t counter_[kOutputs] = {};
  std::uint8_t map_counter_ = 0, map_next_counter_ = 0;
  CounterSet<TxCounter> counters_{kTxCounterNames};
};

}  // namespace qnav::drivers::qnavcan
