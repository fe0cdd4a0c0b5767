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
//  Sends (publish(), from a MavSnapshot of the worker's state at its sample time):
//    HEARTBEAT 1 Hz (MAV_TYPE_ONBOARD_CONTROLLER, MAV_AUTOPILOT_INVALID; custom_mode = qnav's mode);
//    ODOMETRY at odometry_hz, on multiples of its period in sample time (frame LOCAL_FRD = 20 north-aligned, child BODY_FRD = 12, the
//      NavEstimate's position, the attitude quaternion, the DVL body velocity, reset_counter, quality);
//    VISION_POSITION_DELTA at the same rate (the estimate's motion since the last one, body frame);
//    DISTANCE_SENSOR at the same rate with the DVL altitude (while it reports one);
//    NAMED_VALUE_FLOAT 1 Hz in Repeat: xtrack_m, xtrack_sig, side (-1 port, 0 on, 1 starboard,
//      2 unknown), node; STATUSTEXT on a mode change, a refused command and a fault bit that rises;
//    SET_POSITION_TARGET_LOCAL_NED 1 Hz with mavlink.guided, in Repeat with a route fix, while the
//      autopilot's HEARTBEAT says GUIDED (ArduSub custom_mode 4) and armed.
//  Signing (mavlink.key_file; the key read and checked at start by Daemon::init, mavlink_key.hpp):
//    every parser verifies signed frames with the key (bad_signature, replay, stale_timestamp: counted
//    by the parser, in parser_rejects); a COMMAND_LONG to qnavd that is not signed with the key is
//    refused without an answer and counted (cmd_unsigned) before the sender is even looked at (an
//    unsigned frame's ids prove nothing). Other messages (HEARTBEAT, ATTITUDE, SYSTEM_TIME) are read
//    signed or not. Everything qnavd sends is signed (link id kSignLinkId), the timestamp the newest of
//    the UTC clock (10 us units since 2015-01-01), every verified incoming timestamp, and the last one
//    sent + 1; the same timestamp is the parsers' local one (a signed frame more than a minute behind
//    it is stale). A configured key_file whose key was not loaded (a worker built without Daemon::init)
//    refuses every mode command: signing fails closed. Refusals are logged once a second at most as a
//    {"event":"mavlink_signing"} line (cmd_unsigned and the parsers' signing counters).
//  EKF origin (mavlink.origin_lat_deg / origin_lon_deg / origin_alt_m): SET_GPS_GLOBAL_ORIGIN to the
//    autopilot's system once a second (kOriginPeriodNs) from the first publish() until the autopilot
//    answers GPS_GLOBAL_ORIGIN (ArduPilot does so once its EKF took the origin; an origin it already
//    had is answered the same way, and reported if it differs from ours). When the autopilot's
//    HEARTBEAT returns after kApSilentNs of silence (it rebooted: its EKF lost the origin), the origin
//    is sent again.
//  Loss (DVL lost, attitude lost, camera lost in Vo): ODOMETRY quality = -1 with velocity NaN at once
//    (the next period), VISION_POSITION_DELTA not sent (and rebased: the first delta after the loss
//    starts from the recovered position). Never a zero delta for "no data".
// Memory: three parsers (~1 KB each), no heap. Time: O(bytes queued) per drain, a few frames per publish.
#pragma once

#include <cstdint>
#include <cstdio>

#include "drivers/mavlink/frame.hpp"
#include "drivers/mavlink/messages.hpp"
#include "drivers/mavlink/parser.hpp"
#include "drivers/qnavcan/messages.hpp"
#include "firmware/pipeline/nav_estimate.hpp"
#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/messages.hpp"
#include "hal/core/clock.hpp"
#include "hal/linux/monotonic_clock.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/spsc_ring.hpp"

