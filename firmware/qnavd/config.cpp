// qnavd's configuration: one key table (name, type, bounds, unit, meaning, accessors) drives the
// parser, the validation and the documentation (config_keys_markdown), so the three cannot drift.
// Runs once at start-up, before any buffer is sized: heap and exceptions are fine here (toml++ throws
// toml::parse_error; nothing escapes this file).
#include "firmware/qnavd/config.hpp"

// toml++ 3.3.0 asserts (abort) where its own error path handles the input, e.g. a table header
// "[(a]" (parse_key: "expected bare key starting character"; found by test/fuzz fuzz_config, input
// test/fuzz/regressions/config/). With asserts off it reports a parse error, as NDEBUG builds do.
#define TOML_ASSERT(expr) static_cast<void>(0)
#include <toml++/toml.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <map>
#include <sstream>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace qnav::daemon {

namespace {

enum class Kind : std::uint8_t { kBool, kInt, kFloat, kString, kEnum };

// A value read from the file (or from a DaemonConfig, for the documented default). kEnum: i is the
// index into KeySpec::names.
struct Value {
  bool b = false;
  std::int64_t i = 0;
  double f = 0.0;
  std::string s;
};

struct KeySpec {
  std::string name;  // dotted: "route.max_nodes"; [[sim.pass]] keys are "sim.pass.<key>"
  Kind kind = Kind::kInt;
  std::string unit;
  std::int64_t int_min = 0, int_max = 0;    // kInt
  double float_min = 0.0, float_max = 0.0;  // kFloat
  bool float32 = false;                     // kFloat stored as float: defaults printed to float precision
  bool power_of_two = false;                // kInt
  std::vector<std::int64_t> int_choices;    // kInt: the accepted values, when not a range
  std::vector<std::string> names;           // kEnum: the accepted strings
  std::vector<std::pair<std::string, double>> aliases;  // kFloat: words that stand for a number (sim.speed)
  std::string rule;                         // a cross-key rule, appended to the allowed column
  bool required = false;                    // no default (sim.pass.mode)
  std::string meaning;
  std::function<Value(const DaemonConfig&)> get;
  std::function<void(DaemonConfig&, const Value&)> set;
  std::function<std::string(const std::string&)> check;  // kString: "" when accepted, else why not
};

constexpr std::size_t kMaxPasses = decltype(DaemonConfig::sim_mission)::capacity();

// ---- Formatting ------------------------------------------------------------------------------------

// Shortest text that reads back as the same double (or float).
std::string format_number(double v, bool float32) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[40];
  int precision = 1;
  for (; precision < 17; ++precision) {
    std::snprintf(buf, sizeof buf, "%.*g", precision, v);
    const double back = std::strtod(buf, nullptr);
    if (float32 ? static_cast<float>(back) == static_cast<float>(v) : back == v) break;
  }
  // Whole digits in full (60, not 6e+01) up to 17 of them.
  const int whole_digits = v == 0.0 ? 1 : static_cast<int>(std::floor(std::log10(std::fabs(v)))) + 1;
  if (whole_digits > precision && whole_digits <= 17) precision = whole_digits;
  std::snprintf(buf, sizeof buf, "%.*g", precision, v);
  return buf;
}

// As a TOML float literal: always with a '.' or an exponent.
std::string format_float_literal(double v, bool float32) {
  std::string s = format_number(v, float32);
  if (s.find_first_of(".eni") == std::string::npos) s += ".0";
  return s;
}

std::string quoted(const std::string& s) { return "\"" + s + "\""; }

std::string join(const std::vector<std::string>& parts, const char* sep) {
  std::string out;
  for (std::size_t i = 0; i < parts.size(); ++i) out += (i ? sep : "") + parts[i];
  return out;
}

const char* type_name(Kind k) {
  switch (k) {
    case Kind::kBool: return "boolean";
    case Kind::kInt: return "integer";
    case Kind::kFloat: return "float";
    case Kind::kString: return "string";
    case Kind::kEnum: return "string";
  }
  return "?";
}

const char* expected_text(Kind k) {
  switch (k) {
    case Kind::kBool: return "expected a boolean (true or false)";
    case Kind::kInt: return "expected an integer";
    case Kind::kFloat: return "expected a number";
    case Kind::kString: return "expected a string";
    case Kind::kEnum: return "expected a string";
  }
  return "?";
}

const char* node_type_text(toml::node_type t) {
  switch (t) {
    case toml::node_type::none: return "nothing";
    case toml::node_type::table: return "a table";
    case toml::node_type::array: return "an array";
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a float";
    case toml::node_type::boolean: return "a boolean";
    case toml::node_type::date: return "a date";
    case toml::node_type::time: return "a time";
    case toml::node_type::date_time: return "a date-time";
  }
  return "?";
}

std::string value_text(const KeySpec& k, const Value& v) {
  switch (k.kind) {
    case Kind::kBool: return v.b ? "true" : "false";
    case Kind::kInt: return std::to_string(v.i);
    case Kind::kFloat: return format_float_literal(v.f, k.float32);
    case Kind::kString: return quoted(v.s);
    case Kind::kEnum:
      return v.i >= 0 && static_cast<std::size_t>(v.i) < k.names.size() ? quoted(k.names[static_cast<std::size_t>(v.i)])
                                                                        : "?";
  }
  return "?";
}

// The allowed column, and the tail of range errors: "[1, 99]", "[16, 4096], power of two", ...
std::string allowed_text(const KeySpec& k) {
  std::string s;
  switch (k.kind) {
    case Kind::kBool: s = "true, false"; break;
    case Kind::kInt:
      if (!k.int_choices.empty()) {
        std::vector<std::string> parts;
        for (std::int64_t c : k.int_choices) parts.push_back(std::to_string(c));
        s = join(parts, ", ");
      } else {
        s = "[" + std::to_string(k.int_min) + ", " + std::to_string(k.int_max) + "]";
        if (k.power_of_two) s += ", power of two";
      }
      break;
    case Kind::kFloat:
      s = "[" + format_number(k.float_min, false) + ", " + format_number(k.float_max, false) + "]";
      for (const auto& a : k.aliases) s += ", `" + quoted(a.first) + "` (" + format_number(a.second, false) + ")";
      break;
    case Kind::kString: return k.rule.empty() ? "any" : k.rule;
    case Kind::kEnum: {
      std::vector<std::string> parts;
      for (const std::string& n : k.names) parts.push_back("`" + quoted(n) + "`");
      s = join(parts, ", ");
      break;
    }
  }
  if (!k.rule.empty()) s += ", " + k.rule;
  return s;
}

// ---- The key table ---------------------------------------------------------------------------------
// Each key is declared with an accessor, a generic lambda `[](auto& c) -> auto& { return c.field; }`
// that yields the field for reading (const config: the documented default) and for writing.

template <typename Access>
KeySpec int_key(const char* name, Access access, std::int64_t lo, std::int64_t hi, const char* unit,
                const char* meaning) {
  KeySpec k;
  k.name = name;
  k.kind = Kind::kInt;
  k.int_min = lo;
  k.int_max = hi;
  k.unit = unit;
  k.meaning = meaning;
  k.get = [access](const DaemonConfig& c) {
    Value v;
    v.i = static_cast<std::int64_t>(access(c));
    return v;
  };
  k.set = [access](DaemonConfig& c, const Value& v) {
    auto& field = access(c);
    field = static_cast<std::remove_reference_t<decltype(field)>>(v.i);
  };
  return k;
}

template <typename Access>
KeySpec queue_key(const char* name, Access access, std::int64_t lo, std::int64_t hi, const char* unit,
                  const char* meaning) {
  KeySpec k = int_key(name, access, lo, hi, unit, meaning);
  k.power_of_two = true;
  return k;
}

template <typename Access>
KeySpec float_key(const char* name, Access access, double lo, double hi, const char* unit, const char* meaning) {
  KeySpec k;
  k.name = name;
  k.kind = Kind::kFloat;
  k.float_min = lo;
  k.float_max = hi;
  k.unit = unit;
  k.meaning = meaning;
  k.float32 = std::is_same_v<std::decay_t<decltype(access(std::declval<const DaemonConfig&>()))>, float>;
  k.get = [access](const DaemonConfig& c) {
    Value v;
    v.f = static_cast<double>(access(c));
    return v;
  };
  k.set = [access](DaemonConfig& c, const Value& v) {
    auto& field = access(c);
    field = static_cast<std::remove_reference_t<decltype(field)>>(v.f);
  };
  return k;
}

template <typename Access>
KeySpec bool_key(const char* name, Access access, const char* meaning) {
  KeySpec k;
  k.name = name;
  k.kind = Kind::kBool;
  k.meaning = meaning;
  k.get = [access](const DaemonConfig& c) {
    Value v;
    v.b = access(c);
    return v;
  };
  k.set = [access](DaemonConfig& c, const Value& v) { access(c) = v.b; };
  return k;
}

template <typename Access>
KeySpec string_key(const char* name, Access access, const char* rule,
                   std::function<std::string(const std::string&)> check, const char* meaning) {
  KeySpec k;
  k.name = name;
  k.kind = Kind::kString;
  k.rule = rule;
  k.meaning = meaning;
  k.check = std::move(check);
  k.get = [access](const DaemonConfig& c) {
    Value v;
    v.s = access(c);
    return v;
  };
  k.set = [access](DaemonConfig& c, const Value& v) { access(c) = v.s; };
  return k;
}

