#include "drivers/qnavcan/messages.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "nav/core/assert.hpp"

namespace qnav::drivers::qnavcan {

namespace {
// Tables mirror docs/qnav.dbc line by line (name, start, length, big-endian, signed, factor, offset,
// min, max, unit). test/unit/drivers/qnavcan/dbc_layout_test.cpp checks them against the file.
constexpr SignalDef kAttitude[] = {
    {"Roll", 0, 16, false, true, 0.0001, 0, -3.1416, 3.1416, "rad"},
    {"Pitch", 16, 16, false, true, 0.0001, 0, -1.5708, 1.5708, "rad"},
    {"Heading", 32, 16, false, false, 0.0001, 0, 0, 6.2832, "rad"},
    {"Counter", 48, 8, false, false, 1, 0, 0, 255, ""},
    {"Valid", 56, 1, false, false, 1, 0, 0, 1, ""},
};
constexpr SignalDef kRates[] = {
    {"RollRate", 0, 16, false, true, 0.0005, 0, -16, 16, "rad/s"},
    {"PitchRate", 16, 16, false, true, 0.0005, 0, -16, 16, "rad/s"},
    {"YawRate", 32, 16, false, true, 0.0005, 0, -16, 16, "rad/s"},
    {"Counter", 48, 8, false, false, 1, 0, 0, 255, ""},
};
constexpr SignalDef kDepth[] = {
    {"Depth", 7, 24, true, false, 0.001, 0, 0, 11000, "m"},
    {"Altitude", 31, 16, true, false, 0.01, 0, 0, 655.35, "m"},
    {"Counter", 47, 8, true, false, 1, 0, 0, 255, ""},
    {"DepthValid", 55, 1, true, false, 1, 0, 0, 1, ""},
    {"AltitudeValid", 54, 1, true, false, 1, 0, 0, 1, ""},
};
constexpr SignalDef kModeCmd[] = {
    {"Mode", 0, 4, false, false, 1, 0, 0, 5, ""},
    {"ResetNav", 4, 1, false, false, 1, 0, 0, 1, ""},
    {"Reverse", 5, 1, false, false, 1, 0, 0, 1, ""},
    {"RouteId", 8, 16, false, false, 1, 0, 0, 65535, ""},
    {"Counter", 24, 8, false, false, 1, 0, 0, 255, ""},
};
constexpr SignalDef kNavStatus[] = {
    {"State", 0, 4, false, false, 1, 0, 0, 5, ""},
    {"Localised", 4, 1, false, false, 1, 0, 0, 1, ""},
    {"Confidence", 8, 8, false, false, 0.5, 0, 0, 100, "%"},
    {"NodeIndex", 16, 16, false, false, 1, 0, 0, 65535, ""},
    {"FaultLeak", 32, 1, false, false, 1, 0, 0, 1, ""},
    {"FaultSensorTimeout", 33, 1, false, false, 1, 0, 0, 1, ""},
    {"FaultDeadlineMiss", 34, 1, false, false, 1, 0, 0, 1, ""},
    {"FaultBusOff", 35, 1, false, false, 1, 0, 0, 1, ""},
    {"FaultRouteDamaged", 36, 1, false, false, 1, 0, 0, 1, ""},
    {"FaultSoftware", 37, 1, false, false, 1, 0, 0, 1, ""},
    {"FaultSonarLost", 38, 1, false, false, 1, 0, 0, 1, ""},
    {"FaultAttitudeLost", 39, 1, false, false, 1, 0, 0, 1, ""},
    {"FaultDvlLost", 40, 1, false, false, 1, 0, 0, 1, ""},
    {"FaultCameraLost", 41, 1, false, false, 1, 0, 0, 1, ""},
    {"Counter", 48, 8, false, false, 1, 0, 0, 255, ""},
    {"ModeReject", 56, 4, false, false, 1, 0, 0, 8, ""},
};
constexpr SignalDef kGuidance[] = {
    {"CrossTrack", 0, 16, false, true, 0.01, 0, -327, 327, "m"},
    {"HeadingError", 16, 16, false, true, 0.0001, 0, -3.1416, 3.1416, "rad"},
    {"DistToNext", 32, 16, false, false, 0.1, 0, 0, 6553.5, "m"},
    {"TargetNode", 48, 16, false, false, 1, 0, 0, 65535, ""},
};
constexpr SignalDef kVoStep[] = {
    {"Dx", 0, 16, false, true, 0.001, 0, -32, 32, "m"},
    {"Dy", 16, 16, false, true, 0.001, 0, -32, 32, "m"},
    {"Dyaw", 32, 16, false, true, 0.0001, 0, -3.1416, 3.1416, "rad"},
    {"Inliers", 48, 8, false, false, 1, 0, 0, 255, ""},
    {"Counter", 56, 8, false, false, 1, 0, 0, 255, ""},
};
constexpr SignalDef kRouteStatus[] = {
    {"GuidanceStatus", 0, 4, false, false, 1, 0, 0, 4, ""},
    {"Side", 4, 3, false, false, 1, 0, 0, 3, ""},
    {"CrossTrackSigma", 8, 16, false, false, 0.01, 0, 0, kCrossTrackSigmaMaxM, "m"},
    {"EstimateNode", 24, 16, false, false, 1, 0, 0, 65535, ""},
    {"TileSeq", 40, 16, false, false, 1, 0, 0, 65535, ""},
    {"Counter", 56, 8, false, false, 1, 0, 0, 255, ""},
};
constexpr SignalDef kMapPose[] = {
    {"X", 0, 21, false, true, 0.01, 0, -kMapPositionMax, kMapPositionMax, "m|px"},
    {"Y", 21, 21, false, true, 0.01, 0, -kMapPositionMax, kMapPositionMax, "m|px"},
    {"Heading", 42, 14, false, true, 0.0004, 0, -3.1416, 3.1416, "rad"},
    {"Counter", 56, 8, false, false, 1, 0, 0, 255, ""},
};
constexpr SignalDef kMapStatus[] = {
    {"NodeId", 0, 16, false, false, 1, 0, 0, 65535, ""},
    {"NodeCount", 16, 16, false, false, 1, 0, 0, 65535, ""},
    {"FrameSeq", 32, 16, false, false, 1, 0, 0, 65535, ""},
    {"Registered", 48, 1, false, false, 1, 0, 0, 1, ""},
    {"Black", 49, 1, false, false, 1, 0, 0, 1, ""},
    {"Saturated", 50, 1, false, false, 1, 0, 0, 1, ""},
    {"Textureless", 51, 1, false, false, 1, 0, 0, 1, ""},
    {"Lost", 52, 1, false, false, 1, 0, 0, 1, ""},
    {"Metric", 53, 1, false, false, 1, 0, 0, 1, ""},
    {"NewNode", 54, 1, false, false, 1, 0, 0, 1, ""},
    {"Revisit", 55, 1, false, false, 1, 0, 0, 1, ""},
    {"Counter", 56, 8, false, false, 1, 0, 0, 255, ""},
};
constexpr SignalDef kHealth[] = {
    {"FaultLeak", 0, 1, false, false, 1, 0, 0, 1, ""},
    {"FaultSensorTimeout", 1, 1, false, false, 1, 0, 0, 1, ""},
    {"FaultDeadlineMiss", 2, 1, false, false, 1, 0, 0, 1, ""},
    {"FaultBusOff", 3, 1, false, false, 1, 0, 0, 1, ""},
    {"FaultRouteDamaged", 4, 1, false, false, 1, 0, 0, 1, ""},
    {"FaultSoftware", 5, 1, false, false, 1, 0, 0, 1, ""},
    {"FaultSonarLost", 6, 1, false, false, 1, 0, 0, 1, ""},
    {"FaultAttitudeLost", 7, 1, false, false, 1, 0, 0, 1, ""},
    {"FaultDvlLost", 8, 1, false, false, 1, 0, 0, 1, ""},
    {"FaultCameraLost", 9, 1, false, false, 1, 0, 0, 1, ""},
    {"RejectedInputs", 16, 16, false, false, 1, 0, 0, 65535, ""},
    {"DeadlineMisses", 32, 16, false, false, 1, 0, 0, 65535, ""},
    {"CpuLoad", 48, 8, false, false, 0.5, 0, 0, 100, "%"},
    {"Leak", 56, 1, false, false, 1, 0, 0, 1, ""},
    {"BusOff", 57, 1, false, false, 1, 0, 0, 1, ""},
};
constexpr SignalDef kHeartbeat[] = {
    {"Uptime", 0, 32, false, false, 1, 0, 0, 4294967295.0, "s"},
    {"State", 32, 4, false, false, 1, 0, 0, 5, ""},
    {"SwMajor", 40, 8, false, false, 1, 0, 0, 255, ""},
    {"SwMinor", 48, 8, false, false, 1, 0, 0, 255, ""},
    {"Counter", 56, 8, false, false, 1, 0, 0, 255, ""},
};

template <std::size_t N>
constexpr Span<const SignalDef> sp(const SignalDef (&a)[N]) {
  static_assert(N <= kMaxSignalsPerMessage, "raise kMaxSignalsPerMessage");
  return Span<const SignalDef>(a, N);
}

const MessageDef kMessages[] = {
    {"QNAV_ATTITUDE_IN", kIdAttitudeIn, 8, "AHRS", sp(kAttitude), 20},
    {"QNAV_RATES_IN", kIdRatesIn, 8, "AHRS", sp(kRates), 20},
    {"QNAV_DEPTH_IN", kIdDepthIn, 8, "DEPTH", sp(kDepth), 100},
    {"QNAV_MODE_CMD", kIdModeCmd, 4, "VEHICLE", sp(kModeCmd), 0},
    {"QNAV_NAV_STATUS", kIdNavStatus, 8, "QNAV", sp(kNavStatus), 100},
    {"QNAV_ROUTE_GUIDANCE", kIdRouteGuidance, 8, "QNAV", sp(kGuidance), 100},
    {"QNAV_VO_STEP", kIdVoStep, 8, "QNAV", sp(kVoStep), 100},
    {"QNAV_ROUTE_STATUS", kIdRouteStatus, 8, "QNAV", sp(kRouteStatus), 100},
    {"QNAV_MAP_POSE", kIdMapPose, 8, "QNAV", sp(kMapPose), 0},
    {"QNAV_MAP_STATUS", kIdMapStatus, 8, "QNAV", sp(kMapStatus), 0},
    {"QNAV_HEALTH", kIdHealth, 8, "QNAV", sp(kHealth), 1000},
    {"QNAV_HEARTBEAT", kIdHeartbeat, 8, "QNAV", sp(kHeartbeat), 1000},
};

constexpr std::size_t kMaxSignals = kMaxSignalsPerMessage;

// The fault word's signals sit in table order FaultLeak .. FaultCameraLost (bit 0 .. 9 of the word).
static_assert(sizeof fault::kSignalNames / sizeof fault::kSignalNames[0] == fault::kBitCount, "one name per fault bit");

// Decodes every signal of `id` into v[]; the first range failure is reported after all are decoded.
Status decode_all(const hal::CanFrame& f, std::uint32_t id, double* v) noexcept {
  if (f.id != id) return Status(StatusCode::kNotFound, "frame has another id");
  if (f.extended || f.fd || f.rtr || f.error) return Status(StatusCode::kUnsupported, "qnav messages are classic 11-bit data frames");
  const MessageDef* m = find_message(id);
  if (m == nullptr) return Status(StatusCode::kNotFound, "unknown message");
  if (f.len < m->dlc) return Status(StatusCode::kTruncated, "frame shorter than the DBC length");
  Status first = Status::ok();
  for (std::size_t i = 0; i < m->signals.size() && i < kMaxSignals; ++i) {
    const Status s = decode_signal(f.data, m->signals[i], v[i]);
    if (!s.is_ok() && first.is_ok()) first = s;
  }
  return first;
}

Status encode_all(hal::CanFrame& f, std::uint32_t id, const double* v) noexcept {
  const MessageDef* m = find_message(id);
  if (m == nullptr) return Status(StatusCode::kNotFound, "unknown message");
  hal::CanFrame out;
  out.id = id;
  out.len = m->dlc;
  for (std::size_t i = 0; i < m->signals.size() && i < kMaxSignals; ++i)
    QNAV_RETURN_IF_ERROR(encode_signal(out.data, m->signals[i], v[i]));
  f = out;
  return Status::ok();
}

std::uint8_t u8(double v) noexcept { return static_cast<std::uint8_t>(std::lround(v)); }
std::uint16_t u16(double v) noexcept { return static_cast<std::uint16_t>(std::lround(v)); }
Mode mode_of(double v) noexcept { return static_cast<Mode>(u8(v)); }
double flag(bool b) noexcept { return b ? 1.0 : 0.0; }

// Fault word <-> its kBitCount one-bit signal values (v[0] = bit 0). Reserved bits are refused.
Status faults_to_signals(std::uint16_t word, double* v) noexcept {
  if ((word & static_cast<std::uint16_t>(~fault::kDefined)) != 0)
    return Status(StatusCode::kOutOfRange, "fault word has a reserved bit (10..15) set");
  for (int b = 0; b < fault::kBitCount; ++b) v[b] = flag(((word >> b) & 1u) != 0);
  return Status::ok();
}
std::uint16_t faults_from_signals(const double* v) noexcept {
  std::uint16_t word = 0;
  for (int b = 0; b < fault::kBitCount; ++b)
    if (v[b] > 0.5) word = static_cast<std::uint16_t>(word | (1u << b));
  return word;
}
}  // namespace

const char* to_string(GuidanceState s) noexcept {
  switch (s) {
    case GuidanceState::kTracking: return "Tracking";
    case GuidanceState::kHoldCourse: return "HoldCourse";
    case GuidanceState::kDeadReckoned: return "DeadReckoned";
    case GuidanceState::kRouteEnd: return "RouteEnd";
    case GuidanceState::kNotRepeating: return "NotRepeating";
  }
  return "?";
}

const char* to_string(SideOfRoute s) noexcept {
  switch (s) {
    case SideOfRoute::kOnRoute: return "OnRoute";
    case SideOfRoute::kPort: return "Port";
    case SideOfRoute::kStarboard: return "Starboard";
    case SideOfRoute::kUnknown: return "Unknown";
  }
  return "?";
}

const char* mode_name(Mode m) noexcept {
  switch (m) {
    case Mode::kIdle: return "idle";
    case Mode::kTeach: return "teach";
    case Mode::kRepeat: return "repeat";
    case Mode::kMap: return "map";
    case Mode::kHold: return "hold";
    case Mode::kVo: return "vo";
  }
  return "?";
}

Span<const MessageDef> all_messages() noexcept { return Span<const MessageDef>(kMessages, sizeof kMessages / sizeof kMessages[0]); }

const MessageDef* find_message(std::uint32_t id) noexcept {
  for (const MessageDef& m : kMessages)
    if (m.id == id) return &m;
  return nullptr;
}

double clamp_to_signal(std::uint32_t id, const char* signal, double v) noexcept {
  const MessageDef* m = find_message(id);
  if (!QNAV_ASSERT(m != nullptr, "clamp_to_signal: no such qnav message id")) return 0.0;
  for (const SignalDef& sd : m->signals)
    if (std::strcmp(sd.name, signal) == 0) return std::isfinite(v) ? std::min(sd.max, std::max(sd.min, v)) : 0.0;
  QNAV_ASSERT(false, "clamp_to_signal: no such signal in the message");
  return 0.0;
}

Status decode_generic(const hal::CanFrame& f, const MessageDef*& def, double* values, std::size_t capacity) noexcept {
  def = find_message(f.id);
  if (def == nullptr || f.extended) return Status(StatusCode::kNotFound, "not a qnav message id");
  if (capacity < def->signals.size()) return Status(StatusCode::kCapacityExceeded, "values array too small");
  return decode_all(f, f.id, values);
}

Status decode(const hal::CanFrame& f, AttitudeIn& o) noexcept {
  double v[kMaxSignals];
  QNAV_RETURN_IF_ERROR(decode_all(f, kIdAttitudeIn, v));
  o = AttitudeIn{v[0], v[1], v[2], u8(v[3]), v[4] > 0.5};
  return Status::ok();
}
Status decode(const hal::CanFrame& f, RatesIn& o) noexcept {
  double v[kMaxSignals];
  QNAV_RETURN_IF_ERROR(decode_all(f, kIdRatesIn, v));
  o = RatesIn{v[0], v[1], v[2], u8(v[3])};
  return Status::ok();
}
Status decode(const hal::CanFrame& f, DepthIn& o) noexcept {
  double v[kMaxSignals];
  QNAV_RETURN_IF_ERROR(decode_all(f, kIdDepthIn, v));
  o = DepthIn{v[0], v[1], u8(v[2]), v[3] > 0.5, v[4] > 0.5};
  return Status::ok();
}
Status decode(const hal::CanFrame& f, ModeCmd& o) noexcept {
  double v[kMaxSignals];
  QNAV_RETURN_IF_ERROR(decode_all(f, kIdModeCmd, v));
  o = ModeCmd{};
  o.mode = mode_of(v[0]);
  o.reset_nav = v[1] > 0.5;
  o.reverse = v[2] > 0.5;
  o.route_id = u16(v[3]);
  o.counter = u8(v[4]);
  return Status::ok();
}
Status decode(const hal::CanFrame& f, NavStatus& o) noexcept {
  double v[kMaxSignals];
  QNAV_RETURN_IF_ERROR(decode_all(f, kIdNavStatus, v));
  o = NavStatus{mode_of(v[0]), v[1] > 0.5, v[2], u16(v[3]), faults_from_signals(v + 4), u8(v[4 + fault::kBitCount]), u8(v[5 + fault::kBitCount])};
  return Status::ok();
}
Status decode(const hal::CanFrame& f, RouteGuidance& o) noexcept {
  double v[kMaxSignals];
  QNAV_RETURN_IF_ERROR(decode_all(f, kIdRouteGuidance, v));
  o = RouteGuidance{v[0], v[1], v[2], u16(v[3])};
  return Status::ok();
}
Status decode(const hal::CanFrame& f, VoStep& o) noexcept {
  double v[kMaxSignals];
  QNAV_RETURN_IF_ERROR(decode_all(f, kIdVoStep, v));
  o = VoStep{v[0], v[1], v[2], u8(v[3]), u8(v[4])};
  return Status::ok();
}
Status decode(const hal::CanFrame& f, RouteStatus& o) noexcept {
  double v[kMaxSignals];
  QNAV_RETURN_IF_ERROR(decode_all(f, kIdRouteStatus, v));  // the ranges keep both enums in their values
  o = RouteStatus{
      static_cast<GuidanceState>(u8(v[0])), static_cast<SideOfRoute>(u8(v[1])), v[2], u16(v[3]), u16(v[4]), u8(v[5])};
  return Status::ok();
}
Status decode(const hal::CanFrame& f, MapPose& o) noexcept {
  double v[kMaxSignals];
  QNAV_RETURN_IF_ERROR(decode_all(f, kIdMapPose, v));
  o = MapPose{v[0], v[1], v[2], u8(v[3])};
  return Status::ok();
}
Status decode(const hal::CanFrame& f, MapStatus& o) noexcept {
  double v[kMaxSignals];
  QNAV_RETURN_IF_ERROR(decode_all(f, kIdMapStatus, v));
  o = MapStatus{};
  o.node_id = u16(v[0]);
  o.node_count = u16(v[1]);
  o.frame_seq = u16(v[2]);
  o.registered = v[3] > 0.5;
  o.black = v[4] > 0.5;
  o.saturated = v[5] > 0.5;
  o.textureless = v[6] > 0.5;
  o.lost = v[7] > 0.5;
  o.metric = v[8] > 0.5;
  o.new_node = v[9] > 0.5;
  o.revisit = v[10] > 0.5;
  o.counter = u8(v[11]);
  return Status::ok();
}
Status decode(const hal::CanFrame& f, Health& o) noexcept {
  double v[kMaxSignals];
  QNAV_RETURN_IF_ERROR(decode_all(f, kIdHealth, v));
  const double* w = v + fault::kBitCount;
  o = Health{faults_from_signals(v), u16(w[0]), u16(w[1]), w[2], w[3] > 0.5, w[4] > 0.5};
  return Status::ok();
}
Status decode(const hal::CanFrame& f, Heartbeat& o) noexcept {
  double v[kMaxSignals];
  QNAV_RETURN_IF_ERROR(decode_all(f, kIdHeartbeat, v));
  o = Heartbeat{static_cast<std::uint32_t>(std::llround(v[0])), mode_of(v[1]), u8(v[2]), u8(v[3]), u8(v[4])};
  return Status::ok();
}

AttitudeIn attitude_from_heading(double heading_rad, double roll_rad, double pitch_rad, std::uint8_t counter) noexcept {
  constexpr double kTwoPi = 6.283185307179586;
  double h = std::fmod(heading_rad, kTwoPi);
  if (h < 0) h += kTwoPi;
  AttitudeIn a;
  a.heading_rad = std::fmin(h, 6.2832);
  a.roll_rad = roll_rad;
  a.pitch_rad = pitch_rad;
  a.valid = true;
  a.counter = counter;
  return a;
}

Status encode(const AttitudeIn& m, hal::CanFrame& f) noexcept {
  const double v[] = {m.roll_rad, m.pitch_rad, m.heading_rad, double(m.counter), m.valid ? 1.0 : 0.0};
  return encode_all(f, kIdAttitudeIn, v);
}
Status encode(const RatesIn& m, hal::CanFrame& f) noexcept {
  const double v[] = {m.roll_rate_radps, m.pitch_rate_radps, m.yaw_rate_radps, double(m.counter)};
  return encode_all(f, kIdRatesIn, v);
}
Status encode(const DepthIn& m, hal::CanFrame& f) noexcept {
  const double v[] = {m.depth_m, m.altitude_m, double(m.counter), m.depth_valid ? 1.0 : 0.0, m.altitude_valid ? 1.0 : 0.0};
  return encode_all(f, kIdDepthIn, v);
}
Status encode(const ModeCmd& m, hal::CanFrame& f) noexcept {
  const double v[] = {double(static_cast<std::uint8_t>(m.mode)), flag(m.reset_nav), flag(m.reverse), double(m.route_id),
                      double(m.counter)};
  static_assert(sizeof v / sizeof v[0] == sizeof kModeCmd / sizeof kModeCmd[0], "one value per MODE_CMD signal");
  return encode_all(f, kIdModeCmd, v);
}
Status encode(const NavStatus& m, hal::CanFrame& f) noexcept {
  double v[4 + fault::kBitCount + 2] = {double(static_cast<std::uint8_t>(m.state)), flag(m.localised), m.confidence_pct,
                                        double(m.node_index)};
  QNAV_RETURN_IF_ERROR(faults_to_signals(m.fault_flags, v + 4));
  v[4 + fault::kBitCount] = double(m.counter);
  v[5 + fault::kBitCount] = double(m.mode_reject);
  static_assert(sizeof v / sizeof v[0] == sizeof kNavStatus / sizeof kNavStatus[0], "one value per NAV_STATUS signal");
  return encode_all(f, kIdNavStatus, v);
}
Status encode(const RouteGuidance& m, hal::CanFrame& f) noexcept {
  const double v[] = {m.cross_track_m, m.heading_error_rad, m.dist_to_next_m, double(m.target_node)};
  return encode_all(f, kIdRouteGuidance, v);
}
Status encode(const VoStep& m, hal::CanFrame& f) noexcept {
  const double v[] = {m.dx_m, m.dy_m, m.dyaw_rad, double(m.inliers), double(m.counter)};
  return encode_all(f, kIdVoStep, v);
}
Status encode(const RouteStatus& m, hal::CanFrame& f) noexcept {
  // A sigma too large for the signal means "unknown": send the top of the range instead of failing.
  const double sigma = m.cross_track_sigma_m > kCrossTrackSigmaMaxM ? kCrossTrackSigmaMaxM : m.cross_track_sigma_m;
  const double v[] = {double(static_cast<std::uint8_t>(m.status)),
                      double(static_cast<std::uint8_t>(m.side)),
                      sigma,
                      double(m.estimate_node),
                      double(m.tile_seq),
                      double(m.counter)};
  static_assert(sizeof v / sizeof v[0] == sizeof kRouteStatus / sizeof kRouteStatus[0],
                "one value per ROUTE_STATUS signal");
  return encode_all(f, kIdRouteStatus, v);
}
Status encode(const MapPose& m, hal::CanFrame& f) noexcept {
  const double v[] = {m.x, m.y, m.heading_rad, double(m.counter)};
  static_assert(sizeof v / sizeof v[0] == sizeof kMapPose / sizeof kMapPose[0], "one value per MAP_POSE signal");
  return encode_all(f, kIdMapPose, v);
}
Status encode(const MapStatus& m, hal::CanFrame& f) noexcept {
  const double v[] = {double(m.node_id), double(m.node_count), double(m.frame_seq), flag(m.registered), flag(m.black), flag(m.saturated),
                      flag(m.textureless),  flag(m.lost),         flag(m.metric),      flag(m.new_node),   flag(m.revisit), double(m.counter)};
  static_assert(sizeof v / sizeof v[0] == sizeof kMapStatus / sizeof kMapStatus[0], "one value per MAP_STATUS signal");
  return encode_all(f, kIdMapStatus, v);
}
Status encode(const Health& m, hal::CanFrame& f) noexcept {
  double v[fault::kBitCount + 5] = {};
  QNAV_RETURN_IF_ERROR(faults_to_signals(m.fault_flags, v));
  double* w = v + fault::kBitCount;
  w[0] = double(m.rejected_inputs);
  w[1] = double(m.deadline_misses);
  w[2] = m.cpu_load_pct;
  w[3] = flag(m.leak);
  w[4] = flag(m.bus_off);
  static_assert(sizeof v / sizeof v[0] == sizeof kHealth / sizeof kHealth[0], "one value per HEALTH signal");
  return encode_all(f, kIdHealth, v);
}
Status encode(const Heartbeat& m, hal::CanFrame& f) noexcept {
  const double v[] = {double(m.uptime_s), double(static_cast<std::uint8_t>(m.state)), double(m.sw_major), double(m.sw_minor),
                      double(m.counter)};
  return encode_all(f, kIdHeartbeat, v);
}

}  // namespace qnav::drivers::qnavcan
