// qnav can: qnav's CAN interface from the command line.
//   qnav can decode LOG [--node N] [--all]  decode a candump log (candump -l, or candump's screen output):
//                                    qnav messages (docs/qnav.dbc)
//                                    and DroneCAN AHRS Solution/RawIMU; prints counters at the end
//   qnav can listen IFACE [--seconds S] [--node N]
//                                    the same, live from a SocketCAN interface (can0, vcan0)
//   qnav can dbc FILE                read a DBC file and check every signal against qnav's codec
//   qnav can simulate OUT [--seconds S] [--faults]
//                                    write a candump log of an AHRS (qnav ATTITUDE_IN + DroneCAN
//                                    Solution at 20 Hz, node 42); --faults adds corrupted frames
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "drivers/dronecan/ahrs_receiver.hpp"
#include "drivers/qnavcan/dbc.hpp"
#include "drivers/qnavcan/messages.hpp"
#include "drivers/qnavcan/receiver.hpp"
#include "firmware/cli/cli_app.hpp"
#include "firmware/qnav/command.hpp"
#include "firmware/tools/text_file.hpp"
#include "hal/core/candump.hpp"
#include "hal/linux/monotonic_clock.hpp"
#include "hal/linux/socketcan_bus.hpp"
#include "hal/sim/can_log_replay.hpp"

namespace {
using namespace qnav;
namespace qc = qnav::drivers::qnavcan;
namespace dc = qnav::drivers::dronecan;

// candump logs and DBC files are text, read whole and bounded.
constexpr std::size_t kMaxLogBytes = std::size_t{256} << 20;
constexpr std::size_t kMaxDbcBytes = std::size_t{4} << 20;

template <typename C>
void print_counters(const char* what, const C& c) {
  std::printf("%s:", what);
  for (std::size_t i = 0; i < c.size(); ++i) std::printf(" %s=%u", c.name_at(i), c.count_at(i));
  std::printf("\n");
}

// Decodes frames from any CanBus (a log replay or a live socket) and prints what it understood.
struct Decoder {
  explicit Decoder(std::uint8_t node) : drx(node) {}
  qc::QnavCanReceiver qrx;
  dc::DroneCanAhrsReceiver drx;
  unsigned frames = 0, printed = 0, solutions = 0;
  unsigned max_print = 20;

  void on_frame(const hal::CanRxFrame& f) {
    ++frames;
    const double t_s = static_cast<double>(f.stamp.sample_ns) * 1e-9;
    if (f.frame.extended) {
      if (drx.on_frame(f) == dc::AhrsUpdate::kSolution) {
        ++solutions;
        const dc::AhrsSolution& s = drx.solution().value;
        const double x = static_cast<double>(s.orientation_xyzw[0]), y = static_cast<double>(s.orientation_xyzw[1]),
                     z = static_cast<double>(s.orientation_xyzw[2]), w = static_cast<double>(s.orientation_xyzw[3]);
        const double roll = std::atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y));
        const double pitch = std::asin(std::fmax(-1.0, std::fmin(1.0, 2 * (w * y - z * x))));
        const double yaw = std::atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z));
        if (printed++ < max_print)
          std::printf("%10.6f dronecan node %u Solution roll %.4f pitch %.4f yaw %.4f rad, gz %.3f rad/s\n", t_s,
                      drx.solution().source_node, roll, pitch, yaw, static_cast<double>(s.angular_velocity_radps[2]));
      }
      return;
    }
    const Status s = qrx.on_frame(f);
    const qc::MessageDef* def = nullptr;
    double values[qc::kMaxSignalsPerMessage];
    const Status g = printed < max_print ? qc::decode_generic(f.frame, def, values, qc::kMaxSignalsPerMessage) : Status(StatusCode::kEmpty, "");
    if (def != nullptr && (g.is_ok() || g == StatusCode::kOutOfRange)) {  // out of range: values decoded, shown
      ++printed;
      std::printf("%10.6f %s", t_s, def->name);
      for (std::size_t i = 0; i < def->signals.size(); ++i) std::printf(" %s=%.10g%s", def->signals[i].name, values[i], def->signals[i].unit);
      std::printf("%s\n", s.is_ok() ? "" : (std::string("  [rejected: ") + s.message() + "]").c_str());
    }
  }
  void summary(unsigned bad_lines) const {
    if (printed >= max_print) std::printf("... (first %u decoded lines shown)\n", max_print);
    std::printf("frames %u, bad log lines %u, qnav inputs accepted %u, DroneCAN solutions %u, raw IMU %u\n", frames, bad_lines,
                qrx.accepted(), solutions, drx.raw_imus());
    print_counters("qnav rx counters", qrx.counters());
    print_counters("dronecan transport counters", drx.reassembler().counters());
    print_counters("dronecan ahrs counters", drx.counters());
  }
};