// choices: the accepted strings and what each stores (an enum, or a string for dvl.protocol).
template <typename Access, typename T>
KeySpec enum_key(const char* name, Access access, std::vector<std::pair<std::string, T>> choices, const char* meaning) {
  KeySpec k;
  k.name = name;
  k.kind = Kind::kEnum;
  k.meaning = meaning;
  for (const auto& c : choices) k.names.push_back(c.first);
  k.get = [access, choices](const DaemonConfig& c) {
    Value v;
    v.i = -1;
    for (std::size_t i = 0; i < choices.size(); ++i)
      if (choices[i].second == access(c)) v.i = static_cast<std::int64_t>(i);
    return v;
  };
  k.set = [access, choices](DaemonConfig& c, const Value& v) {
    access(c) = choices[static_cast<std::size_t>(v.i)].second;
  };
  return k;
}

KeySpec with_setter(KeySpec k, std::function<void(DaemonConfig&, const Value&)> set) {
  k.set = std::move(set);
  return k;
}

KeySpec with_rule(KeySpec k, const char* rule) {
  k.rule = rule;
  return k;
}

// The pass a [[sim.pass]] key writes (the one being read) or documents (a default SimPass).
const SimPass& pass_of(const DaemonConfig& c) {
  static const SimPass kDefault{};
  return c.sim_mission.empty() ? kDefault : c.sim_mission.back();
}
SimPass& pass_of(DaemonConfig& c) { return c.sim_mission.back(); }

std::string check_not_empty(const std::string& s) { return s.empty() ? "must not be empty" : ""; }

// Linux dev_valid_name(): 1 to IFNAMSIZ - 1 characters, not "." or "..", no '/', ':' or white space.
std::string check_interface(const std::string& s) {
  const bool ok =
      !s.empty() && s.size() <= 15 && s != "." && s != ".." && s.find_first_of("/: \t\n\r\v\f") == std::string::npos;
  return ok ? "" : "must be a network interface name: 1 to 15 characters, no '/', ':' or white space";
}

std::string check_host_port(const std::string& s) {
  const std::size_t colon = s.rfind(':');
  bool ok = colon != std::string::npos && colon > 0 && colon + 1 < s.size() && s.size() - colon - 1 <= 5;
  if (ok) {
    long port = 0;
    for (std::size_t i = colon + 1; i < s.size(); ++i) {
      if (s[i] < '0' || s[i] > '9') ok = false;
      port = port * 10 + (s[i] - '0');
    }
    ok = ok && port >= 1 && port <= 65535;
  }
  return ok ? "" : "must be HOST:PORT with PORT in [1, 65535]";
}