namespace qnav::daemon {

constexpr std::uint16_t kMavCmdSetMode = 31010;  // MAV_CMD_USER_1: qnav's mode command
constexpr std::uint32_t kArduSubGuided = 4;      // ArduSub custom_mode GUIDED
constexpr std::uint8_t kSignLinkId = 0;          // the link id of qnavd's signatures (one stream: the same bytes go to every link)
constexpr std::int64_t kOriginPeriodNs = 1000000000;  // SET_GPS_GLOBAL_ORIGIN repeat period until answered
constexpr std::int64_t kApSilentNs = 5000000000;      // autopilot HEARTBEAT silence that counts as a reboot

enum class MavCounter : std::uint8_t {
  kRxQueueOverflow,  // (io) bytes dropped before parsing: reported from IoCounters
  kParserRejects,    // every parser reject (garbage, bad CRC, unknown id, bad length, signing ...)
  kForeignSystem,    // a frame from a system other than the autopilot's (ignored)
  kUnusedMessage,    // a known message qnavd does not read (ignored)
  kCmdWrongSender,   // a mode command from another system / component: refused (DENIED)
  kCmdNotForUs,      // a COMMAND_LONG addressed to another system or component (ignored)
  kCmdUnsupported,   // a COMMAND_LONG of another command from the autopilot (UNSUPPORTED)
  kCmdBadParam,      // a mode command with parameters out of range (DENIED)
  kBadAttitude,      // an ATTITUDE with non-finite angles
  kTxQueueFull,      // a frame not sent: the mav_tx queue was full
  kCmdUnsigned,      // a mode command not signed with mavlink.key_file's key: refused (no answer)
  kCount
};
inline constexpr const char* kMavCounterNames[] = {"rx_overflow",     "parser_rejects", "foreign_system", "unused_message", "cmd_wrong_sender",
                                                   "cmd_not_for_us", "cmd_unsupported", "cmd_bad_param",  "bad_attitude",   "tx_queue_full",
                                                   "cmd_unsigned"};

// What the worker hands over each loop (its sample time, its mode, faults and the estimate).
struct MavSnapshot {
  std::int64_t now_ns = 0;
  drivers::qnavcan::Mode mode = drivers::qnavcan::Mode::kIdle;
  std::uint16_t faults = 0;        // qnavcan fault bits
  bool loss = false;               // DVL lost, attitude lost, or camera lost in Mode = Vo
  bool have_attitude = false;
  Mat3d world_R_body = Mat3d::Identity();  // NED <- FRD
  bool have_velocity = false;
  double vx_mps = 0.0, vy_mps = 0.0;       // DVL body velocity (forward, starboard)
  double altitude_m = -1.0;                // DVL altitude; < 0 unknown
  double confidence_pct = 0.0;             // Repeat: the localiser's probability
  bool localised = false;
  const pipeline::NavEstimate* estimate = nullptr;
  // Repeat guidance
  bool in_repeat = false;
  bool route_fix = false;          // a route fix placed the estimate in the route frame (this repeat)
  bool guidance_valid = false;     // tracking (not hold course), offsets known
  double cross_track_m = 0.0, cross_track_sigma_m = 0.0;
  int side = 2;
  std::uint32_t node = 0;
  Vec2d waypoint_ne = Vec2d::Zero();  // route frame
};

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