// Every can option (one invocation per process), declared in setup_can below.
struct CanOptions {
  std::string path;
  long node = 0;
  bool all = false, faults = false;
  double listen_s = 5.0, simulate_s = 2.0;
};
CanOptions g_opt;

// "" when the input can be read; otherwise printed with the reason, and the caller returns 1.
bool input_ok(const char* path) {
  const std::string e = qnav::cli::input_file_problem(path);
  if (e.empty()) return true;
  std::fprintf(stderr, "qnav can: %s\n", e.c_str());
  return false;
}

int decode() {
  const char* path = g_opt.path.c_str();
  const long node = g_opt.node;
  if (!input_ok(path)) return 1;
  std::string text;
  const Status rs = tools::read_text_file(path, kMaxLogBytes, text);
  if (!rs.is_ok()) {
    std::fprintf(stderr, "qnav can: %s\n", rs.message());
    return 1;
  }
  hal::CanLogReplay replay(text.data(), text.size(), 0);
  auto d = std::make_unique<Decoder>(static_cast<std::uint8_t>(node));
  if (g_opt.all) d->max_print = ~0u;
  hal::CanRxFrame f;
  // To the end of the log: a run of bad lines makes receive() pause (kTimeout), never stop the read.
  while (!replay.finished()) {
    if (replay.receive(f, 0).is_ok()) d->on_frame(f);
  }
  d->summary(replay.bad_lines());
  if (d->frames == 0) {
    std::fprintf(stderr,
                 "qnav can: %s: no CAN frame in the log: %u line(s), none a candump frame (candump -l `(time) can0 123#1122`, or "
                 "candump's screen format `  can0  123   [2]  11 22`; the first bad line is %u)\n",
                 path, replay.bad_lines(), replay.first_bad_line());
    return 1;
  }
  if (replay.bad_lines() > 0) {
    std::fprintf(stderr, "qnav can: %s: %u line(s) did not parse (first: line %u); the rest was decoded\n", path,
                 replay.bad_lines(), replay.first_bad_line());
    return 1;
  }
  return 0;
}

// Live: a SocketCAN interface (can0, vcan0) for --seconds, all frames, error frames subscribed.
int listen_live() {
  const char* iface = g_opt.path.c_str();
  const long node = g_opt.node;
  const double seconds = g_opt.listen_s;
  hal::SocketCanBus bus;
  hal::SocketCanConfig cfg;
  cfg.interface = iface;
  errno = 0;
  const Status st = bus.open(cfg);
  if (!st.is_ok()) {
    const int e = errno;
    const char* hint = "";
    if (std::strstr(st.message(), "socket(PF_CAN)") != nullptr)
      hint = " (the kernel has no SocketCAN: load the can-raw / vcan modules: modprobe can-raw; modprobe vcan)";
    else if (e == ENODEV || e == ENXIO)
      hint = " (no such CAN interface: `ip link` lists them; a virtual one: ip link add dev vcan0 type vcan && ip link set up vcan0)";
    else if (e == EPERM || e == EACCES)
      hint = " (permission denied: run as root or with CAP_NET_RAW)";
    else if (e == ENETDOWN)
      hint = " (the interface is down: ip link set up IFACE)";
    std::fprintf(stderr, "qnav can: %s: %s%s%s%s\n", iface, st.message(), e != 0 ? ": " : "", e != 0 ? std::strerror(e) : "", hint);
    return 1;
  }
  auto d = std::make_unique<Decoder>(static_cast<std::uint8_t>(node));
  const std::int64_t end = hal::monotonic_now_ns() + static_cast<std::int64_t>(seconds * 1e9);
  hal::CanRxFrame f;
  while (hal::monotonic_now_ns() < end) {
    const Status r = bus.receive(f, 100);
    if (r.is_ok()) d->on_frame(f);
    else if (r != StatusCode::kTimeout) {
      std::fprintf(stderr, "qnav can: %s: %s\n", iface, r.message());
      return 1;
    }
  }
  d->summary(0);
  const hal::CanBusStats bs = bus.stats();
  std::printf("socket: rx %u, kernel drops %u, error frames %u, bus-off %u\n", bs.rx_frames, bs.rx_dropped, bs.error_frames, bs.bus_off);
  return 0;
}