// code-size: table (one entry per key; scripts/code-size lists it apart from the functions)
std::vector<KeySpec> build_key_table() {
  using drivers::qnavcan::Mode;
  const DaemonConfig defaults;
  // Registrations the filter keeps per update (route::kMaxMeasurementsKept) less the wide-search ones
  // that come on top of the belief registrations: the most belief_registrations can be.
  const auto max_belief =
      static_cast<std::int64_t>(route::kMaxMeasurementsKept - defaults.localiser.filter.wide_search_registrations);

  std::vector<KeySpec> t;
  // [daemon]
  t.push_back(enum_key(
      "daemon.backend", [](auto& c) -> auto& { return c.backend; },
      std::vector<std::pair<std::string, Backend>>{{"sim", Backend::kSim}, {"linux", Backend::kLinux}},
      "sim: the simulated vehicle in-process (sensors and autopilot, [sim]); linux: the vehicle's CAN bus, sonar and "
      "DVL"));
  t.push_back(string_key(
      "daemon.route_dir", [](auto& c) -> auto& { return c.route_dir; }, "not empty", check_not_empty,
      "Folder of the route files (`route_<id>.qroute`)"));
  t.push_back(enum_key(
      "daemon.log", [](auto& c) -> auto& { return c.log; },
      std::vector<std::pair<std::string, LogFormat>>{
          {"json", LogFormat::kJson}, {"kv", LogFormat::kKeyValue}, {"off", LogFormat::kOff}},
      "One line per tile on stdout: JSON, key=value pairs, or none"));
  t.push_back(bool_key(
      "daemon.realtime", [](auto& c) -> auto& { return c.realtime; },
      "mlockall and SCHED_FIFO threads when permitted"));
  t.push_back(int_key(
      "daemon.io_priority", [](auto& c) -> auto& { return c.io_priority; }, 1, 99, "",
      "SCHED_FIFO priority of the I/O thread"));
  t.push_back(int_key(
      "daemon.nav_priority", [](auto& c) -> auto& { return c.nav_priority; }, 1, 99, "",
      "SCHED_FIFO priority of the navigation thread"));
  t.push_back(int_key(
      "daemon.io_cpu", [](auto& c) -> auto& { return c.io_cpu; }, -1, 63, "", "CPU the I/O thread runs on; -1 = any"));
  t.push_back(int_key(
      "daemon.nav_cpu", [](auto& c) -> auto& { return c.nav_cpu; }, -1, 63, "",
      "CPU the navigation thread runs on; -1 = any"));
  t.push_back(float_key(
      "daemon.shutdown_timeout_s", [](auto& c) -> auto& { return c.shutdown_timeout_s; }, 0.1, 60.0, "s",
      "Longest wait for the threads to stop on shutdown"));
  t.push_back(float_key(
      "daemon.health_period_s", [](auto& c) -> auto& { return c.health_period_s; }, 0.1, 60.0, "s",
      "Period of the health log line with the counters"));
  // [can]
  t.push_back(string_key(
      "can.interface", [](auto& c) -> auto& { return c.can_interface; }, "interface name, 1 to 15 characters",
      check_interface, "SocketCAN interface of the vehicle bus (linux backend)"));
  t.push_back(float_key(
      "can.attitude_stale_s", [](auto& c) -> auto& { return c.attitude_stale_s; }, 0.01, 10.0, "s",
      "Attitude older than this is stale"));
  t.push_back(float_key(
      "can.depth_stale_s", [](auto& c) -> auto& { return c.depth_stale_s; }, 0.01, 60.0, "s",
      "Depth older than this is stale"));
  t.push_back(queue_key(
      "can.rx_queue", [](auto& c) -> auto& { return c.can_rx_queue; }, 16, 4096, "frames", "CAN receive queue depth"));
  t.push_back(queue_key(
      "can.tx_queue", [](auto& c) -> auto& { return c.can_tx_queue; }, 16, 4096, "frames", "CAN transmit queue depth"));
  // [sonar]
  t.push_back(enum_key(
      "sonar.source", [](auto& c) -> auto& { return c.sonar_source; },
      std::vector<std::pair<std::string, SonarSource>>{{"sim", SonarSource::kSim}, {"jsf_tcp", SonarSource::kJsfTcp}},
      "sim: the simulated side-scan; jsf_tcp: an EdgeTech JSF stream over TCP from sonar.address"));
  t.push_back(string_key(
      "sonar.address", [](auto& c) -> auto& { return c.sonar_address; }, "HOST:PORT", check_host_port,
      "Sonar topside address (jsf_tcp)"));
  t.push_back(float_key(
      "sonar.stale_s", [](auto& c) -> auto& { return c.sonar_stale_s; }, 0.1, 60.0, "s",
      "No ping for this long: sonar stale"));
  t.push_back(queue_key(
      "sonar.ping_queue", [](auto& c) -> auto& { return c.ping_queue; }, 4, 1024, "pings",
      "Ping queue depth between the sonar reader and the navigation thread"));
  t.push_back(
      with_setter(int_key(
                      "sonar.max_samples_per_side", [](auto& c) -> auto& { return c.max_samples_per_side; }, 64, 16384,
                      "samples", "Largest ping accepted, per side; also the scanline corrector's max_samples_per_side"),
                  [](DaemonConfig& c, const Value& v) {
                    c.max_samples_per_side = static_cast<std::size_t>(v.i);
                    c.tiles.corrector.max_samples_per_side = static_cast<int>(v.i);
                  }));
  // [dvl]
  t.push_back(bool_key(
      "dvl.enabled", [](auto& c) -> auto& { return c.dvl_enabled; }, "Read the DVL"));
  t.push_back(string_key(
      "dvl.device", [](auto& c) -> auto& { return c.dvl_device; }, "not empty", check_not_empty,
      "DVL serial device (linux backend)"));
  t.push_back(enum_key(
      "dvl.protocol", [](auto& c) -> auto& { return c.dvl_protocol; },
      std::vector<std::pair<std::string, std::string>>{{"waterlinked", "waterlinked"}, {"pd6", "pd6"}},
      "Water Linked DVL serial protocol, or Teledyne RDI PD6"));
  {
    KeySpec baud = int_key(
        "dvl.baud", [](auto& c) -> auto& { return c.dvl_baud; }, 0, 0, "bit/s", "DVL serial speed");
    baud.int_choices = {9600, 19200, 38400, 57600, 115200, 230400, 460800};
    t.push_back(baud);
  }
  t.push_back(float_key(
      "dvl.stale_s", [](auto& c) -> auto& { return c.dvl_stale_s; }, 0.05, 60.0, "s",
      "DVL velocity older than this is stale"));
  // [leak]
  t.push_back(string_key(
      "leak.chip", [](auto& c) -> auto& { return c.leak_chip; }, "gpiochip name or \"\"", nullptr,
      "GPIO chip of the leak detector's line (libgpiod, linux backend); \"\" = no leak detector"));
  t.push_back(int_key(
      "leak.line", [](auto& c) -> auto& { return c.leak_line; }, 0, 511, "", "Line offset of the leak detector on leak.chip"));
  t.push_back(bool_key(
      "leak.active_low", [](auto& c) -> auto& { return c.leak_active_low; },
      "The detector pulls the line low when wet (false: high when wet)"));
  // [mavlink]
  t.push_back(bool_key(
      "mavlink.enabled", [](auto& c) -> auto& { return c.mavlink_enabled; },
      "Be the autopilot's external navigation source over MAVLink 2 (ODOMETRY, VISION_POSITION_DELTA, DISTANCE_SENSOR; docs/interfaces.md)"));
  t.push_back(string_key(
      "mavlink.udp_remote", [](auto& c) -> auto& { return c.mavlink_udp_remote; }, "HOST:PORT (IPv4) or \"\"",
      [](const std::string& s) { return s.empty() ? std::string() : check_host_port(s); },
      "Send to this UDP endpoint (the autopilot, mavlink-router, a ground station) and read its replies; \"\" = none"));
  t.push_back(int_key(
      "mavlink.udp_listen_port", [](auto& c) -> auto& { return c.mavlink_udp_listen_port; }, 0, 65535, "",
      "Also serve MAVLink on this UDP port (replies go to the sender of valid frames, kept while it is alive); 0 = none"));
  t.push_back(string_key(
      "mavlink.serial_device", [](auto& c) -> auto& { return c.mavlink_serial_device; }, "device path or \"\"", nullptr,
      "The autopilot's serial port (linux backend, e.g. /dev/ttyAMA0); \"\" = none"));
  {
    KeySpec baud = int_key(
        "mavlink.baud", [](auto& c) -> auto& { return c.mavlink_baud; }, 0, 0, "bit/s", "mavlink.serial_device speed");
    baud.int_choices = {57600, 115200, 230400, 460800, 921600};
    t.push_back(baud);
  }
  t.push_back(int_key(
      "mavlink.system_id", [](auto& c) -> auto& { return c.mavlink_system_id; }, 1, 255, "",
      "qnavd's MAVLink system id (the vehicle's: the autopilot's own SYSID_THISMAV / MAV_SYS_ID)"));
  t.push_back(int_key(
      "mavlink.component_id", [](auto& c) -> auto& { return c.mavlink_component_id; }, 1, 255, "",
      "qnavd's MAVLink component id (197 = MAV_COMP_ID_VISUAL_INERTIAL_ODOMETRY)"));
  t.push_back(float_key(
      "mavlink.odometry_hz", [](auto& c) -> auto& { return c.mavlink_odometry_hz; }, 1.0, 50.0, "Hz",
      "ODOMETRY and VISION_POSITION_DELTA rate (ArduPilot needs >= 4 Hz)"));
  t.push_back(bool_key(
      "mavlink.guided", [](auto& c) -> auto& { return c.mavlink_guided; },
      "In Repeat, while the autopilot reports GUIDED and armed, send the look-ahead waypoint as SET_POSITION_TARGET_LOCAL_NED"));
  t.push_back(int_key(
      "mavlink.autopilot_system_id", [](auto& c) -> auto& { return c.mavlink_autopilot_system_id; }, 1, 255, "",
      "The only system whose COMMAND_LONG mode commands qnavd accepts (others are refused and counted)"));
  t.push_back(int_key(
      "mavlink.autopilot_component_id", [](auto& c) -> auto& { return c.mavlink_autopilot_component_id; }, 1, 255, "",
      "The only component (of autopilot_system_id) whose mode commands qnavd accepts"));
  t.push_back(string_key(
      "mavlink.key_file", [](auto& c) -> auto& { return c.mavlink_key_file; }, "absolute path or \"\"",
      [](const std::string& s) { return s.empty() || s[0] == '/' ? std::string() : std::string("must be an absolute path"); },
      "MAVLink 2 signing key: a regular file owned by root, mode 0600, of 64 hex digits (32 bytes); mode commands must then be "
      "signed with it and qnavd signs what it sends; \"\" = no signing"));
  t.push_back(float_key(
      "mavlink.origin_lat_deg", [](auto& c) -> auto& { return c.mavlink_origin_lat_deg; }, -90.0, 90.0, "deg",
      "EKF origin latitude (WGS84), sent as SET_GPS_GLOBAL_ORIGIN until the autopilot answers GPS_GLOBAL_ORIGIN; "
      "set with origin_lon_deg, or neither (no origin sent)"));
  t.push_back(float_key(
      "mavlink.origin_lon_deg", [](auto& c) -> auto& { return c.mavlink_origin_lon_deg; }, -180.0, 180.0, "deg",
      "EKF origin longitude (WGS84); set with origin_lat_deg"));
  t.push_back(float_key(
      "mavlink.origin_alt_m", [](auto& c) -> auto& { return c.mavlink_origin_alt_m; }, -1000.0, 10000.0, "m",
      "EKF origin altitude above mean sea level (the water surface's, for a depth-referenced vehicle); only with origin_lat_deg"));
  // [vo]
  t.push_back(bool_key(
      "vo.enabled", [](auto& c) -> auto& { return c.vo_enabled; },
      "Read the stereo camera pair and accept Mode = Vo (sizes the frame pool and the VO arena)"));
  t.push_back(enum_key(
      "vo.camera", [](auto& c) -> auto& { return c.vo_camera; },
      std::vector<std::pair<std::string, CameraSource>>{{"sim", CameraSource::kSim}, {"v4l2", CameraSource::kV4l2}},
      "sim: the simulated rover's stereo bench (sim backend); v4l2: two V4L2 cameras (vo.left_device, vo.right_device)"));
  t.push_back(string_key(
      "vo.left_device", [](auto& c) -> auto& { return c.vo_left_device; }, "not empty", check_not_empty,
      "Left camera (v4l2), rectified GREY or YUYV frames of vo.width x vo.height"));
  t.push_back(string_key(
      "vo.right_device", [](auto& c) -> auto& { return c.vo_right_device; }, "not empty", check_not_empty,
      "Right camera (v4l2)"));
  t.push_back(string_key(
      "vo.trigger_chip", [](auto& c) -> auto& { return c.vo_trigger_chip; }, "gpiochip name or \"\"", nullptr,
      "GPIO chip of the cameras' hardware trigger line (libgpiod); \"\" = free-running cameras"));
  t.push_back(int_key(
      "vo.trigger_line", [](auto& c) -> auto& { return c.vo_trigger_line; }, 0, 511, "",
      "Line offset of the trigger on vo.trigger_chip"));
  t.push_back(float_key(
      "vo.rate_hz", [](auto& c) -> auto& { return c.vo_rate_hz; }, 0.5, 60.0, "Hz",
      "Pairs per second the trigger line asks for (free-running cameras keep their own rate)"));
  t.push_back(float_key(
      "vo.pair_tolerance_ms", [](auto& c) -> auto& { return c.vo_pair_tolerance_ms; }, 0.01, 1000.0, "ms",
      "Left and right frames whose kernel stamps are this close make a pair (v4l2). Triggered cameras: ~0.1 ms apart; "
      "free-running, unsynchronised cameras need up to half a frame period, and the rig's motion in that time is a stereo error"));
  t.push_back(enum_key(
      "vo.preset", [](auto& c) -> auto& { return c.vo_preset; },
      std::vector<std::pair<std::string, VoPreset>>{{"bench", VoPreset::kBench}, {"kitti", VoPreset::kKitti}, {"euroc", VoPreset::kEuroc}},
      "Tuned settings the VO starts from (firmware/pipeline/vo_defaults): bench = the simulated rover with an attitude sensor; "
      "kitti = a car's stereo pair without one (6D, constant velocity); euroc = a hovering rig (6D, zero motion). The vo.* keys the "
      "file sets override it"));
  t.push_back(int_key(
      "vo.width", [](auto& c) -> auto& { return c.vo.max_width; }, 64, 2048, "px",
      "Width of one rectified camera image (sizes the frame pool and the VO buffers)"));
  t.push_back(int_key(
      "vo.height", [](auto& c) -> auto& { return c.vo.max_height; }, 64, 2048, "px", "Height of one rectified camera image"));
  t.push_back(float_key(
      "vo.focal_px", [](auto& c) -> auto& { return c.vo.camera.focal_px; }, 10.0, 20000.0, "px", "Focal length of the rectified pair"));
  t.push_back(float_key(
      "vo.cu_px", [](auto& c) -> auto& { return c.vo.camera.cu_px; }, 0.0, 2047.0, "px", "Principal point, column"));
  t.push_back(float_key(
      "vo.cv_px", [](auto& c) -> auto& { return c.vo.camera.cv_px; }, 0.0, 2047.0, "px", "Principal point, row"));
  t.push_back(float_key(
      "vo.baseline_m", [](auto& c) -> auto& { return c.vo.camera.baseline_m; }, 0.005, 5.0, "m", "Stereo baseline"));
  t.push_back(float_key(
      "vo.tilt_down_deg", [](auto& c) -> auto& { return c.vo_tilt_down_deg; }, 0.0, 90.0, "deg",
      "Camera mount: optical axis forward, tilted down by this much (90 = looking straight down)"));
  t.push_back(float_key(
      "vo.mount_height_m", [](auto& c) -> auto& { return c.vo_mount_height_m; }, 0.0, 10.0, "m",
      "Camera mount: left camera above the body origin"));
  t.push_back(int_key(
      "vo.max_corners", [](auto& c) -> auto& { return c.vo.max_corners; }, 32, 1000, "corners",
      "Harris corners per frame (bounds stereo, matching and motion estimation)"));
  t.push_back(enum_key(
      "vo.vme", [](auto& c) -> auto& { return c.vo.mode; },
      std::vector<std::pair<std::string, vo::VmeMode>>{{"3d", vo::VmeMode::k3D}, {"6d", vo::VmeMode::k6D}},
      "Motion estimation: 3d = translation with the attitude sensor's rotation (Mars paper eq. 9); 6d = Arun"));
  t.push_back(bool_key(
      "vo.attitude_filter", [](auto& c) -> auto& { return c.vo.estimate_attitude_bias; },
      "3d: estimate the attitude sensor's drift from the visual rotations (nav/motion AttitudeBiasFilter)"));
  t.push_back(float_key(
      "vo.max_step_m", [](auto& c) -> auto& { return c.vo.max_step_m; }, 0.01, 100.0, "m",
      "Largest plausible motion between two frames (a larger step is refused as implausible)"));
  t.push_back(queue_key(
      "vo.frame_queue", [](auto& c) -> auto& { return c.vo_frame_queue; }, 2, 64, "pairs",
      "Stereo pair queue depth between the camera reader and the navigation thread (frame pool slots)"));
  t.push_back(float_key(
      "vo.stale_s", [](auto& c) -> auto& { return c.vo_stale_s; }, 0.1, 60.0, "s",
      "No stereo pair for this long in Mode = Vo: camera lost (FaultCameraLost)"));
  // [map]
  t.push_back(bool_key(
      "map.enabled", [](auto& c) -> auto& { return c.map_enabled; },
      "Take downward-camera frames into the frame pool and accept Mode = Map (sizes the mapper's arena). Sim backend: the "
      "simulated camera of a [[sim.pass]] with mode = \"map\"; linux backend: the V4L2 camera map.device (without one, "
      "Mode = Map is refused with UnsupportedMode and nothing is sized for it)"));
  t.push_back(string_key(
      "map.device", [](auto& c) -> auto& { return c.map_device; }, "V4L2 capture device or \"\"", nullptr,
      "Downward camera (linux backend): a V4L2 capture device giving rectified GREY or YUYV frames of map.width x map.height "
      "(intrinsics: map.focal_px, cu_px, cv_px), opened at start and reopened once a second when it fails; \"\" = none. "
      "The sim backend flies its simulated camera: must be \"\" there"));
  t.push_back(int_key(
      "map.width", [](auto& c) -> auto& { return c.map_width; }, 64, 2048, "px", "Width of a rectified downward frame"));
  t.push_back(int_key(
      "map.height", [](auto& c) -> auto& { return c.map_height; }, 64, 2048, "px", "Height of a rectified downward frame"));
  t.push_back(float_key(
      "map.focal_px", [](auto& c) -> auto& { return c.map_focal_px; }, 0.0, 20000.0, "px",
      "Focal length of the downward camera; 0 = unknown (the map in mosaic pixels, as `qnav map` without --camera)"));
  t.push_back(float_key(
      "map.cu_px", [](auto& c) -> auto& { return c.map_cu_px; }, -1.0, 2047.0, "px", "Principal point, column; -1 = image centre"));
  t.push_back(float_key(
      "map.cv_px", [](auto& c) -> auto& { return c.map_cv_px; }, -1.0, 2047.0, "px", "Principal point, row; -1 = image centre"));
  t.push_back(float_key(
      "map.altitude_m", [](auto& c) -> auto& { return c.map_altitude_m; }, 0.0, 1000.0, "m",
      "Camera altitude above the seabed (constant); with map.focal_px the map is in metres; 0 = unknown"));
  t.push_back(float_key(
      "map.node_spacing", [](auto& c) -> auto& { return c.map_node_spacing; }, 0.0, 1e6, "m or px",
      "Topological map node spacing (metres when metric, else mosaic pixels); 0 = 0.2 m / 30 px (`qnav map`'s default)"));
  t.push_back(int_key(
      "map.max_nodes", [](auto& c) -> auto& { return c.map_max_nodes; }, 2, 65534, "nodes", "Topological map nodes at most (fixed memory)"));
  t.push_back(queue_key(
      "map.frame_queue", [](auto& c) -> auto& { return c.map_frame_queue; }, 2, 64, "frames",
      "Downward frame queue depth between the camera reader and the navigation thread (frame pool slots)"));
  t.push_back(float_key(
      "map.stale_s", [](auto& c) -> auto& { return c.map_stale_s; }, 0.1, 60.0, "s",
      "No downward frame for this long in Mode = Map (or the camera device down): camera lost (FaultCameraLost)"));
  // [route]
  t.push_back(int_key(
      "route.id", [](auto& c) -> auto& { return c.route_id; }, 0, 65535, "",
      "Route used when QNAV_MODE_CMD gives route id 0"));
  t.push_back(with_setter(int_key(
                              "route.max_nodes", [](auto& c) -> auto& { return c.max_nodes; }, 2, 65535, "nodes",
                              "Longest route; sizes the route store and the localiser's belief (filter max_nodes)"),
                          [](DaemonConfig& c, const Value& v) {
                            c.max_nodes = static_cast<std::size_t>(v.i);
                            c.localiser.filter.max_nodes = static_cast<std::size_t>(v.i);
                          }));
  t.push_back(float_key(
      "route.tile_length_m", [](auto& c) -> auto& { return c.tiles.tiles.tile_length_m; }, 0.0, 5000.0, "m",
      "Along-track length of a sonar tile (dead-reckoned travel); 0 frames tiles by ping count (route.scanlines_per_tile)"));
  t.push_back(with_rule(float_key(
                            "route.tile_stride_m", [](auto& c) -> auto& { return c.tiles.tiles.tile_stride_m; }, 0.1,
                            5000.0, "m", "A tile (a route node when teaching) every this much travel"),
                        "<= route.tile_length_m"));
  t.push_back(int_key(
      "route.scanlines_per_tile", [](auto& c) -> auto& { return c.tiles.tiles.scanlines_per_tile; }, 20, 4000, "pings",
      "Most pings a tile holds (by distance: more are counted as tile_overflow; default: route.tile_length_m at 0.05 m per "
      "ping); with route.tile_length_m = 0, the pings per tile"));
  t.push_back(with_rule(int_key(
                            "route.scanline_stride", [](auto& c) -> auto& { return c.tiles.tiles.scanline_stride; }, 1,
                            4000, "pings", "With route.tile_length_m = 0: a tile every this many pings (unused by distance)"),
                        "<= route.scanlines_per_tile"));
  t.push_back(float_key(
      "route.resolution_m", [](auto& c) -> auto& { return c.tiles.tiles.resolution_m; }, 0.01, 5.0, "m",
      "Tile pixel size"));
  t.push_back(with_setter(int_key(
                              "route.tile_px", [](auto& c) -> auto& { return c.tiles.tiles.tile_width_px; }, 64, 2048,
                              "px", "Tile raster side (square); also the feature extractor's largest tile"),
                          [](DaemonConfig& c, const Value& v) {
                            const int px = static_cast<int>(v.i);
                            c.tiles.tiles.tile_width_px = px;
                            c.tiles.tiles.tile_height_px = px;
                            c.tiles.features.max_width = px;
                            c.tiles.features.max_height = px;
                          }));
  t.push_back(with_setter(
      int_key(
          "route.ground_bins_per_side", [](auto& c) -> auto& { return c.tiles.corrector.ground_bins_per_side; }, 16,
          4096, "bins", "Ground-range bins per side of a corrected ping; also the tile builder's max_bins_per_side"),
      [](DaemonConfig& c, const Value& v) {
        c.tiles.corrector.ground_bins_per_side = static_cast<int>(v.i);
        c.tiles.tiles.max_bins_per_side = static_cast<int>(v.i);
      }));
  t.push_back(float_key(
      "route.ground_bin_m", [](auto& c) -> auto& { return c.tiles.corrector.ground_bin_m; }, 0.01, 5.0, "m",
      "Ground-range bin size"));
  t.push_back(int_key(
      "route.max_keypoints", [](auto& c) -> auto& { return c.tiles.features.max_keypoints; }, 8,
      static_cast<std::int64_t>(route::kMaxKeypointsPerNode), "keypoints",
      "Keypoints kept per tile (and per route node)"));
  t.push_back(int_key(
      "route.belief_registrations", [](auto& c) -> auto& { return c.localiser.filter.belief_registrations; }, 1,
      max_belief, "registrations", "Registrations per update against the most probable nodes"));
  t.push_back(with_rule(
      int_key(
          "route.searching_registrations", [](auto& c) -> auto& { return c.localiser.filter.searching_registrations; },
          1, static_cast<std::int64_t>(route::kMaxMeasurementsKept), "registrations",
          "Registrations per update while searching (not localised, or lost)"),
      ">= route.belief_registrations"));
  t.push_back(int_key(
      "route.min_inliers", [](auto& c) -> auto& { return c.localiser.registration.robust.min_inliers; }, 3, 100,
      "inliers", "Fewest RANSAC inliers for a registration to count"));
  t.push_back(float_key(
      "route.side_deadband_m", [](auto& c) -> auto& { return c.localiser.guidance.side_deadband_m; }, 0.0, 100.0, "m",
      "Cross-track offsets within this are on the route (side on_route)"));
  t.push_back(float_key(
      "route.dead_reckon_max_m", [](auto& c) -> auto& { return c.localiser.guidance.dead_reckon_max_m; }, 0.0, 10000.0,
      "m", "Travel after the last fix still steered on dead reckoning; 0 = never"));
  t.push_back(bool_key(
      "route.learn", [](auto& c) -> auto& { return c.route_learn; },
      "Repeat learns: confidently localised tiles that agree with odometry are appended to the route's experiences (ROUTE.exp)"));
  t.push_back(float_key(
      "route.entry_prior", [](auto& c) -> auto& { return c.route_entry_prior; }, 0.0, 0.99, "share",
      "Share of a Repeat pass's start belief on the route's entry end (node 0 forwards, the last node in reverse), "
      "the rest uniform; 0: uniform, for a pass that may join the route anywhere"));
  t.push_back(int_key(
      "route.max_experiences", [](auto& c) -> auto& { return c.max_experiences; }, 1,
      static_cast<std::int64_t>(route::kMaxExperiencesPerNode), "experiences",
      "Experiences per route node beside the taught one (fixed memory; a new ROUTE.exp is created with it)"));
  t.push_back(enum_key(
      "route.motion", [](auto& c) -> auto& { return c.localiser.filter.motion; },
      std::vector<std::pair<std::string, route::MotionModel>>{{"odometry", route::MotionModel::kOdometry},
                                                              {"eq5", route::MotionModel::kPaperEq5}},
      "Filter motion model: odometry (distance travelled) or eq5 (the paper's fixed transition kernel)"));
  // [budget]
  t.push_back(int_key(
      "budget.ping_us", [](auto& c) -> auto& { return c.ping_budget_us; }, 10, 1000000, "us",
      "Time budget of one ping; a longer one counts a deadline miss (docs/budgets.md)"));
  t.push_back(int_key(
      "budget.tile_us", [](auto& c) -> auto& { return c.tile_budget_us; }, 100, 10000000, "us",
      "Time budget of one tile: features + localiser update"));
  t.push_back(int_key(
      "budget.mode_us", [](auto& c) -> auto& { return c.mode_budget_us; }, 100, 10000000, "us",
      "Time budget of a mode change: route file create / open and every node's metadata read (fsync included)"));
  t.push_back(int_key(
      "budget.vo_us", [](auto& c) -> auto& { return c.vo_budget_us; }, 100, 10000000, "us",
      "Time budget of one stereo pair through the visual odometry"));
  t.push_back(int_key(
      "budget.map_us", [](auto& c) -> auto& { return c.map_budget_us; }, 100, 10000000, "us",
      "Time budget of one downward frame in Mode = Map: homography chain, topological map (and the map file's "
      "rewrite after a new node)"));
  // [sim]
  t.push_back(float_key(
      "sim.length_m", [](auto& c) -> auto& { return c.sim_length_m; }, 200.0, 50000.0, "m",
      "Length of the simulated survey line"));
  t.push_back(int_key(
      "sim.seed", [](auto& c) -> auto& { return c.sim_seed; }, 0, 4294967295LL, "",
      "Seed of the simulated seabed and sensors"));
  {
    KeySpec speed = float_key(
        "sim.speed", [](auto& c) -> auto& { return c.sim_speed; }, SimSpeed::kFast, SimSpeed::kMax, "x real time",
        "Pace of the simulated mission: 0 = as fast as the pipeline takes it; a factor of real time (1 = real time, 10 = ten "
        "times faster), slept to absolute deadlines on the monotonic clock, a late step counted (sim_late_steps), never "
        "skipped; the lockstep with the daemon holds at every speed (docs/fly-along.md)");
    speed.aliases = {{"fast", SimSpeed::kFast}, {"recorded", SimSpeed::kRecorded}};
    t.push_back(speed);
  }
  t.push_back(string_key(
      "sim.can_interface", [](auto& c) -> auto& { return c.sim_can_interface; }, "an interface name; \"\" = in process",
      [](const std::string& s) { return s.empty() ? std::string() : check_interface(s); },
      "The SocketCAN interface (vcan0, can0) the simulated vehicle and qnavd exchange their CAN frames on, so candump "
      "and SavvyCAN see the mission; \"\" = an in-process bus. It must exist when qnavd starts"));
  t.push_back(bool_key(
      "sim.exit_at_end", [](auto& c) -> auto& { return c.sim_exit_at_end; },
      "qnavd exits 0 when the mission is flown"));
  t.push_back(int_key(
      "sim.replay_lines", [](auto& c) -> auto& { return c.sim_replay_lines; }, 10, 2000, "pings",
      "Recorded passes: pings per tile (as `qnav route train --sonar --lines`)"));
  t.push_back(with_rule(int_key(
                            "sim.replay_stride", [](auto& c) -> auto& { return c.sim_replay_stride; }, 1, 2000, "pings",
                            "Recorded passes: a tile every this many pings (as `--stride`)"),
                        "<= sim.replay_lines"));
  t.push_back(enum_key(
      "sim.replay_nav", [](auto& c) -> auto& { return c.sim_replay_nav; },
      std::vector<std::pair<std::string, std::string>>{{"fix", "fix"}, {"dr", "dr"}},
      "Recorded passes: navigation from the file's position fixes or by dead reckoning on its speed and heading"));
  t.push_back(enum_key(
      "sim.ahrs", [](auto& c) -> auto& { return c.sim_ahrs; },
      std::vector<std::pair<std::string, std::string>>{{"qnav", "qnav"}, {"dronecan", "dronecan"}},
      "The simulated AHRS speaks qnav's QNAV_ATTITUDE_IN or a DroneCAN uavcan.equipment.ahrs.Solution (node 42)"));
  t.push_back(string_key(
      "sim.candump", [](auto& c) -> auto& { return c.sim_candump; }, "any; \"\" = off", nullptr,
      "File the simulated autopilot records every bus frame to (candump -l format, `qnav can decode` reads it)"));
  t.push_back(string_key(
      "sim.closed_loop_csv", [](auto& c) -> auto& { return c.sim_closed_loop_csv; }, "any; \"\" = off", nullptr,
      "File the closed-loop passes (sim.pass.closed_loop) write their tracks to: taught, qnav-guided, dead reckoning alone "
      "(the CSV of `qnav route follow --csv`; scripts/route_follow_plot.py draws it)"));
  t.push_back(enum_key(
      "sim.stall", [](auto& c) -> auto& { return c.sim_stall; },
      std::vector<std::pair<std::string, std::string>>{
          {"none", "none"}, {"dvl", "dvl"}, {"attitude", "attitude"}, {"sonar", "sonar"}, {"camera", "camera"}},
      "Fault test: this simulated sensor falls silent for sim.stall_s during pass sim.stall_pass"));
  t.push_back(with_rule(
      int_key(
          "sim.stall_pass", [](auto& c) -> auto& { return c.sim_stall_pass; }, 0,
          static_cast<std::int64_t>(kMaxPasses) - 1, "", "Pass of the stall, counting the [[sim.pass]] tables from 0"),
      "< number of passes"));
  t.push_back(float_key(
      "sim.stall_start_s", [](auto& c) -> auto& { return c.sim_stall_start_s; }, 0.0, 100000.0, "s",
      "Start of the stall after the start of its pass (mission time)"));
  t.push_back(float_key(
      "sim.stall_s", [](auto& c) -> auto& { return c.sim_stall_s; }, 0.0, 3600.0, "s",
      "Length of the stall (mission time)"));
  {
    std::vector<std::pair<std::string, std::string>> kinds;
    for (const char* k : kSimFaultKinds) kinds.emplace_back(k, k);
    t.push_back(enum_key(
        "sim.fault", [](auto& c) -> auto& { return c.sim_fault; }, kinds,
        "Fault injection: damaged or disordered input during sim.fault_s of pass sim.fault_pass (docs/reliability.md)"));
  }
  t.push_back(with_rule(
      int_key(
          "sim.fault_pass", [](auto& c) -> auto& { return c.sim_fault_pass; }, 0,
          static_cast<std::int64_t>(kMaxPasses) - 1, "", "Pass of the injected fault, counting the [[sim.pass]] tables from 0"),
      "< number of passes"));
  t.push_back(float_key(
      "sim.fault_start_s", [](auto& c) -> auto& { return c.sim_fault_start_s; }, 0.0, 100000.0, "s",
      "Start of the injected fault after the start of its pass (mission time)"));
  t.push_back(float_key(
      "sim.fault_s", [](auto& c) -> auto& { return c.sim_fault_s; }, 0.0, 3600.0, "s",
      "Length of the injected fault (mission time)"));
  // [[sim.pass]]
  {
    KeySpec mode = enum_key(
        "sim.pass.mode", [](auto& c) -> auto& { return pass_of(c).mode; },
        std::vector<std::pair<std::string, Mode>>{
            {"teach", Mode::kTeach}, {"repeat", Mode::kRepeat}, {"hold", Mode::kHold}, {"vo", Mode::kVo}, {"map", Mode::kMap}},
        "Mode the simulated autopilot commands (QNAV_MODE_CMD) for the pass, Idle after it; one `[[sim.pass]]` "
        "table per pass, 1 to 16, at least one with the sim backend");
    mode.required = true;
    t.push_back(mode);
  }
  t.push_back(float_key(
      "sim.pass.offset_pct", [](auto& c) -> auto& { return pass_of(c).offset_pct; }, -100.0, 100.0, "%",
      "Lateral offset of the pass, percent of the full swath, right of the taught direction"));
  t.push_back(bool_key(
      "sim.pass.reverse", [](auto& c) -> auto& { return pass_of(c).reverse; },
      "Fly the pass from the route's last node to its first"));
  t.push_back(float_key(
      "sim.pass.length_m", [](auto& c) -> auto& { return pass_of(c).length_m; }, 0.5, 1000.0, "m",
      "Mode vo: distance the simulated rover drives over the Mars yard (stereo pairs every 0.15-0.25 m)"));
  t.push_back(string_key(
      "sim.pass.file", [](auto& c) -> auto& { return pass_of(c).file; }, "XTF or JSF file; \"\" = the simulated survey", nullptr,
      "Replay this recorded side-scan file in the pass (its navigation, timing and pings) instead of the simulated survey"));
  t.push_back(int_key(
      "sim.pass.first_ping", [](auto& c) -> auto& { return pass_of(c).first_ping; }, 0, 999999999, "",
      "First ping of the recorded file flown in the pass"));
  t.push_back(with_rule(int_key(
                            "sim.pass.last_ping", [](auto& c) -> auto& { return pass_of(c).last_ping; }, -1, 1000000000, "",
                            "End of the pass in the recorded file (exclusive); -1 = the end of the file"),
                        "-1 or > first_ping"));
  t.push_back(string_key(
      "sim.pass.candump", [](auto& c) -> auto& { return pass_of(c).candump; }, "candump -l log or \"\"", nullptr,
      "Replay the CAN sensors of this candump -l log in the pass (attitude, DroneCAN AHRS) instead of the simulated AHRS; "
      "mode commands and qnavd's own frames in it are skipped"));
  t.push_back(string_key(
      "sim.pass.dvl_log", [](auto& c) -> auto& { return pass_of(c).dvl_log; }, "DVL capture or \"\"", nullptr,
      "Replay this capture of the DVL's serial output (dvl.protocol, timed by its own sentences) instead of the simulated DVL"));
  t.push_back(string_key(
      "sim.pass.images", [](auto& c) -> auto& { return pass_of(c).images; }, "stereo sequence or frame folder, or \"\"", nullptr,
      "Mode vo: replay this rectified stereo sequence (KITTI layout left/ right/, or EuRoC cam0/ cam1/) instead of the simulated rover; "
      "mode map: the downward camera's frames, every .png/.jpg/.pgm of the folder in name order, map.width x map.height; \"\" = the "
      "synthetic seabed loop (drivers/downward_sim: 320 x 240, f 300 px, 2 m up, 90 frames per lap of radius 0.8 m)"));
  t.push_back(bool_key(
      "sim.pass.closed_loop", [](auto& c) -> auto& { return pass_of(c).closed_loop; },
      "Mode repeat, simulated: fly the pass in closed loop -- the vehicle steers on qnavd's QNAV_ROUTE_GUIDANCE / STATUS "
      "frames (the autopilot law of `qnav route follow`, docs/route.md) with 1 deg compass bias, 1 % DVL scale error, "
      "DVL dropouts and a 0.2 m/s current, starting offset_pct off the route; a twin flies the same on dead reckoning alone"));
  t.push_back(int_key(
      "sim.pass.max_frames", [](auto& c) -> auto& { return pass_of(c).max_frames; }, 0, 1000000, "pairs",
      "Pairs (mode vo) or frames (mode map) of sim.pass.images replayed; 0 = all (the synthetic seabed loop: 120 frames)"));
  return t;
}

