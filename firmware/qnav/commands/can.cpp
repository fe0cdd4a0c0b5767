// qnav can: qnav's CAN interface from the command line.
//   qnav can decode LOG [--node N] [--all]  decode a candump log (candump -l): qnav messages (docs/qnav.dbc)
//                                    and DroneCAN AHRS Solution/RawIMU; prints counters at the end
//   qnav can listen IFACE [--seconds S] [--node N]
//                                    the same, live from a SocketCAN interface (can0, vcan0)
//   qnav can dbc FILE                read a DBC file and check every signal against qnav's codec
//   qnav can simulate OUT [--seconds S] [--faults]
//                                    write a candump log of an AHRS (qnav ATTITUDE_IN + DroneCAN
//                                    Solution at 20 Hz, node 42); --faults adds corrupted frames
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
#include "firmware/qnav/args.hpp"
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

int decode(int argc, char** argv) {
  static const char* const kValued[] = {"--node", nullptr};
  const char* path = cli::positional(argc, argv, 2, 0, kValued);
  long node = 0;
  if (path == nullptr || !cli::option_long(argc, argv, "--node", node) || node < 0 || node > 127) {
    std::fprintf(stderr, "usage: qnav can decode LOG [--node N] [--all]\n");
    return 2;
  }
  std::string text;
  const Status rs = tools::read_text_file(path, kMaxLogBytes, text);
  if (!rs.is_ok()) {
    std::fprintf(stderr, "qnav can: %s\n", rs.message());
    return 1;
  }
  hal::CanLogReplay replay(text.data(), text.size(), 0);
  auto d = std::make_unique<Decoder>(static_cast<std::uint8_t>(node));
  if (cli::flag(argc, argv, "--all")) d->max_print = ~0u;
  hal::CanRxFrame f;
  // To the end of the log: a run of bad lines makes receive() pause (kTimeout), never stop the read.
  while (!replay.finished()) {
    if (replay.receive(f, 0).is_ok()) d->on_frame(f);
  }
  d->summary(replay.bad_lines());
  if (d->frames == 0) {
    std::fprintf(stderr, "qnav can: %s: no CAN frame in the log\n", path);
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
int listen_live(int argc, char** argv) {
  static const char* const kValued[] = {"--node", "--seconds", nullptr};
  const char* iface = cli::positional(argc, argv, 2, 0, kValued);
  long node = 0;
  double seconds = 5;
  if (iface == nullptr || !cli::option_long(argc, argv, "--node", node) || node < 0 || node > 127 ||
      !cli::option_double(argc, argv, "--seconds", seconds) || seconds <= 0) {
    std::fprintf(stderr, "usage: qnav can listen IFACE [--seconds S] [--node N]\n");
    return 2;
  }
  hal::SocketCanBus bus;
  hal::SocketCanConfig cfg;
  cfg.interface = iface;
  const Status st = bus.open(cfg);
  if (!st.is_ok()) {
    std::fprintf(stderr, "qnav can: %s: %s\n", iface, st.message());
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

int dbc(int argc, char** argv) {
  const char* path = cli::positional(argc, argv, 2, 0, nullptr);
  if (path == nullptr) {
    std::fprintf(stderr, "usage: qnav can dbc FILE\n");
    return 2;
  }
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

int simulate(int argc, char** argv) {
  static const char* const kValued[] = {"--seconds", nullptr};
  const char* out = cli::positional(argc, argv, 2, 0, kValued);
  double seconds = 2.0;
  if (out == nullptr || !cli::option_double(argc, argv, "--seconds", seconds) || seconds <= 0 || seconds > 3600) {
    std::fprintf(stderr, "usage: qnav can simulate OUT [--seconds S] [--faults]\n");
    return 2;
  }
  const bool faults = cli::flag(argc, argv, "--faults");
  FILE* f = std::fopen(out, "w");
  if (!f) {
    std::fprintf(stderr, "qnav can: cannot write %s\n", out);
    return 1;
  }
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

int run_can(int argc, char** argv) {
  if (argc >= 2 && std::strcmp(argv[1], "decode") == 0) return decode(argc, argv);
  if (argc >= 2 && std::strcmp(argv[1], "listen") == 0) return listen_live(argc, argv);
  if (argc >= 2 && std::strcmp(argv[1], "dbc") == 0) return dbc(argc, argv);
  if (argc >= 2 && std::strcmp(argv[1], "simulate") == 0) return simulate(argc, argv);
  std::fprintf(stderr, "usage: qnav can decode LOG [--node N] | listen IFACE [--seconds S] | dbc FILE | simulate OUT [--seconds S] [--faults]\n");
  return 2;
}
}  // namespace

QNAV_COMMAND("can", "CAN interface: decode candump logs, check a DBC, simulate an AHRS", run_can);
