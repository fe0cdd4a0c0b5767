// qnav dvl: DVL serial protocols from the command line.
//   qnav dvl parse FILE [--pd6]      parse a capture of DVL output (Water Linked serial protocol, or
//                                    RDI PD6 with --pd6 / when the first line starts with ':'); prints
//                                    the velocities and the rejection counters
//   qnav dvl listen DEVICE [--baud B] [--pd6] [--seconds S]
//                                    live from a serial device through the termios backend
//   qnav dvl simulate OUT [--seconds S] [--faults]
//                                    write Water Linked sentences (wrz + wru at 8 Hz) with valid
//                                    checksums; --faults adds bad checksums, lock losses and stale lines
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "drivers/dvl/dvl_driver.hpp"
#include "drivers/dvl/line_assembler.hpp"
#include "drivers/dvl/pd6_parser.hpp"
#include "drivers/dvl/wl_parser.hpp"
#include "firmware/cli/cli_app.hpp"
#include "firmware/qnav/command.hpp"
#include "hal/linux/monotonic_clock.hpp"
#include "hal/linux/termios_serial.hpp"

namespace {
using namespace qnav;
using namespace qnav::drivers::dvl;

template <typename C>
void print_counters(const C& c) {
  std::printf("rejected:");
  for (std::size_t i = 0; i < c.size(); ++i) std::printf(" %s=%u", c.name_at(i), c.count_at(i));
  std::printf("\n");
}

// Every dvl option (one invocation per process), declared in setup_dvl below.
struct DvlOptions {
  std::string path;
  bool pd6 = false, faults = false;
  long baud = 115200;
  double listen_s = 5.0, simulate_s = 5.0;
};
DvlOptions g_opt;

int parse() {
  const char* path = g_opt.path.c_str();
  // A capture may be a device (a pty, /dev/ttyUSB0): only folders, missing and empty files are refused here.
  if (const std::string e = qnav::cli::input_file_problem(path); !e.empty()) {
    std::fprintf(stderr, "qnav dvl: %s\n", e.c_str());
    return 1;
  }
  FILE* f = std::fopen(path, "rb");
  if (!f) {
    std::fprintf(stderr, "qnav dvl: cannot read %s: %s\n", path, std::strerror(errno));
    return 1;
  }
  bool pd6 = g_opt.pd6;
  const int first = std::fgetc(f);
  if (first == ':') pd6 = true;
  if (first != EOF) std::ungetc(first, f);
  LineAssembler lines;
  WlParser wl;
  Pd6Parser pd;
  WlMessage msg;
  Pd6Ensemble ens;
  unsigned n_lines = 0, n_vel = 0, n_lock = 0, shown = 0;
  double sum_speed = 0;
  std::int64_t t_ns = 0;  // line index as time (a file has no arrival times): 1 ms per line
  // A capture is read to its end but never without bound (a device such as /dev/zero has no end).
  constexpr std::uint64_t kMaxCaptureBytes = std::uint64_t{64} << 20;
  std::uint64_t bytes = 0, binary = 0;  // binary: control bytes, never in a text capture
  int c;
  while ((c = std::fgetc(f)) != EOF) {
    if (++bytes > kMaxCaptureBytes) {
      std::fclose(f);
      std::fprintf(stderr, "qnav dvl: %s: larger than %llu MiB: split the capture\n", path,
                   static_cast<unsigned long long>(kMaxCaptureBytes >> 20));
      return 1;
    }
    binary += (c < 0x20 && c != '\n' && c != '\r' && c != '\t') ? 1u : 0u;
    if (!lines.push(static_cast<std::uint8_t>(c))) continue;
    ++n_lines;
    t_ns += 1000000;
    const DvlVelocity* v = nullptr;
    if (pd6) {
      auto r = pd.parse_line(lines.line(), lines.size(), t_ns, ens);
      if (r.is_ok() && r.value() == Pd6Result::kEnsemble) v = &ens.velocity;
    } else if (wl.parse_line(lines.line(), lines.size(), t_ns, msg).is_ok() && msg.kind == WlKind::kVelocity) {
      v = &msg.velocity;
    }
    if (v == nullptr) continue;
    ++n_vel;
    if (v->bottom_lock) {
      ++n_lock;
      sum_speed += std::sqrt(v->vx_mps * v->vx_mps + v->vy_mps * v->vy_mps + v->vz_mps * v->vz_mps);
    }
    if (shown++ < 10)
      std::printf("v = (%+.3f, %+.3f, %+.3f) m/s  lock %s  altitude %.2f m  fom %.3f\n", v->vx_mps, v->vy_mps, v->vz_mps,
                  v->bottom_lock ? "yes" : "no ", v->altitude_m, v->fom_mps);
  }
  std::fclose(f);
  if (shown > 10) std::printf("... (first 10 of %u velocity samples shown)\n", n_vel);
  std::printf("%s: %u lines, %u velocity samples, %u with bottom lock, mean speed %.3f m/s, over-long lines %u\n",
              pd6 ? "PD6" : "Water Linked", n_lines, n_vel, n_lock, n_lock ? sum_speed / n_lock : 0.0, lines.overlong());
  if (pd6) print_counters(pd.counters());
  else print_counters(wl.counters());
  if (n_vel == 0) {
    std::fprintf(stderr, "qnav dvl: %s: no %s velocity sentence in %u lines (rejections counted above)%s\n", path,
                 pd6 ? "PD6" : "Water Linked", n_lines,
                 binary > bytes / 100 ? ": the file is binary (a DVL capture is text, one sentence a line)"
                 : n_lines == 0 ? ": no complete line"
                 : pd6          ? ""
                                : " (an RDI PD6 capture? give --pd6)");
    return 1;
  }
  return 0;
}

// Live: a DVL on a serial device (or a pty) through TermiosSerialPort + DvlSerialDriver.
int listen_live() {
  const char* dev = g_opt.path.c_str();
  const long baud = g_opt.baud;
  const double seconds = g_opt.listen_s;
  hal::TermiosSerialPort port;
  hal::SerialConfig cfg;
  cfg.baud = static_cast<std::uint32_t>(baud);
  errno = 0;
  const Status st = port.open(dev, cfg);
  if (!st.is_ok()) {
    const int e = errno;
    const char* hint = e == EACCES  ? " (permission denied: add the user to the dialout group, or run as root)"
                       : e == ENOENT ? " (no such device: `ls /dev/tty*` lists serial ports)"
                       : e == EBUSY  ? " (the device is in use by another program)"
                                     : "";
    std::fprintf(stderr, "qnav dvl: %s: %s%s%s%s\n", dev, st.message(), e != 0 ? ": " : "", e != 0 ? std::strerror(e) : "", hint);
    return 1;
  }
  const bool pd6 = g_opt.pd6;
  DvlSerialDriver drv(port, pd6 ? DvlProtocol::kPd6 : DvlProtocol::kWaterLinked);
  const std::int64_t end = hal::monotonic_now_ns() + static_cast<std::int64_t>(seconds * 1e9);
  unsigned n = 0;
  while (hal::monotonic_now_ns() < end) {
    auto r = drv.poll(100);
    if (!r.is_ok()) {
      std::fprintf(stderr, "qnav dvl: %s: %s\n", dev, r.status().message());
      return 1;
    }
    DvlVelocity v;
    while (drv.pop(v)) {
      ++n;
      std::printf("%.6f v = (%+.3f, %+.3f, %+.3f) m/s  lock %s  altitude %.2f m  latency %.1f ms\n",
                  static_cast<double>(v.stamp.arrival_ns) * 1e-9, v.vx_mps, v.vy_mps, v.vz_mps, v.bottom_lock ? "yes" : "no ",
                  v.altitude_m, static_cast<double>(v.stamp.arrival_ns - v.stamp.sample_ns) * 1e-6);
    }
  }
  std::printf("%s: %u lines, %u velocity samples\n", dev, drv.lines(), n);
  std::printf("rejected:");
  for (std::size_t i = 0; i < static_cast<std::size_t>(DvlCounter::kCount); ++i)
    std::printf(" %s=%u", kDvlCounterNames[i], drv.counter(static_cast<DvlCounter>(i)));
  std::printf("\n");
  return 0;
}

int simulate() {
  const char* out = g_opt.path.c_str();
  const double seconds = g_opt.simulate_s;
  const bool faults = g_opt.faults;
  FILE* f = qnav::cli::open_output("qnav dvl", out);
  if (f == nullptr) return 1;
  const int steps = static_cast<int>(seconds * 8);
  const long long t0_us = 1700000000000000LL;
  char body[256], line[300];
  for (int i = 0; i < steps; ++i) {
    const long long tov = t0_us + i * 125000LL;
    const double vx = 0.5 + 0.1 * std::sin(i * 0.2), vy = 0.05 * std::cos(i * 0.2), vz = 0.01;
    const bool lock = !(faults && i % 16 == 8);
    std::snprintf(body, sizeof body, "wrz,%.3f,%.3f,%.3f,%c,%.2f,%.3f,1e-05;0;0;0;1e-05;0;0;0;1e-05,%lld,%lld,125.00,0",
                  lock ? vx : 0.0, lock ? vy : 0.0, lock ? vz : 0.0, lock ? 'y' : 'n', lock ? 3.2 + 0.1 * std::sin(i * 0.05) : -1.0,
                  lock ? 0.002 : 2.707, tov, tov + 15000);
    wl_with_checksum(body, line, sizeof line);
    if (faults && i % 16 == 3) line[6] = line[6] == '1' ? '2' : '1';  // corrupted in transit -> checksum
    std::fputs(line, f);
    for (int k = 0; k < 4; ++k) {
      std::snprintf(body, sizeof body, "wru,%d,%.3f,%.2f,-45,-98", k, lock ? vx * 0.5 : 0.0, lock ? 3.7 : -1.0);
      wl_with_checksum(body, line, sizeof line);
      std::fputs(line, f);
    }
    if (faults && i % 16 == 12) {  // the previous velocity line sent again -> stale
      std::snprintf(body, sizeof body, "wrz,%.3f,%.3f,%.3f,y,3.20,0.002,1e-05;0;0;0;1e-05;0;0;0;1e-05,%lld,%lld,125.00,0", vx, vy,
                    vz, tov, tov + 15000);
      wl_with_checksum(body, line, sizeof line);
      std::fputs(line, f);
    }
  }
  std::fclose(f);
  std::printf("wrote %d velocity reports (8 Hz, %.1f s%s) to %s\n", steps, seconds, faults ? ", with faults" : "", out);
  return 0;
}

void setup_dvl(CLI::App& cmd, qnav::cli::Runner& run) {
  using qnav::cli::add_flag;
  using qnav::cli::add_number;
  cmd.require_subcommand(1);
  CLI::App* p = cmd.add_subcommand("parse", "parse a capture of DVL output (Water Linked serial protocol, or RDI PD6); prints the\n"
                                            "velocities and the rejection counters; exit 1 when no velocity sentence is found");
  qnav::cli::add_positional(*p, "FILE", g_opt.path, "the capture (text, one sentence a line)");
  add_flag(*p, "--pd6", g_opt.pd6, "RDI PD6 (also chosen when the first line starts with ':')");
  run.on(p, parse);

  CLI::App* l = cmd.add_subcommand("listen", "live from a serial device through the termios backend");
  qnav::cli::add_positional(*l, "DEVICE", g_opt.path, "the serial device (/dev/ttyUSB0, a pty)");
  add_number(*l, "--baud", g_opt.baud, "line speed", "bit/s", 50, 4000000);
  add_flag(*l, "--pd6", g_opt.pd6, "RDI PD6 instead of the Water Linked protocol");
  add_number(*l, "--seconds", g_opt.listen_s, "how long to listen", "s", 0.001, 1e6);
  run.on(l, listen_live);

  CLI::App* m = cmd.add_subcommand("simulate", "write Water Linked sentences (wrz + wru at 8 Hz) with valid checksums");
  qnav::cli::add_positional(*m, "OUT", g_opt.path, "the capture to write (folders created)");
  add_number(*m, "--seconds", g_opt.simulate_s, "length of the capture", "s", 0.125, 3600);
  add_flag(*m, "--faults", g_opt.faults, "add bad checksums, lock losses and stale lines");
  run.on(m, simulate);
}
}  // namespace

QNAV_CLI_COMMAND("dvl", "DVL serial protocols: parse a capture (Water Linked / PD6), simulate one", setup_dvl);
