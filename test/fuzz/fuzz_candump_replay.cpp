// A multi-line candump log (`qnav can decode`, qnavd's recorded buses) through hal/sim CanLogReplay to
// the end of the log, every frame into the qnav receiver, the generic DBC decoder and the DroneCAN AHRS
// receiver. The replay must reach the end of the log in a bounded number of calls (bad lines make
// receive() pause, never stop).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "drivers/dronecan/ahrs.hpp"
#include "drivers/dronecan/ahrs_receiver.hpp"
#include "drivers/dronecan/transfer.hpp"
#include "drivers/qnavcan/messages.hpp"
#include "drivers/qnavcan/receiver.hpp"
#include "hal/core/candump.hpp"
#include "hal/sim/can_log_replay.hpp"
#include "test/fuzz/fuzz_support.hpp"

int qnav_fuzz_candump_replay(const std::uint8_t* data, std::size_t size) {
  using namespace qnav;
  hal::CanLogReplay replay(reinterpret_cast<const char*>(data), size, 1000);
  drivers::qnavcan::QnavCanReceiver qrx;
  drivers::dronecan::DroneCanAhrsReceiver drx;
  // Each receive() consumes at least one line (or ends): the number of calls is bounded by the lines.
  for (std::size_t calls = 0; !replay.finished(); ++calls) {
    if (calls > size + 1) __builtin_trap();
    hal::CanRxFrame f;
    if (!replay.receive(f, 0).is_ok()) continue;
    if (f.frame.extended) {
      (void)drx.on_frame(f);
      continue;
    }
    (void)qrx.on_frame(f);
    const drivers::qnavcan::MessageDef* def = nullptr;
    double v[drivers::qnavcan::kMaxSignalsPerMessage];
    (void)drivers::qnavcan::decode_generic(f.frame, def, v, drivers::qnavcan::kMaxSignalsPerMessage);
  }
  return 0;
}

static void seeds_candump_replay(qnav::fuzz::Seeds& out) {
  using namespace qnav;
  namespace qc = drivers::qnavcan;
  std::string log;
  auto line = [&](const hal::CanFrame& f, std::int64_t t_us) {
    hal::CanLogRecord r;
    r.frame = f;
    r.has_time = true;
    r.time_us = t_us;
    std::snprintf(r.interface, sizeof r.interface, "can0");
    char buf[hal::kMaxCanLogLine];
    const std::size_t n = hal::format_can_log_line(r, buf, sizeof buf);
    log.append(buf, n);
    log += '\n';
  };
  const std::int64_t t0 = 1436509052249713;
  for (int k = 0; k < 6; ++k) {
    hal::CanFrame f;
    qc::AttitudeIn a;
    a.heading_rad = 0.1 * k;
    a.valid = true;
    if (qc::encode(a, f)) line(f, t0 + 100000 * k);
    qc::DepthIn d;
    d.depth_m = 12.5;
    d.depth_valid = true;
    if (qc::encode(d, f)) line(f, t0 + 100000 * k + 5000);
  }
  hal::CanFrame m;
  qc::ModeCmd mc;
  mc.mode = qc::Mode::kRepeat;
  mc.route_id = 3;
  if (qc::encode(mc, m)) line(m, t0 + 700000);
  out.push_back(qnav::fuzz::Seed{"qnav.log", log});
  // A DroneCAN AHRS Solution as a multi-frame transfer, with a bad line and a blank one in between.
  std::string dc = "(1436509052.000000) can0 1D0A022A#0001020304050607\n\n  not a line\n";
  dc += "(1436509052.100000) can0 1D0A022A#08090A0B0C0D0E4F\n(1436509052.200000) can0 1D0A022A#10111213141516B0\n";
  out.push_back(qnav::fuzz::Seed{"dronecan.log", dc});
}
QNAV_FUZZ_TARGET(candump_replay, 300)
