// qnav hil: the hardware-in-the-loop bench's tools (docs/hil.md).
//   qnav hil play SCENARIO.toml   play a recorded mission into the real daemon through real devices:
//                                 JSF over TCP, DVL sentences on a pseudo-terminal, AHRS frames and
//                                 mode commands on SocketCAN (firmware/tools/hil_player.hpp).
#include <cstdio>
#include <string>

#include "firmware/cli/cli_app.hpp"
#include "firmware/qnav/command.hpp"
#include "firmware/tools/hil_player.hpp"

namespace {
using namespace qnav;

struct Options {
  std::string scenario;
} g_opt;

int play() {
  if (const std::string e = cli::input_file_problem(g_opt.scenario); !e.empty()) {
    std::fprintf(stderr, "qnav hil play: %s\n", e.c_str());
    return 1;
  }
  tools::HilScenario sc;
  std::string error;
  if (!tools::load_hil_scenario(g_opt.scenario.c_str(), sc, error)) {
    std::fprintf(stderr, "qnav hil play: %s\n", error.c_str());
    return 1;
  }
  if (!sc.played.empty()) {
    if (const std::string e = cli::make_parent_dirs(sc.played); !e.empty()) {
      std::fprintf(stderr, "qnav hil play: %s\n", e.c_str());
      return 1;
    }
  }
  tools::HilPlayStats st;
  const bool ok = tools::play_hil_scenario(sc, stdout, st, error);
  std::printf("hil play: %u pings played; sonar %u sent, %u unsent (no client, or it did not read), %u connections, %u dropped; "
              "dvl %u sentences; ahrs %u frames; %u mode commands; %u items held back by silences; %u CAN send errors\n",
              st.pings, st.sonar_sent, st.sonar_unsent, st.sonar_connections, st.sonar_drops, st.dvl_sent, st.ahrs_sent, st.mode_sent,
              st.silenced, st.can_errors);
  if (!ok) {
    std::fprintf(stderr, "qnav hil play: %s\n", error.c_str());
    return 1;
  }
  if (st.sonar_sent + st.dvl_sent + st.ahrs_sent == 0) {
    std::fprintf(stderr, "qnav hil play: nothing reached the daemon (no sonar client, no DVL sentence, no AHRS frame)\n");
    return 1;
  }
  return 0;
}

void setup_hil(CLI::App& cmd, cli::Runner& run) {
  CLI::App* p = cmd.add_subcommand("play", "play a recorded mission into the real daemon: JSF over TCP, DVL on a pseudo-terminal, "
                                           "AHRS and mode commands on SocketCAN (scenario file: docs/hil.md)");
  cli::add_positional(*p, "SCENARIO", g_opt.scenario, "the scenario file (TOML: devices, then [[pass]] tables)");
  run.on(p, play);
}

}  // namespace

QNAV_CLI_COMMAND("hil", "hardware-in-the-loop bench: play a recorded mission into qnavd through real devices", setup_hil);
