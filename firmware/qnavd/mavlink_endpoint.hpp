// MavlinkEndpoint: qnavd's MAVLink side on the nav thread ([mavlink], docs/interfaces.md "MAVLink").
// The io thread moves bytes (MavlinkIo, queues mav_rx / mav_tx); this class parses, decides and encodes.
//  Receives (drain()): one drivers/mavlink Parser per link; the autopilot's HEARTBEAT (mode, armed),
//    ATTITUDE (an attitude source, as the CAN AHRS: returned to the worker), SYSTEM_TIME (kept), and
//    COMMAND_LONG kCmdSetMode (MAV_CMD_USER_1 = 31010: param1 qnav mode 0 idle, 1 teach, 2 repeat,
//    3 map, 4 hold, 5 vo; param2 route id (0 = route.id); param3 reverse (1); param4 reset the
//    navigation origin (1)) returned to the worker, which acts and answers through ack().
//    Commands are accepted only from (autopilot_system_id, autopilot_component_id) and addressed to
//    qnavd (target system = ours, target component = ours or 0); anything else is refused and
//    counted, never acted on (no answer to a wrong sender: an intruder learns nothing; another
//    command from the autopilot is answered UNSUPPORTED, bad parameters DENIED). Every frame the parser rejects, every frame from a system or message
//    qnavd does not use, is counted (MavCounter, health log "mavlink").
//  Sends (publish()): the answers decided in drain(), the EKF origin (below), and the streams
//    (MavlinkStreams, mavlink_streams.hpp: HEARTBEAT, ODOMETRY, VISION_POSITION_DELTA,
//    DISTANCE_SENSOR, NAMED_VALUE_FLOAT, STATUSTEXT, SET_POSITION_TARGET_LOCAL_NED).
//  Signing policy (mavlink.key_file; the parsers' checks and the signing of what is sent are
//    MavlinkWire's, mavlink_wire.hpp): a COMMAND_LONG to qnavd that is not signed with the key is
//    refused without an answer and counted (cmd_unsigned) before the sender is even looked at (an
//    unsigned frame's ids prove nothing). Other messages (HEARTBEAT, ATTITUDE, SYSTEM_TIME) are read
//    signed or not. A configured key_file whose key was not loaded (a worker built without Daemon::init)
//    refuses every mode command: signing fails closed. Refusals are logged once a second at most as a
//    {"event":"mavlink_signing"} line (cmd_unsigned and the parsers' signing counters).
//  EKF origin (mavlink.origin_lat_deg / origin_lon_deg / origin_alt_m): SET_GPS_GLOBAL_ORIGIN to the
//    autopilot's system once a second (kOriginPeriodNs) from the first publish() until the autopilot
//    answers GPS_GLOBAL_ORIGIN (ArduPilot does so once its EKF took the origin; an origin it already
//    had is answered the same way, and reported if it differs from ours). When the autopilot's
//    HEARTBEAT returns after kApSilentNs of silence (it rebooted: its EKF lost the origin), the origin
//    is sent again.
// Owns: the wire (parsers, encoder, key), the streams, the autopilot's state and the pending answers.
// Memory: three parsers (~1 KB each), no heap. Time: O(bytes queued) per drain, a few frames per publish.
#pragma once

#include <cstdint>
#include <cstdio>

#include "drivers/mavlink/frame.hpp"
#include "drivers/mavlink/messages.hpp"
#include "drivers/qnavcan/messages.hpp"
#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/mavlink_streams.hpp"
#include "firmware/qnavd/mavlink_wire.hpp"
#include "firmware/qnavd/messages.hpp"
#include "hal/core/clock.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/spsc_ring.hpp"

namespace qnav::daemon {

constexpr std::uint16_t kMavCmdSetMode = 31010;  // MAV_CMD_USER_1: qnav's mode command
constexpr std::uint32_t kArduSubGuided = 4;      // ArduSub custom_mode GUIDED
constexpr std::int64_t kOriginPeriodNs = 1000000000;  // SET_GPS_GLOBAL_ORIGIN repeat period until answered
constexpr std::int64_t kApSilentNs = 5000000000;      // autopilot HEARTBEAT silence that counts as a reboot

// What drain() found for the worker.
struct MavInputs {
  bool attitude = false;
  std::int64_t attitude_ns = 0;
  double roll_rad = 0.0, pitch_rad = 0.0, yaw_rad = 0.0;
  bool mode_cmd = false;
  drivers::qnavcan::ModeCmd cmd;
};

class MavlinkEndpoint {
 public:
  // utc: the wall clock of signing timestamps (ns since 1970); nullptr = the system's (CLOCK_REALTIME).
  MavlinkEndpoint(const DaemonConfig& c, FILE* log, const hal::Clock* utc = nullptr) noexcept;
  // Parses what is queued, up to and including the first accepted mode command (the worker acts on
  // it, calls ack(), and drains again; a second one in the same item is what the next drain returns).
  MavInputs drain(SpscRing<MavBytes>& rx) noexcept;
  // The answer to the mode command drain() returned: accepted, or refused with qnav's reason.
  void ack(bool accepted, const char* why, SpscRing<MavBytes>& tx) noexcept;
  void publish(const MavSnapshot& s, SpscRing<MavBytes>& tx) noexcept;

