// The HIL scenario player behind `qnav hil play SCENARIO.toml` (docs/hil.md): it plays a recorded
// mission into the real daemon through real kernel devices, as the vehicle around qnavd would:
//   - the side-scan's JSF stream to the daemon's sonar TCP connection (we are the topside's data port),
//   - DVL sentences onto a pseudo-terminal behind a symlink (the daemon's [dvl] device),
//   - AHRS frames and the autopilot's QNAV_MODE_CMD onto a SocketCAN interface (vcan0 on the bench).
// A scenario is a list of passes flown in order. Each pass plays one recorded dive of aligned files
// (`qnav sonar simulate --out P.jsf --dvl-log P_dvl.txt --candump P_ahrs.log` writes one JSF ping, one
// DVL sentence and one AHRS frame per ping) at `rate_hz` pings per second: `lead_s` of hovering (the
// first ping's AHRS frame repeated, nothing else: the daemon refuses a mode without a recent heading),
// the mode command, one ping period, the pings, then Idle and `after_s` of hovering. [[pass.silence]] windows (seconds from the pass's first ping) hold one stream
// back: the DVL that goes quiet, the AHRS that goes stale, the sonar that stops. AHRS frames are sent
// with a rolling Counter (re-encoded through docs/qnav.dbc's codec), as a live AHRS would.
// Every ping played is written to `played` (CSV: pass, ping, the wall-clock time it was sent on
// candump's clock), so a verdict joins the daemon's outputs that candump recorded to the truth of
// the ping it answered. Tool code: reads whole files and allocates; never linked by the daemon.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "drivers/qnavcan/messages.hpp"
#include "hal/core/can.hpp"

namespace qnav::tools {

enum class HilStream : std::uint8_t { kSonar, kDvl, kAhrs };

struct HilSilence {
  HilStream stream = HilStream::kDvl;
  double from_s = 0.0;  // seconds from the pass's first ping
  double to_s = 0.0;
};

struct HilPass {
  std::string name;
  std::string jsf, dvl, candump;  // the recorded dive (each optional; paths relative to the scenario)
  bool send_mode = false;         // a QNAV_MODE_CMD at the start of the pass
  drivers::qnavcan::Mode mode = drivers::qnavcan::Mode::kIdle;
  std::uint16_t route = 0;
  bool reverse = false;
  double lead_s = 1.0;     // hovering before the mode command (then one ping period to the first ping)
  int pings = 0;           // play only the first N pings (0: all)
  bool idle_after = true;  // QNAV_MODE_CMD Idle after the last ping
  double after_s = 2.0;    // hovering after the pass
  std::vector<HilSilence> silences;
  // A live closed-loop pass (closed_loop = true) plays no recorded dive: the player flies the dive of
  // `qnav sonar simulate` (seed, length_m, samples, range_m; its own pass_seed) with a
  // pipeline::ClosedLoopVehicle (the drift and current of `qnav route follow --sim` for `seed`),
  // starting offset_m to starboard, steered by pipeline::RouteAutopilot on the QNAV_ROUTE_GUIDANCE /
  // STATUS frames it reads from the CAN interface; each ping rendered from the true pose and sent as
  // JSF with the vehicle's dead reckoning, the DVL and AHRS from the same. The taught track: the
  // teach dive's navigation (teach_truth, the CSV of `qnav sonar simulate --truth-csv`) and the
  // taught route's nodes (route_file, read when the pass starts). truth_csv: the true pose per ping
  // (the columns of --truth-csv); the pass ends at RouteEnd or after 1.3 x length_m.
  bool closed_loop = false;
  long long seed = 1, pass_seed = 2, samples = 512;
  double length_m = 150.0, speed_mps = 3.0, range_m = 40.0, offset_m = 0.0, start_s = 1700000600.0, guidance_age_s = 0.0;
  std::string teach_truth, route_file, truth_csv;
};

struct HilScenario {
  double rate_hz = 10.0;
  std::string can_interface;  // "" = no CAN (then no AHRS and no mode commands)
  std::string sonar_listen;   // "IPv4:port" the daemon connects to; "" = no sonar
  std::string dvl_pty;        // symlink to the DVL's pseudo-terminal; "" = no DVL
  std::string played;         // CSV of the pings played ("" = none)
  double wait_connect_s = 10.0;  // before the first pass: wait this long for the daemon's sonar connection
  std::vector<HilPass> passes;
};

// Reads and checks a scenario file (TOML). Unknown keys, wrong types and out-of-range values are
// errors naming the key and line; relative paths are made relative to the file's folder.
bool load_hil_scenario(const char* path, HilScenario& out, std::string& error);

// One pass's recorded dive, split per ping.
struct HilDive {
  std::vector<std::string> jsf_pings;  // the JSF messages of each ping (bytes)
  std::vector<std::string> dvl_lines;  // one sentence per ping, with its line end
  std::vector<hal::CanFrame> ahrs;     // one frame per ping (the candump log's frames in order)
  std::size_t pings() const;           // the pings the pass plays: the shortest non-empty stream
};
bool load_hil_dive(const HilPass& pass, HilDive& out, std::string& error);

struct HilPlayStats {
  std::uint32_t pings = 0, sonar_sent = 0, sonar_unsent = 0, dvl_sent = 0, ahrs_sent = 0, mode_sent = 0;
  std::uint32_t silenced = 0, sonar_connections = 0, sonar_drops = 0, can_errors = 0;
};

// Opens the devices and plays every pass. log gets one line per pass and event; the return is false
// (with error) when a device could not be opened or a pass could not be read.
bool play_hil_scenario(const HilScenario& sc, std::FILE* log, HilPlayStats& stats, std::string& error);

}  // namespace qnav::tools