int dbc() {
  const char* path = g_opt.path.c_str();
  if (!input_ok(path)) return 1;
  std::string text;
  const Status rs = tools::read_text_file(path, kMaxDbcBytes, text);
  if (!rs.is_ok()) {
    std::fprintf(stderr, "qnav can: %s\n", rs.message());
    return 1;
  }
  auto file = std::make_unique<qc::DbcFile>();
  const Status s = qc::parse_dbc(text.data(), text.size(), *file);
  if (!s.is_ok()) {
    std::fprintf(stderr, "qnav can: %s: line %zu: %s\n", path, file->error_line, s.message());
    return 1;
  }
  if (file->messages.empty()) {
    std::fprintf(stderr, "qnav can: %s: no message (BO_) in the DBC file\n", path);
    return 1;
  }
  int mismatches = 0, signals = 0;
  for (const qc::DbcMessage& m : file->messages) {
    const qc::MessageDef* c = qc::find_message(m.id);
    char period[24];
    if (m.cycle_ms > 0) std::snprintf(period, sizeof period, "every %u ms", m.cycle_ms);
    else std::snprintf(period, sizeof period, "on event");
    std::printf("0x%03X %-20s dlc %u  %2zu signals  %-13s from %s%s\n", m.id, m.name, m.dlc, m.signals.size(), period,
                m.transmitter, c ? "" : "   [not in codec]");
    if (c == nullptr || c->signals.size() != m.signals.size() || c->dlc != m.dlc) {
      ++mismatches;
      continue;
    }
    for (std::size_t i = 0; i < m.signals.size(); ++i) {
      const qc::DbcSignal& d = m.signals[i];
      const qc::SignalDef& k = c->signals[i];
      ++signals;
      if (std::strcmp(d.name, k.name) != 0 || d.start_bit != k.start_bit || d.length != k.length || d.big_endian != k.big_endian ||
          d.is_signed != k.is_signed || d.factor != k.factor || d.offset != k.offset || d.min != k.min || d.max != k.max) {
        std::printf("   signal %s differs from the codec\n", d.name);
        ++mismatches;
      }
    }
  }
  std::printf("%zu messages, %d signals, %d mismatches with the codec\n", file->messages.size(), signals, mismatches);
  if (mismatches != 0) {
    std::fprintf(stderr, "qnav can: %s: %d mismatches with the codec (listed above)\n", path, mismatches);
    return 1;
  }
  return 0;
}

