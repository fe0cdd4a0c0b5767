// qnav's CAN messages as typed structs, packed/unpacked through the signal tables that mirror
// docs/qnav.dbc (ids, DLC, every signal's start/length/byte order/sign/factor/offset/range).
// Inputs (qnav receives): ATTITUDE_IN 0x100, RATES_IN 0x101, DEPTH_IN 0x102, MODE_CMD 0x110.
// Outputs (qnav sends):   NAV_STATUS 0x200, ROUTE_GUIDANCE 0x201, VO_STEP 0x202, ROUTE_STATUS 0x203,
//                         MAP_POSE 0x204, MAP_STATUS 0x205, HEALTH 0x210, HEARTBEAT 0x2FF.
// decode_*(): kNotFound (other id), kTruncated (frame shorter than the DBC's DLC), kOutOfRange (a
// signal outside its DBC range), kUnsupported (extended/FD/RTR frame). encode_*(): kOutOfRange when a
// value does not fit (or a fault word has a reserved bit set), kInvalidArgument for NaN.
// The fault word (NAV_STATUS, HEALTH) travels as one 1-bit signal per defined bit (FaultLeak ..
// FaultCameraLost, bits 0..9 of the word at the word's own bit positions); reserved bits 10..15 are
// sent as 0 and ignored on receive. At most kMaxSignalsPerMessage signals per message.
// All O(signals * 64), no heap.
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivers/qnavcan/signal_codec.hpp"
#include "hal/core/can.hpp"

namespace qnav::drivers::qnavcan {

enum class Mode : std::uint8_t { kIdle = 0, kTeach = 1, kRepeat = 2, kMap = 3, kHold = 4, kVo = 5 };

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
  bool reverse = false;  // with Mode kRepeat: follow the route from its last node to its first
};
struct NavStatus {
  Mode state = Mode::kIdle;
  bool localised = false;
  double confidence_pct = 0;
  std::uint16_t node_index = 0;
  std::uint16_t fault_flags = 0;
  std::uint8_t counter = 0;
  std::uint8_t mode_reject = 0;  // why the last QNAV_MODE_CMD was refused (0 = accepted; DBC value table ModeReject)
};
struct RouteGuidance {
  double cross_track_m = 0, heading_error_rad = 0, dist_to_next_m = 0;
  std::uint16_t target_node = 0;
};
// ROUTE_STATUS: the companion of ROUTE_GUIDANCE, so that "holding course" is never read as "on route".
// The first four states equal nav/route/guidance.hpp's GuidanceStatus order; kNotRepeating is sent
// when qnav is not in repeat mode. SideOfRoute has its own wire numbering (nav's RouteSide is
// kPort = -1 .. kUnknown = 2): map by name, never by value.
enum class GuidanceState : std::uint8_t {
  kTracking = 0,
  kHoldCourse = 1,
  kDeadReckoned = 2,
  kRouteEnd = 3,
  kNotRepeating = 4
};
enum class SideOfRoute : std::uint8_t { kOnRoute = 0, kPort = 1, kStarboard = 2, kUnknown = 3 };
// CrossTrackSigma's largest value; encode saturates larger (and infinite) sigmas here: "unknown".
constexpr double kCrossTrackSigmaMaxM = 655.35;
struct RouteStatus {
  GuidanceState status = GuidanceState::kNotRepeating;
  SideOfRoute side = SideOfRoute::kUnknown;
  double cross_track_sigma_m = kCrossTrackSigmaMaxM;  // 1-sigma of CrossTrack; >= 655.35 = unknown
  std::uint16_t estimate_node = 0;                    // the route filter's estimated node (guidance is against it)
  std::uint16_t tile_seq = 0;                         // the sensed tile this status describes (wraps)
  std::uint8_t counter = 0;
};
const char* to_string(GuidanceState s) noexcept;  // the DBC value names: "Tracking", ..., "NotRepeating"
const char* to_string(SideOfRoute s) noexcept;    // "OnRoute", "Port", "Starboard", "Unknown"
const char* mode_name(Mode m) noexcept;           // the log's names: "idle", "teach", "repeat", "map", "hold", "vo"