  const CounterSet<MavCounter>& counters() const noexcept { return wire_.counters(); }
  std::uint32_t parser_rejects() const noexcept { return wire_.parser_rejects(); }
  std::uint32_t frames_rx() const noexcept { return frames_rx_; }
  std::uint32_t odometry_sent() const noexcept { return streams_.odometry_sent(); }
  std::uint32_t commands_accepted() const noexcept { return commands_accepted_; }
  bool autopilot_seen() const noexcept { return ap_seen_; }
  bool autopilot_guided_armed() const noexcept { return ap_seen_ && ap_custom_mode_ == kArduSubGuided && ap_armed_; }
  std::uint32_t targets_sent() const noexcept { return streams_.targets_sent(); }
  // Refused inputs (for HEALTH.RejectedInputs): counters that are rejections, and parser rejects.
  std::uint32_t rejected() const noexcept;
  // mavlink.key_file configured: mode commands must be signed (and what is sent is, when the key loaded).
  bool signing_required() const noexcept { return wire_.signing_required(); }
  bool signing() const noexcept { return wire_.has_key(); }
  // The parsers' signing refusals summed (bad_signature, replay, stale_timestamp, signed_refused, signing_streams).
  std::uint32_t signing_rejects() const noexcept { return wire_.signing_rejects(); }
  // The newest signing timestamp (10 us units since 2015-01-01): qnavd's local one.
  std::uint64_t local_timestamp() const noexcept { return wire_.local_timestamp(); }
  // EKF origin: SET_GPS_GLOBAL_ORIGIN frames sent, and whether the autopilot answered GPS_GLOBAL_ORIGIN.
  std::uint32_t origins_sent() const noexcept { return origins_sent_; }
  bool origin_acknowledged() const noexcept { return origin_acked_; }
  // SET_GPS_GLOBAL_ORIGIN from the configuration (degE7, mm), also what the tests compare with.
  static drivers::mavlink::SetGpsGlobalOrigin origin_message(const DaemonConfig& c) noexcept;

 private:
  void on_frame(const drivers::mavlink::Frame& f, std::int64_t arrival_ns, MavInputs& in) noexcept;
  void on_command(const drivers::mavlink::Frame& f, bool from_ap, MavInputs& in) noexcept;
  // The COMMAND_ACK of `command` with `result` to the frame's sender.
  static drivers::mavlink::CommandAck make_ack(std::uint16_t command, std::uint8_t result, std::uint8_t sys, std::uint8_t comp) noexcept;
  // An answer decided in drain(), sent by publish().
  void defer_ack(std::uint16_t command, std::uint8_t result, const drivers::mavlink::Frame& f) noexcept;
  void on_origin(const drivers::mavlink::Frame& f) noexcept;
  void log_signing(std::int64_t t) noexcept;

  const DaemonConfig& cfg_;
  FILE* log_;
  MavlinkWire wire_;
  MavlinkStreams streams_;
  std::uint32_t signing_logged_ = 0;
  // EKF origin
  std::int64_t next_origin_ns_ = 0;
  std::uint32_t origins_sent_ = 0;
  bool origin_acked_ = false, origin_mismatch_ = false;
  std::int64_t ap_last_hb_ns_ = 0;
  std::uint32_t frames_rx_ = 0, commands_accepted_ = 0;
  // the autopilot
  bool ap_seen_ = false, ap_armed_ = false;
  std::uint32_t ap_custom_mode_ = 0;
  std::uint64_t ap_unix_usec_ = 0;
  // the pending command (drain -> ack)
  std::uint8_t cmd_sys_ = 0, cmd_comp_ = 0;
  drivers::qnavcan::ModeCmd next_cmd_{};  // a second mode command found in the item of the first
  bool has_next_cmd_ = false;
  drivers::mavlink::CommandAck pending_ack_{};  // an answer decided in drain() (unsupported, bad parameters), sent by publish()
  bool has_pending_ack_ = false;
};

}  // namespace qnav::daemon