int simulate() {
  const char* out = g_opt.path.c_str();
  const double seconds = g_opt.simulate_s;
  const bool faults = g_opt.faults;
  FILE* f = qnav::cli::open_output("qnav can", out);
  if (f == nullptr) return 1;
  const std::int64_t t0_us = 1700000000000000LL;
  const int steps = static_cast<int>(seconds * 20);
  char line[hal::kMaxCanLogLine];
  unsigned written = 0;
  auto emit = [&](const hal::CanFrame& fr, std::int64_t t_us) {
    hal::CanLogRecord r;
    r.frame = fr;
    r.has_time = true;
    r.time_us = t_us;
    std::strcpy(r.interface, "can0");
    if (hal::format_can_log_line(r, line, sizeof line) > 0) {
      std::fprintf(f, "%s\n", line);
      ++written;
    }
  };
  for (int i = 0; i < steps; ++i) {
    const std::int64_t t_us = t0_us + i * 50000;
    const double yaw = 0.3 * (static_cast<double>(i) * 0.05);  // 0.3 rad/s turn
    qc::AttitudeIn a{0.02 * std::sin(i * 0.1), -0.01, std::fmod(yaw, 6.2831), static_cast<std::uint8_t>(i), true};
    hal::CanFrame fr;
    if (qc::encode(a, fr).is_ok()) emit(fr, t_us);
    dc::AhrsSolution s;
    s.timestamp_us = static_cast<std::uint64_t>(i) * 50000 + 1;
    s.orientation_xyzw[2] = static_cast<float>(std::sin(yaw / 2));
    s.orientation_xyzw[3] = static_cast<float>(std::cos(yaw / 2));
    s.angular_velocity_radps[2] = 0.3f;
    s.linear_accel_mps2[2] = -9.81f;
    std::uint8_t payload[dc::kSolutionMaxBytes];
    const std::size_t n = dc::encode_solution(s, true, payload, sizeof payload);
    hal::CanFrame frames[16];
    const std::size_t k = dc::split_transfer(dc::kSolutionSignature, dc::make_message_id(16, dc::kSolutionId, 42),
                                             static_cast<std::uint8_t>(i), payload, n, frames, 16);
    for (std::size_t j = 0; j < k; ++j) {
      if (faults && i % 10 == 5 && j == 2) frames[j].data[0] ^= 0x40;  // corrupted payload -> CRC error
      if (faults && i % 10 == 7 && j == 3) continue;                   // lost frame -> toggle error
      emit(frames[j], t_us + 200 + static_cast<std::int64_t>(j) * 150);
    }
    if (faults && i % 10 == 9) emit(fr, t_us + 2000);  // attitude repeated -> stale
  }
  std::fclose(f);
  std::printf("wrote %u frames (%d steps at 20 Hz%s) to %s\n", written, steps, faults ? ", with faults" : "", out);
  return 0;
}

void setup_can(CLI::App& cmd, qnav::cli::Runner& run) {
  using qnav::cli::add_flag;
  using qnav::cli::add_number;
  cmd.require_subcommand(1);
  CLI::App* d = cmd.add_subcommand("decode", "decode a candump log (candump -l, or candump's screen output): qnav messages\n"
                                             "(docs/qnav.dbc) and DroneCAN AHRS Solution/RawIMU; counters at the end;\n"
                                             "exit 1 when no line is a CAN frame or some lines did not parse");
  qnav::cli::add_positional(*d, "LOG", g_opt.path, "the candump log");
  add_number(*d, "--node", g_opt.node, "DroneCAN node id of the AHRS (0: any)", "", 0, 127);
  add_flag(*d, "--all", g_opt.all, "print every decoded frame (default: the first 20)");
  run.on(d, decode);

  CLI::App* l = cmd.add_subcommand("listen", "the same, live from a SocketCAN interface (can0, vcan0)");
  qnav::cli::add_positional(*l, "IFACE", g_opt.path, "the SocketCAN interface");
  add_number(*l, "--seconds", g_opt.listen_s, "how long to listen", "s", 0.001, 1e6);
  add_number(*l, "--node", g_opt.node, "DroneCAN node id of the AHRS (0: any)", "", 0, 127);
  run.on(l, listen_live);

  CLI::App* b = cmd.add_subcommand("dbc", "read a DBC file and check every signal against qnav's codec (exit 1 on a mismatch or no message)");
  qnav::cli::add_positional(*b, "FILE", g_opt.path, "the DBC file (docs/qnav.dbc)");
  run.on(b, dbc);

  CLI::App* m = cmd.add_subcommand("simulate", "write a candump -l log of an AHRS (qnav ATTITUDE_IN + DroneCAN Solution at 20 Hz, node 42)");
  qnav::cli::add_positional(*m, "OUT", g_opt.path, "the log to write (folders created)");
  add_number(*m, "--seconds", g_opt.simulate_s, "length of the log", "s", 0.05, 3600);
  add_flag(*m, "--faults", g_opt.faults, "add corrupted, lost and repeated frames");
  run.on(m, simulate);
}
}  // namespace

QNAV_CLI_COMMAND("can", "CAN interface: decode candump logs, check a DBC, simulate an AHRS", setup_can);