struct VoStep {
  double dx_m = 0, dy_m = 0, dyaw_rad = 0;
  std::uint8_t inliers = 0;
  std::uint8_t counter = 0;
};
// Mode = Map, one pair per downward frame (MAP_POSE then MAP_STATUS): the homography chain's pose
// of the frame in the map's frame (frame 0's image axes: x right, y down; heading from x towards y)
// in metres when the map is metric (MapStatus::metric), else in mosaic pixels.
constexpr double kMapPositionMax = 10485.75;  // MAP_POSE.X / Y range (+-); encode() refuses beyond it
struct MapPose {
  double x = 0, y = 0;   // m (metric) or mosaic px
  double heading_rad = 0;
  std::uint8_t counter = 0;
};
// The node the vehicle is at (the last observed frame's node; kMapNoNode before the first), the map
// size and how this frame fared: registered, or refused as black / saturated / textureless (bad
// input, the bits can combine) or lost (too few keypoints or matches, degenerate homography).
constexpr std::uint16_t kMapNoNode = 65535;
struct MapStatus {
  std::uint16_t node_id = kMapNoNode;
  std::uint16_t node_count = 0;
  std::uint16_t frame_seq = 0;  // the daemon's frame sequence (its map log's seq), wraps at 65535
  bool registered = false, black = false, saturated = false, textureless = false, lost = false;
  bool metric = false;          // MAP_POSE in metres (else mosaic pixels)
  bool new_node = false;        // this frame created node_id
  bool revisit = false;         // this frame recognised node_id as a revisit
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

// Fault word bits (NavStatus::fault_flags, Health::fault_flags); on the wire one signal per bit,
// named in fault::kSignalNames (DBC FaultLeak .. FaultCameraLost). Bits 10..15 are reserved.
namespace fault {
constexpr std::uint16_t kLeak = 1u << 0;
constexpr std::uint16_t kSensorTimeout = 1u << 1;
constexpr std::uint16_t kDeadlineMiss = 1u << 2;
constexpr std::uint16_t kBusOff = 1u << 3;
constexpr std::uint16_t kRouteDamaged = 1u << 4;
constexpr std::uint16_t kSoftware = 1u << 5;  // a software bug was caught (an assert-class event; see the daemon)
constexpr std::uint16_t kSonarLost = 1u << 6;
constexpr std::uint16_t kAttitudeLost = 1u << 7;
constexpr std::uint16_t kDvlLost = 1u << 8;
constexpr std::uint16_t kCameraLost = 1u << 9;
constexpr int kBitCount = 10;
constexpr std::uint16_t kDefined = (1u << kBitCount) - 1u;  // encoding a word with another bit set: kOutOfRange
inline constexpr const char* kSignalNames[kBitCount] = {
    "FaultLeak",     "FaultSensorTimeout", "FaultDeadlineMiss", "FaultBusOff",  "FaultRouteDamaged",
    "FaultSoftware", "FaultSonarLost",     "FaultAttitudeLost", "FaultDvlLost", "FaultCameraLost"};
}  // namespace fault

constexpr std::uint32_t kIdAttitudeIn = 0x100, kIdRatesIn = 0x101, kIdDepthIn = 0x102, kIdModeCmd = 0x110;
constexpr std::uint32_t kIdNavStatus = 0x200, kIdRouteGuidance = 0x201, kIdVoStep = 0x202, kIdRouteStatus = 0x203,
                        kIdMapPose = 0x204, kIdMapStatus = 0x205, kIdHealth = 0x210, kIdHeartbeat = 0x2FF;

// The most signals any message has (NAV_STATUS and HEALTH: 15); size decode_generic's array with it.
constexpr std::size_t kMaxSignalsPerMessage = 16;

// Every message of docs/qnav.dbc, in file order.
Span<const MessageDef> all_messages() noexcept;
const MessageDef* find_message(std::uint32_t id) noexcept;
// v clamped to signal `signal` of message `id` as docs/qnav.dbc gives its range (the table above is
// the one place the ranges live); a non-finite v gives 0. A name the table lacks is a software fault
// (QNAV_ASSERT) and gives 0. O(signals of the message).
double clamp_to_signal(std::uint32_t id, const char* signal, double v) noexcept;

Status decode(const hal::CanFrame& f, AttitudeIn& out) noexcept;
Status decode(const hal::CanFrame& f, RatesIn& out) noexcept;
Status decode(const hal::CanFrame& f, DepthIn& out) noexcept;
Status decode(const hal::CanFrame& f, ModeCmd& out) noexcept;
Status decode(const hal::CanFrame& f, NavStatus& out) noexcept;
Status decode(const hal::CanFrame& f, RouteGuidance& out) noexcept;
Status decode(const hal::CanFrame& f, VoStep& out) noexcept;
Status decode(const hal::CanFrame& f, RouteStatus& out) noexcept;
Status decode(const hal::CanFrame& f, MapPose& out) noexcept;
Status decode(const hal::CanFrame& f, MapStatus& out) noexcept;
Status decode(const hal::CanFrame& f, Health& out) noexcept;
Status decode(const hal::CanFrame& f, Heartbeat& out) noexcept;

Status encode(const AttitudeIn& m, hal::CanFrame& f) noexcept;
// The AHRS report of a compass heading as the simulators send it (qnavd's sim vehicle, the HIL
// player, `qnav sonar simulate`): the heading wrapped into [0, 2 pi) and held within the DBC's
// [0, 6.2832], valid, with the given counter.
AttitudeIn attitude_from_heading(double heading_rad, double roll_rad = 0.0, double pitch_rad = 0.0, std::uint8_t counter = 0) noexcept;
Status encode(const RatesIn& m, hal::CanFrame& f) noexcept;
Status encode(const DepthIn& m, hal::CanFrame& f) noexcept;
Status encode(const ModeCmd& m, hal::CanFrame& f) noexcept;
Status encode(const NavStatus& m, hal::CanFrame& f) noexcept;
Status encode(const RouteGuidance& m, hal::CanFrame& f) noexcept;
Status encode(const VoStep& m, hal::CanFrame& f) noexcept;
// cross_track_sigma_m above kCrossTrackSigmaMaxM (or +inf) is sent as kCrossTrackSigmaMaxM; negative
// is kOutOfRange, NaN kInvalidArgument.
Status encode(const RouteStatus& m, hal::CanFrame& f) noexcept;
Status encode(const MapPose& m, hal::CanFrame& f) noexcept;
Status encode(const MapStatus& m, hal::CanFrame& f) noexcept;
Status encode(const Health& m, hal::CanFrame& f) noexcept;
Status encode(const Heartbeat& m, hal::CanFrame& f) noexcept;

// Generic decode of any known message into physical values (one per signal, table order); used by
// `qnav can decode`. `values` must hold at least the message's signal count (kMaxSignalsPerMessage
// always suffices); a smaller `capacity` is kCapacityExceeded with `def` set and nothing decoded.
Status decode_generic(const hal::CanFrame& f, const MessageDef*& def, double* values, std::size_t capacity) noexcept;

}  // namespace qnav::drivers::qnavcan