  const CounterSet<MavCounter>& counters() const noexcept { return counters_; }
  std::uint32_t parser_rejects() const noexcept;
  std::uint32_t frames_rx() const noexcept { return frames_rx_; }
  std::uint32_t odometry_sent() const noexcept { return odometry_sent_; }
  std::uint32_t commands_accepted() const noexcept { return commands_accepted_; }
  bool autopilot_seen() const noexcept { return ap_seen_; }
  bool autopilot_guided_armed() const noexcept { return ap_seen_ && ap_custom_mode_ == kArduSubGuided && ap_armed_; }
  std::uint32_t targets_sent() const noexcept { return targets_sent_; }
  // Refused inputs (for HEALTH.RejectedInputs): counters that are rejections, and parser rejects.
  std::uint32_t rejected() const noexcept;
  // mavlink.key_file configured: mode commands must be signed (and what is sent is, when the key loaded).
  bool signing_required() const noexcept { return signing_required_; }
  bool signing() const noexcept { return has_key_; }
  // The parsers' signing refusals summed (bad_signature, replay, stale_timestamp, signed_refused, signing_streams).
  std::uint32_t signing_rejects() const noexcept;
  // The newest signing timestamp (10 us units since 2015-01-01): qnavd's local one.
  std::uint64_t local_timestamp() const noexcept;
  // EKF origin: SET_GPS_GLOBAL_ORIGIN frames sent, and whether the autopilot answered GPS_GLOBAL_ORIGIN.
  std::uint32_t origins_sent() const noexcept { return origins_sent_; }
  bool origin_acknowledged() const noexcept { return origin_acked_; }
  // SET_GPS_GLOBAL_ORIGIN from the configuration (degE7, mm), also what the tests compare with.
  static drivers::mavlink::SetGpsGlobalOrigin origin_message(const DaemonConfig& c) noexcept;

 private:
  void on_frame(const drivers::mavlink::Frame& f, std::int64_t arrival_ns, MavInputs& in) noexcept;
  template <typename M>
  void send(const M& m, SpscRing<MavBytes>& tx) noexcept;
  void status_text(std::uint8_t severity, const char* text, SpscRing<MavBytes>& tx) noexcept;
  // The COMMAND_ACK of `command` with `result` to the frame's sender.
  static drivers::mavlink::CommandAck make_ack(std::uint16_t command, std::uint8_t result, std::uint8_t sys, std::uint8_t comp) noexcept;
  // An answer decided in drain(), sent by publish().
  void defer_ack(std::uint16_t command, std::uint8_t result, const drivers::mavlink::Frame& f) noexcept;
  std::uint32_t boot_ms(std::int64_t now_ns) const noexcept;
  // The first instant of the ODOMETRY grid (multiples of 1 / odometry_hz in sample time) after t.
  std::int64_t odometry_grid_after(std::int64_t t) const noexcept;
  // The next signing timestamp to send (strictly increasing), and the parsers' local timestamp moved up to it.
  std::uint64_t next_sign_timestamp() noexcept;
  std::uint64_t utc_10us() const noexcept;
  void on_origin(const drivers::mavlink::Frame& f) noexcept;
  void log_signing(std::int64_t t) noexcept;

  const DaemonConfig& cfg_;
  FILE* log_;
  drivers::mavlink::FrameEncoder enc_;
  drivers::mavlink::Parser parsers_[3];
  // signing (mavlink.key_file)
  hal::RealtimeClock system_utc_;
  const hal::Clock* utc_;
  bool signing_required_ = false, has_key_ = false;
  drivers::mavlink::SigningKey key_;
  std::uint64_t last_sign_ts_ = 0;
  std::uint32_t signing_logged_ = 0;
  // EKF origin
  std::int64_t next_origin_ns_ = 0;
  std::uint32_t origins_sent_ = 0;
  bool origin_acked_ = false, origin_mismatch_ = false;
  std::int64_t ap_last_hb_ns_ = 0;
  CounterSet<MavCounter> counters_{kMavCounterNames};
  std::uint32_t frames_rx_ = 0, odometry_sent_ = 0, commands_accepted_ = 0, targets_sent_ = 0;
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
  // output timing and state
  bool started_ = false;
  std::int64_t start_ns_ = 0, next_hb_ns_ = 0, next_odo_ns_ = 0, next_slow_ns_ = 0;
  drivers::qnavcan::Mode last_mode_ = drivers::qnavcan::Mode::kIdle;
  std::uint16_t last_faults_ = 0;
  bool delta_base_ = false;
  std::int64_t delta_ns_ = 0;
  double delta_n_ = 0.0, delta_e_ = 0.0, delta_d_ = 0.0, delta_yaw_ = 0.0, delta_roll_ = 0.0, delta_pitch_ = 0.0;
  std::uint8_t delta_reset_ = 0;
};

}  // namespace qnav::daemon
