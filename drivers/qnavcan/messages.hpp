// qnav's CAN messages as typed structs, packed/unpacked through the signal tables that mirror
// docs/qnav.dbc (ids, DLC, every signal's start/length/byte order/sign/factor/offset/range).
// Inputs (qnav receives): ATTITUDE_IN 0x100, RATES_IN 0x101, DEPTH_IN 0x102, MODE_CMD 0x110.
// Outputs (qnav sends):   NAV_STATUS 0x200, ROUTE_GUIDANCE 0x201, VO_STEP 0x202, HEALTH 0x210,
//                         HEARTBEAT 0x2FF.
// decode_*(): kNotFound (other id), kTruncated (frame shorter than the DBC's DLC), kOutOfRange (a
// signal outside its DBC range), kUnsupported (extended/FD/RTR frame). encode_*(): kOutOfRange when a
// value does not fit. All O(signals * 64), no heap.
#pragma once

#include <cstdint>

#include "drivers/qnavcan/signal_codec.hpp"
#include "hal/core/can.hpp"

namespace qnav::drivers::qnavcan {

enum class Mode : std::uint8_t { kIdle = 0, kTeach = 1, kRepeat = 2, kMap = 3, kHold = 4 };

struct AttitudeIn {
  double roll_rad = 0, pitch_rad = 0, heading_rad = 0;
  std::uint8_t counter = 0;
  bool valid = false;
};
struct RatesIn {
  double roll_rate_radps = 0, pitch_rate_radps = 0, yaw_rate_radps = 0;
  std::uint8_t counter = 0;
};
struct DepthIn {
  double depth_m = 0, altitude_m = 0;
  std::uint8_t counter = 0;
  bool depth_valid = false, altitude_valid = false;
};
struct ModeCmd {
  Mode mode = Mode::kIdle;
  bool reset_nav = false;
  std::uint16_t route_id = 0;
  std::uint8_t counter = 0;
};
struct NavStatus {
  Mode state = Mode::kIdle;
  bool localised = false;
  double confidence_pct = 0;
  std::uint16_t node_index = 0;
  std::uint16_t fault_flags = 0;
  std::uint8_t counter = 0;
};
struct RouteGuidance {
  double cross_track_m = 0, heading_error_rad = 0, dist_to_next_m = 0;
  std::uint16_t target_node = 0;
};
struct VoStep {
  double dx_m = 0, dy_m = 0, dyaw_rad = 0;
  std::uint8_t inliers = 0;
  std::uint8_t counter = 0;
};
struct Health {
  std::uint16_t fault_flags = 0, rejected_inputs = 0, deadline_misses = 0;
  double cpu_load_pct = 0;
  bool leak = false, bus_off = false;
};
struct Heartbeat {
  std::uint32_t uptime_s = 0;
  Mode state = Mode::kIdle;
  std::uint8_t sw_major = 0, sw_minor = 0, counter = 0;
};

// Fault flag bits (NAV_STATUS.FaultFlags, HEALTH.FaultFlags).
namespace fault {
constexpr std::uint16_t kLeak = 1u << 0;
constexpr std::uint16_t kSensorTimeout = 1u << 1;
constexpr std::uint16_t kDeadlineMiss = 1u << 2;
constexpr std::uint16_t kBusOff = 1u << 3;
constexpr std::uint16_t kRouteDamaged = 1u << 4;
}  // namespace fault

constexpr std::uint32_t kIdAttitudeIn = 0x100, kIdRatesIn = 0x101, kIdDepthIn = 0x102, kIdModeCmd = 0x110;
constexpr std::uint32_t kIdNavStatus = 0x200, kIdRouteGuidance = 0x201, kIdVoStep = 0x202, kIdHealth = 0x210,
                        kIdHeartbeat = 0x2FF;

// Every message of docs/qnav.dbc, in file order.
Span<const MessageDef> all_messages() noexcept;
const MessageDef* find_message(std::uint32_t id) noexcept;

Status decode(const hal::CanFrame& f, AttitudeIn& out) noexcept;
Status decode(const hal::CanFrame& f, RatesIn& out) noexcept;
Status decode(const hal::CanFrame& f, DepthIn& out) noexcept;
Status decode(const hal::CanFrame& f, ModeCmd& out) noexcept;
Status decode(const hal::CanFrame& f, NavStatus& out) noexcept;
Status decode(const hal::CanFrame& f, RouteGuidance& out) noexcept;
Status decode(const hal::CanFrame& f, VoStep& out) noexcept;
Status decode(const hal::CanFrame& f, Health& out) noexcept;
Status decode(const hal::CanFrame& f, Heartbeat& out) noexcept;

Status encode(const AttitudeIn& m, hal::CanFrame& f) noexcept;
Status encode(const RatesIn& m, hal::CanFrame& f) noexcept;
Status encode(const DepthIn& m, hal::CanFrame& f) noexcept;
Status encode(const ModeCmd& m, hal::CanFrame& f) noexcept;
Status encode(const NavStatus& m, hal::CanFrame& f) noexcept;
Status encode(const RouteGuidance& m, hal::CanFrame& f) noexcept;
Status encode(const VoStep& m, hal::CanFrame& f) noexcept;
Status encode(const Health& m, hal::CanFrame& f) noexcept;
Status encode(const Heartbeat& m, hal::CanFrame& f) noexcept;

// Generic decode of any known message into physical values (one per signal, table order); used by
// `qnav can decode`. `values` must hold at least the message's signal count.
Status decode_generic(const hal::CanFrame& f, const MessageDef*& def, double* values, std::size_t capacity) noexcept;

}  // namespace qnav::drivers::qnavcan