const std::vector<KeySpec>& key_table() {
  static const std::vector<KeySpec> table = build_key_table();
  return table;
}

const std::vector<std::string>& section_names() {
  static const std::vector<std::string> names = {"daemon", "can", "sonar", "dvl", "leak", "mavlink", "vo", "map", "route", "budget", "sim"};
  return names;
}

const KeySpec* find_key(const std::string& name) {
  for (const KeySpec& k : key_table())
    if (k.name == name) return &k;
  return nullptr;
}

bool is_pass_key(const KeySpec& k) { return k.name.rfind("sim.pass.", 0) == 0; }

// ---- Suggestions ----------------------------------------------------------------------------------

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

std::string closest(const std::string& name, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = 3;  // suggest within an edit distance of 2
  for (const std::string& c : candidates) {
    const std::size_t d = edit_distance(name, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  return best;
}

std::string leaf(const std::string& dotted) {
  const std::size_t dot = dotted.rfind('.');
  return dot == std::string::npos ? dotted : dotted.substr(dot + 1);
}

// A hint for an unknown dotted key: the nearest known key (edit distance <= 2), else the keys of the
// same name in other tables; in a [[sim.pass]], the pass keys.
std::string suggest_key(const std::string& name, bool in_pass) {
  std::vector<std::string> candidates;
  for (const KeySpec& k : key_table())
    if (is_pass_key(k) == in_pass) candidates.push_back(in_pass ? leaf(k.name) : k.name);
  const std::string probe = in_pass ? leaf(name) : name;
  const std::string best = closest(probe, candidates);
  if (!best.empty()) return "did you mean " + best + "?";
  if (in_pass) return "a [[sim.pass]] has mode, offset_pct, reverse, length_m, file, first_ping, last_ping, candump, dvl_log, images, max_frames, closed_loop";
  std::vector<std::string> same_leaf;
  for (const std::string& c : candidates)
    if (leaf(c) == leaf(name)) same_leaf.push_back(c);
  return same_leaf.empty() ? "" : "did you mean " + join(same_leaf, " or ") + "?";
}

// ---- Reading ---------------------------------------------------------------------------------------

int line_of(const toml::source_region& r) { return static_cast<int>(r.begin.line); }

class Reader {
 public:
  explicit Reader(const char* file) : file_(file ? file : "") {}

  void error(const std::string& key, int line, const std::string& message) {
    ConfigError e;
    e.key = key;
    e.line = line;
    e.message = message;
    e.file = file_;
    errors_.push_back(std::move(e));
  }
  bool failed() const { return !errors_.empty(); }
  // The error nearest the top of the file (toml++ iterates tables in key order, not file order).
  ConfigError first_error() const {
    return *std::min_element(errors_.begin(), errors_.end(), [](const ConfigError& a, const ConfigError& b) {
      const int la = a.line > 0 ? a.line : 1 << 30;
      const int lb = b.line > 0 ? b.line : 1 << 30;
      return la < lb;
    });
  }
  int line(const std::string& key) const {
    const auto it = lines_.find(key);
    return it == lines_.end() ? 0 : it->second;
  }

  void read_root(const toml::table& root, DaemonConfig& c) {
    for (auto&& [k, v] : root) {
      const std::string name(k.str());
      const int at = line_of(k.source());
      const bool known = std::find(section_names().begin(), section_names().end(), name) != section_names().end();
      if (known && v.is_table()) {
        read_section(name, *v.as_table(), c);
      } else if (known) {
        error(name, at, std::string("expected a table, got ") + node_type_text(v.type()));
      } else if (v.is_table()) {
        const std::string near = closest(name, section_names());
        error(name, at,
              near.empty() ? "unknown table; the tables are [" + join(section_names(), "], [") + "]"
                           : "unknown table (did you mean [" + near + "]?)");
      } else {
        unknown_key(name, at, false);
      }
    }
  }

 private:
  void unknown_key(const std::string& name, int at, bool in_pass) {
    const std::string hint = suggest_key(name, in_pass);
    error(name, at, hint.empty() ? "unknown key" : "unknown key (" + hint + ")");
  }

  void read_section(const std::string& section, const toml::table& table, DaemonConfig& c) {
    for (auto&& [k, v] : table) {
      const std::string name = section + "." + std::string(k.str());
      const int at = line_of(k.source());
      if (name == "sim.pass") {
        read_passes(v, at, c);
        continue;
      }
      const KeySpec* spec = find_key(name);
      if (spec == nullptr || is_pass_key(*spec)) {
        if (v.is_table())
          error(name, at, "unknown table");
        else
          unknown_key(name, at, false);
        continue;
      }
      read_value(*spec, name, v, c);
      lines_[name] = at;
    }
  }

  void read_passes(const toml::node& v, int at, DaemonConfig& c) {
    const toml::array* passes = v.as_array();
    if (passes == nullptr) {
      error("sim.pass", at, std::string("expected an array of tables ([[sim.pass]]), got ") + node_type_text(v.type()));
      return;
    }
    lines_["sim.pass"] = at;
    for (std::size_t i = 0; i < passes->size(); ++i) {
      const toml::node& p = *passes->get(i);
      const std::string where = "sim.pass[" + std::to_string(i) + "]";
      const int pass_line = line_of(p.source());
      if (i >= kMaxPasses) {
        error("sim.pass", pass_line,
              "at most " + std::to_string(kMaxPasses) + " passes (this is pass " + std::to_string(i + 1) + ")");
        return;
      }
      if (!p.is_table()) {
        error(where, pass_line, std::string("expected a table ([[sim.pass]]), got ") + node_type_text(p.type()));
        continue;
      }
      if (c.sim_mission.emplace_back() == nullptr) return;  // capacity checked above
      bool has_mode = false;
      for (auto&& [k, pv] : *p.as_table()) {
        const std::string key(k.str());
        const KeySpec* spec = find_key("sim.pass." + key);
        if (spec == nullptr) {
          unknown_key(where + "." + key, line_of(k.source()), true);
          continue;
        }
        read_value(*spec, where + "." + key, pv, c);
        lines_[where + "." + key] = line_of(k.source());
        has_mode = has_mode || key == "mode";
      }
      if (!has_mode) error(where, pass_line, "missing mode (one of \"teach\", \"repeat\", \"hold\")");
    }
  }

  // Checks type and bounds; on success stores the value through the key's setter.
  void read_value(const KeySpec& k, const std::string& name, const toml::node& node, DaemonConfig& c) {
    const int at = line_of(node.source());
    const auto wrong_type = [&] {
      error(name, at, std::string(expected_text(k.kind)) + ", got " + node_type_text(node.type()));
    };
    Value v;
    switch (k.kind) {
      case Kind::kBool:
        if (!node.is_boolean()) return wrong_type();
        v.b = node.as_boolean()->get();
        break;
      case Kind::kInt: {
        if (!node.is_integer()) return wrong_type();
        v.i = node.as_integer()->get();
        if (!k.int_choices.empty()) {
          if (std::find(k.int_choices.begin(), k.int_choices.end(), v.i) == k.int_choices.end())
            return error(name, at, "must be one of " + allowed_text(k) + ", got " + std::to_string(v.i));
        } else {
          const bool in_range = v.i >= k.int_min && v.i <= k.int_max;
          const bool pow2_ok = !k.power_of_two || (v.i > 0 && (v.i & (v.i - 1)) == 0);
          if (!in_range || !pow2_ok) {
            const std::string range = "[" + std::to_string(k.int_min) + ", " + std::to_string(k.int_max) + "]";
            return error(name, at,
                         (k.power_of_two ? "must be a power of two in " : "must be in ") + range + ", got " +
                             std::to_string(v.i));
          }
        }
        break;
      }
      case Kind::kFloat:
        if (node.is_string() && !k.aliases.empty()) {
          const std::string& word = node.as_string()->get();
          const auto it = std::find_if(k.aliases.begin(), k.aliases.end(), [&](const auto& a) { return a.first == word; });
          if (it == k.aliases.end()) {
            std::vector<std::string> words;
            for (const auto& a : k.aliases) words.push_back(quoted(a.first));
            return error(name, at,
                         "must be a number in [" + format_number(k.float_min, false) + ", " + format_number(k.float_max, false) +
                             "] or one of " + join(words, ", ") + ", got " + quoted(word));
          }
          v.f = it->second;
        } else if (node.is_floating_point()) {
          v.f = node.as_floating_point()->get();
        } else if (node.is_integer()) {
          v.f = static_cast<double>(node.as_integer()->get());
        } else {
          return wrong_type();
        }
        if (!std::isfinite(v.f)) return error(name, at, "must be a finite number, got " + format_number(v.f, false));
        if (!(v.f >= k.float_min && v.f <= k.float_max))
          return error(name, at, "must be in " + allowed_text(k) + ", got " + format_number(v.f, false));
        break;
      case Kind::kString:
        if (!node.is_string()) return wrong_type();
        v.s = node.as_string()->get();
        if (v.s.find('\0') != std::string::npos) return error(name, at, "must not contain a NUL character");
        if (k.check) {
          const std::string why = k.check(v.s);
          if (!why.empty()) return error(name, at, why + ", got " + quoted(v.s));
        }
        break;
      case Kind::kEnum: {
        if (!node.is_string()) return wrong_type();
        const std::string& s = node.as_string()->get();
        const auto it = std::find(k.names.begin(), k.names.end(), s);
        if (it == k.names.end()) return error(name, at, "must be one of " + join(k.names, ", ") + ", got " + quoted(s));
        v.i = static_cast<std::int64_t>(it - k.names.begin());
        break;
      }
    }
    k.set(c, v);
  }

  std::string file_;
  std::vector<ConfigError> errors_;
  std::map<std::string, int> lines_;  // key -> line where the file sets it
};

// Rules between keys, once every key is read. Reports the first broken one at the line of the key
// it names (or of the other key, when the first keeps its default).
// vo.preset: the preset's settings for the camera the keys give; the vo.* keys the file sets win.
void apply_vo_preset(const Reader& r, DaemonConfig& c) {
  if (c.vo_preset == VoPreset::kBench) return;
  const vo::VoConfig keyed = c.vo;
  const vision::StereoCamera& k = keyed.camera;
  const bool kitti = c.vo_preset == VoPreset::kKitti;
  c.vo = kitti ? pipeline::kitti_vo_config(keyed.max_width, keyed.max_height, k.focal_px, k.cu_px, k.cv_px, k.baseline_m)
               : pipeline::euroc_vo_config(keyed.max_width, keyed.max_height, k.focal_px, k.cu_px, k.cv_px, k.baseline_m);
  c.vo_prior = kitti ? pipeline::kitti_vo_prior() : pipeline::euroc_vo_prior();
  if (r.line("vo.max_corners") > 0) c.vo.max_corners = keyed.max_corners;
  if (r.line("vo.vme") > 0) c.vo.mode = keyed.mode;
  if (r.line("vo.attitude_filter") > 0) c.vo.estimate_attitude_bias = keyed.estimate_attitude_bias;
  if (r.line("vo.max_step_m") > 0) c.vo.max_step_m = keyed.max_step_m;
}

void check_across_keys(Reader& r, DaemonConfig& c) {
  const auto at = [&r](const char* key, const char* other) { return r.line(key) > 0 ? r.line(key) : r.line(other); };
  apply_vo_preset(r, c);
  sonar::TileBuilderConfig& tiles = c.tiles.tiles;
  if (tiles.tile_length_m > 0.0) {
    if (tiles.tile_stride_m > tiles.tile_length_m) {
      return r.error("route.tile_stride_m", at("route.tile_stride_m", "route.tile_length_m"),
                     "must be <= route.tile_length_m (" + format_number(tiles.tile_length_m, false) + "), got " +
                         format_number(tiles.tile_stride_m, false));
    }
    // A tile length of its own: the ring and the keypoint budget follow it unless given too.
    const double swath_m = 2.0 * c.tiles.corrector.ground_bins_per_side * static_cast<double>(c.tiles.corrector.ground_bin_m);
    if (r.line("route.scanlines_per_tile") == 0)
      tiles.scanlines_per_tile = static_cast<int>(std::min(4000.0, std::ceil(tiles.tile_length_m / pipeline::kMinPingSpacingM) + 2.0));
    if (r.line("route.max_keypoints") == 0)
      c.tiles.features.max_keypoints = pipeline::keypoint_budget(tiles.tile_length_m, swath_m, tiles.resolution_m * c.tiles.features.downsample);
    if (r.line("route.scanline_stride") == 0) tiles.scanline_stride = tiles.scanlines_per_tile;  // unused by distance
  } else if (r.line("route.scanlines_per_tile") == 0) {
    return r.error("route.tile_length_m", r.line("route.tile_length_m"),
                   "0 frames tiles by ping count: give route.scanlines_per_tile (and route.scanline_stride) with it");
  } else if (r.line("route.scanline_stride") == 0) {
    tiles.scanline_stride = std::max(1, 2 * tiles.scanlines_per_tile / 3);  // by ping count, a node every 2/3 of a tile
  }
  if (tiles.scanline_stride > tiles.scanlines_per_tile) {
    return r.error("route.scanline_stride", at("route.scanline_stride", "route.scanlines_per_tile"),
                   "must be <= route.scanlines_per_tile (" + std::to_string(tiles.scanlines_per_tile) +
                       "), got " + std::to_string(tiles.scanline_stride));
  }
  if (c.localiser.filter.searching_registrations < c.localiser.filter.belief_registrations) {
    return r.error("route.searching_registrations", at("route.searching_registrations", "route.belief_registrations"),
                   "must be >= route.belief_registrations (" + std::to_string(c.localiser.filter.belief_registrations) +
                       "), got " + std::to_string(c.localiser.filter.searching_registrations));
  }
  if (c.mavlink_enabled && c.mavlink_udp_remote.empty() && c.mavlink_udp_listen_port == 0 && c.mavlink_serial_device.empty()) {
    return r.error("mavlink.enabled", at("mavlink.enabled", "mavlink.udp_remote"),
                   "needs a link: mavlink.udp_remote, mavlink.udp_listen_port or mavlink.serial_device");
  }
  {
    const bool lat = r.line("mavlink.origin_lat_deg") > 0, lon = r.line("mavlink.origin_lon_deg") > 0, alt = r.line("mavlink.origin_alt_m") > 0;
    if (lat != lon || (alt && !lat)) {
      return r.error(lat ? "mavlink.origin_lon_deg" : "mavlink.origin_lat_deg",
                     at(lat ? "mavlink.origin_lat_deg" : "mavlink.origin_lon_deg", "mavlink.origin_alt_m"),
                     "the origin needs both mavlink.origin_lat_deg and mavlink.origin_lon_deg (origin_alt_m optional), or none of the three");
    }
    c.mavlink_origin = lat && lon;
  }
  if (c.backend == Backend::kSim && c.sim_mission.empty()) {
    return r.error("sim.pass", at("daemon.backend", "sim.pass"),
                   "daemon.backend = \"sim\" needs at least one [[sim.pass]] (the simulated mission)");
  }
  if (c.backend == Backend::kSim && c.sim_fault != "none" &&
      static_cast<std::size_t>(c.sim_fault_pass) >= c.sim_mission.size()) {
    return r.error("sim.fault_pass", at("sim.fault_pass", "sim.fault"),
                   "must be < the number of [[sim.pass]] (" + std::to_string(c.sim_mission.size()) + "), got " +
                       std::to_string(c.sim_fault_pass));
  }
  if (c.backend == Backend::kSim && c.sim_stall != "none" &&
      static_cast<std::size_t>(c.sim_stall_pass) >= c.sim_mission.size()) {
    return r.error("sim.stall_pass", at("sim.stall_pass", "sim.stall"),
                   "must be < the number of [[sim.pass]] (" + std::to_string(c.sim_mission.size()) + "), got " +
                       std::to_string(c.sim_stall_pass));
  }
  if (c.backend == Backend::kSim && !c.sim_can_interface.empty() && (c.sim_fault == "can_error_frames" || c.sim_fault == "can_bus_off")) {
    return r.error("sim.fault", at("sim.fault", "sim.can_interface"),
                   "puts error frames on the in-process bus; user space cannot send them on a SocketCAN interface: not with "
                   "sim.can_interface = \"" + c.sim_can_interface + "\"");
  }
  if (c.sim_replay_stride > c.sim_replay_lines) {
    return r.error("sim.replay_stride", at("sim.replay_stride", "sim.replay_lines"),
                   "must be <= sim.replay_lines (" + std::to_string(c.sim_replay_lines) + "), got " + std::to_string(c.sim_replay_stride));
  }
  for (std::size_t i = 0; i < c.sim_mission.size(); ++i) {
    const SimPass& p = c.sim_mission[i];
    const std::string pk = "sim.pass[" + std::to_string(i) + "].";  // the keys as the reader names them
    const auto pass_at = [&](const char* key, const char* other) { return at((pk + key).c_str(), (pk + other).c_str()); };
    if (p.last_ping >= 0 && p.last_ping <= p.first_ping) {
      return r.error(pk + "last_ping", pass_at("last_ping", "first_ping"),
                     "must be -1 or > first_ping (" + std::to_string(p.first_ping) + "), got " + std::to_string(p.last_ping));
    }
    if (c.backend != Backend::kSim) continue;  // the mission is the sim backend's
    if (!p.images.empty() && p.mode != drivers::qnavcan::Mode::kVo && p.mode != drivers::qnavcan::Mode::kMap)
      return r.error(pk + "images", pass_at("images", "mode"),
                     "a stereo sequence is replayed in a pass with mode = \"vo\", a folder of downward frames with mode = \"map\"");
    if (p.mode == drivers::qnavcan::Mode::kMap && (!p.file.empty() || !p.candump.empty() || !p.dvl_log.empty()))
      return r.error(pk + "images", pass_at("file", "candump"), "a map pass replays its downward frames only (no file, candump or dvl_log)");
    if (p.mode == drivers::qnavcan::Mode::kVo && p.images.empty() && (!p.candump.empty() || !p.dvl_log.empty()))
      return r.error(pk + "images", pass_at("candump", "dvl_log"),
                     "a vo pass replays recorded sensor logs with its recorded stereo sequence (sim.pass.images), not with the simulated rover");
    if (p.closed_loop) {
      if (p.mode != drivers::qnavcan::Mode::kRepeat || !p.file.empty() || !p.candump.empty() || !p.dvl_log.empty())
        return r.error(pk + "closed_loop", pass_at("closed_loop", "mode"),
                       "a closed-loop pass is a simulated repeat (mode = \"repeat\", no file, candump or dvl_log)");
      bool taught = false;
      for (std::size_t k = 0; k < i; ++k)
        taught |= c.sim_mission[k].mode == drivers::qnavcan::Mode::kTeach && c.sim_mission[k].file.empty() &&
                  c.sim_mission[k].candump.empty() && c.sim_mission[k].dvl_log.empty();
      if (!taught)
        return r.error(pk + "closed_loop", pass_at("closed_loop", "mode"),
                       "a closed-loop pass needs a simulated teach pass before it (its autopilot logs the taught track there)");
    }
    if (p.mode == drivers::qnavcan::Mode::kVo && !p.file.empty())
      return r.error(pk + "file", pass_at("file", "mode"), "a side-scan file is replayed in a teach, repeat or hold pass, not in mode = \"vo\"");
  }
  if (!c.vo_enabled) {
    for (const SimPass& p : c.sim_mission)
      if (p.mode == drivers::qnavcan::Mode::kVo)
        return r.error("vo.enabled", at("vo.enabled", "sim.pass.mode"), "a [[sim.pass]] with mode = \"vo\" needs vo.enabled = true");
  }
  if (!c.map_enabled) {
    for (const SimPass& p : c.sim_mission)
      if (p.mode == drivers::qnavcan::Mode::kMap)
        return r.error("map.enabled", at("map.enabled", "sim.pass.mode"), "a [[sim.pass]] with mode = \"map\" needs map.enabled = true");
  }
  if (c.backend == Backend::kSim && !c.map_device.empty()) {
    return r.error("map.device", at("map.device", "daemon.backend"),
                   "daemon.backend = \"sim\" flies the simulated downward camera ([[sim.pass]] mode = \"map\"): map.device must be \"\"");
  }
  if (c.map_cu_px >= c.map_width || c.map_cv_px >= c.map_height) {
    return r.error("map.cu_px", at("map.cu_px", "map.width"), "the principal point must lie inside the map.width x map.height image");
  }
  if (c.backend == Backend::kLinux && c.vo_enabled && c.vo_camera == CameraSource::kSim) {
    return r.error("vo.camera", at("vo.camera", "daemon.backend"),
                   "daemon.backend = \"linux\" has no simulated camera: vo.camera = \"v4l2\", or vo.enabled = false");
  }
  if (c.backend == Backend::kSim && c.vo_camera != CameraSource::kSim) {
    return r.error("vo.camera", at("vo.camera", "daemon.backend"), "daemon.backend = \"sim\" reads the simulated camera: vo.camera must be \"sim\"");
  }
  if (c.vo.camera.cu_px >= c.vo.max_width || c.vo.camera.cv_px >= c.vo.max_height) {
    return r.error("vo.cu_px", at("vo.cu_px", "vo.width"),
                   "the principal point must lie inside the vo.width x vo.height image");
  }
  // Derived: the localiser's node window holds every node registered in one update (RouteLocaliser::init).
  c.localiser.window_slots =
      std::max<std::size_t>(c.localiser.window_slots, c.localiser.filter.max_registrations() + 1u);
}

}  // namespace

Pose3 vo_body_T_cam(const DaemonConfig& c) noexcept {
  // Body FRD; camera x right, y down, z along the optical axis (forward, tilted down).
  const double a = deg_to_rad(c.vo_tilt_down_deg);
  const Vec3d z(std::cos(a), 0.0, std::sin(a));
  const Vec3d x(0.0, 1.0, 0.0);
  Pose3 p;
  p.R.col(0) = x;
  p.R.col(1) = z.cross(x);
  p.R.col(2) = z;
  p.t = Vec3d(0.0, 0.0, -c.vo_mount_height_m);
  return p;
}

bool map_runs(const DaemonConfig& c) noexcept { return c.map_enabled && (c.backend == Backend::kSim || !c.map_device.empty()); }

std::size_t frame_pool_slots(const DaemonConfig& c) noexcept {
  return std::max(c.vo_enabled ? c.vo_frame_queue : 0, map_runs(c) ? c.map_frame_queue : 0);
}

std::size_t frame_slot_bytes(const DaemonConfig& c) noexcept {
  const std::size_t pair = c.vo_enabled ? 2 * static_cast<std::size_t>(c.vo.max_width) * static_cast<std::size_t>(c.vo.max_height) : 0;
  const std::size_t down = map_runs(c) ? static_cast<std::size_t>(c.map_width) * static_cast<std::size_t>(c.map_height) : 0;
  return std::max(pair, down);
}

pipeline::TopoMapperConfig map_mapper_config(const DaemonConfig& c) noexcept {
  const bool have_camera = c.map_focal_px > 0.0;
  const vision::PinholeRadTan k = vision::ideal_pinhole(c.map_focal_px, c.map_cu_px, c.map_cv_px, c.map_width, c.map_height);
  const bool metric = have_camera && c.map_altitude_m > 0.0;
  pipeline::TopoMapperConfig m = pipeline::topo_mapper_config(c.map_width, c.map_height, have_camera, k, false, true, metric,
                                                              c.map_node_spacing > 0.0 ? c.map_node_spacing : std::nan(""), c.map_max_nodes);
  if (!have_camera) {  // the principal point alone (no focal length): where the chain's pose is measured from
    m.chain.camera.cx = c.map_cu_px;
    m.chain.camera.cy = c.map_cv_px;
  }
  return m;
}

std::string ConfigError::to_string() const {
  std::string s = file;
  if (line > 0) s += ":" + std::to_string(line);
  s += ": ";
  if (!key.empty()) s += key + ": ";
  return s + message;
}

bool parse_config(const std::string& text, const char* name, DaemonConfig& out, ConfigError& err) {
  out = DaemonConfig{};
  Reader reader(name);
  // toml++ 3.3.0's whitespace tables reach __builtin_unreachable for many non-ASCII code points
  // (U+00E9, U+3042, U+FEFB ...: undefined behaviour; found by test/fuzz fuzz_config, inputs in
  // test/fuzz/regressions/config/). The configuration is ASCII text: a non-ASCII byte is refused
  // with its line before toml++ sees the text.
  int line = 1;
  for (const char ch : text) {
    if (ch == '\n') ++line;
    if (static_cast<unsigned char>(ch) >= 0x80) {
      reader.error("", line, "non-ASCII character (the configuration is ASCII text)");
      err = reader.first_error();
      return false;
    }
  }
  toml::table root;
  try {
    root = toml::parse(text, std::string_view(name ? name : ""));
  } catch (const toml::parse_error& e) {
    reader.error("", line_of(e.source()), std::string(e.description()));
    err = reader.first_error();
    return false;
  }
  DaemonConfig c;
  reader.read_root(root, c);
  if (!reader.failed()) check_across_keys(reader, c);
  if (reader.failed()) {
    err = reader.first_error();
    return false;
  }
  out = std::move(c);
  return true;
}

bool load_config(const char* path, DaemonConfig& out, ConfigError& err) {
  out = DaemonConfig{};
  err = ConfigError{};
  err.file = path ? path : "";
  std::FILE* f = path ? std::fopen(path, "rb") : nullptr;
  if (f == nullptr) {
    err.message = std::string("cannot open: ") + std::strerror(path ? errno : EINVAL);
    return false;
  }
  std::string text;
  char buf[4096];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, n);
  const bool read_failed = std::ferror(f) != 0;
  const int read_errno = errno;
  std::fclose(f);
  if (read_failed) {
    err.message = std::string("cannot read: ") + std::strerror(read_errno);
    return false;
  }
  return parse_config(text, path, out, err);
}

std::string config_keys_markdown() {
  const DaemonConfig defaults;
  std::ostringstream md;
  md << "| key | type | default | unit | allowed | meaning |\n";
  md << "|---|---|---|---|---|---|\n";
  for (const KeySpec& k : key_table()) {
    const std::string def = k.required ? "(required)" : "`" + value_text(k, k.get(defaults)) + "`";
    md << "| `" << k.name << "` | " << (k.aliases.empty() ? type_name(k.kind) : "float or string") << " | " << def << " | " << k.unit << " | " << allowed_text(k)
       << " | " << k.meaning << " |\n";
  }
  return md.str();
}

}  // namespace qnav::daemon
