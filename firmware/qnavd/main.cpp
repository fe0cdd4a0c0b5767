// qnavd: the qnav navigation daemon. See docs/qnavd.md (running it), docs/configuration.md (every
// key) and firmware/qnavd/deployment.hpp (threads, queues, stages).
//   qnavd [--config FILE]          run (default /etc/qnav/qnavd.toml)
//   qnavd --check-config FILE      validate a configuration and exit (0 valid, 1 not)
//   qnavd --print-deployment [--config FILE]   the deployment table with the configured sizes
//   qnavd --print-config-keys      every configuration key (markdown table)
//   qnavd --help | --version
// Built twice: qnavd (the flight binary: linux backend, no simulator or image library linked; a
// configuration with daemon.backend = "sim" is handed to qnavd-sim) and qnavd-sim (QNAVD_SIM_BUILD:
// the same daemon with the sim backend, firmware/qnavd/sim_backend.cpp).
#include <cstdio>
#include <string>

#include "firmware/cli/cli_app.hpp"

#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/daemon.hpp"
#include "firmware/qnavd/deployment.hpp"
#include "hal/linux/process.hpp"

#ifndef QNAV_VERSION
#define QNAV_VERSION "0.0.0"
#endif

namespace {

constexpr const char* kDefaultConfig = "/etc/qnav/qnavd.toml";

bool load(const char* path, qnav::daemon::DaemonConfig& cfg) {
  qnav::daemon::ConfigError err;
  if (!qnav::daemon::load_config(path, cfg, err)) {
    std::fprintf(stderr, "qnavd: %s\n", err.to_string().c_str());
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::string config = kDefaultConfig, check_path;
  bool print_deployment = false, print_keys = false, version = false;
  CLI::App app(
      "qnavd: the qnav navigation daemon (docs/qnavd.md; every configuration key: docs/configuration.md).\n"
      "Signals: SIGTERM/SIGINT finish or discard the route node in progress, fsync, close the route, exit 0.\n"
      "Under systemd (Type=notify) it sends READY=1, pets WatchdogSec on the nav worker's progress, STOPPING=1.\n"
      "Exit codes: 0 done, 1 configuration or start-up failed, 2 usage error (unknown option, missing value).",
      "qnavd");
  qnav::cli::configure(app);
  qnav::cli::add_text(app, "--config", config, "the configuration to run (or to print the deployment of)")->type_name("FILE");
  qnav::cli::add_text(app, "--check-config", check_path,
                      "validate FILE and exit (0 valid, 1 not): errors name the key, line and allowed range")
      ->type_name("FILE");
  qnav::cli::add_flag(app, "--print-deployment", print_deployment,
                      "print threads, queues, stage budgets (us) and static memory for --config, and exit");
  qnav::cli::add_flag(app, "--print-config-keys", print_keys,
                      "print every configuration key with type, default, unit and bounds (markdown), and exit");
  qnav::cli::add_flag(app, "--version", version, "print the version and exit");
  const int rc = qnav::cli::parse(app, argc, argv);
  if (rc >= 0) return rc;
  if (version) {
    std::printf("qnavd %s\n", QNAV_VERSION);
    return 0;
  }
  if (print_keys) {
    std::fputs(qnav::daemon::config_keys_markdown().c_str(), stdout);
    return 0;
  }
  const char* check = check_path.empty() ? nullptr : check_path.c_str();
  const char* config_path = check != nullptr ? check : config.c_str();
  qnav::daemon::DaemonConfig cfg;
  if (!load(config_path, cfg)) return 1;
  if (check) {
    std::printf("%s: valid\n", check);
    return 0;
  }
#ifndef QNAVD_SIM_BUILD
  // The flight binary links no simulator: a simulated vehicle is run by qnavd-sim, with the same
  // arguments, from this program's directory.
  if (cfg.backend == qnav::daemon::Backend::kSim) {
    const qnav::Status es = qnav::hal::exec_sibling("qnavd-sim", argv);
    std::fprintf(stderr, "qnavd: daemon.backend = \"sim\": %s\n", es.message());
    return 1;
  }
#endif
  if (print_deployment) {
    // The table the daemon builds itself from. On the sim backend a recorded pass sets the tile and
    // localiser geometry from its file at start-up: the table is then the one that start-up made.
    bool recorded = false;
    for (const qnav::daemon::SimPass& p : cfg.sim_mission) recorded |= !p.file.empty();
    if (cfg.backend == qnav::daemon::Backend::kSim && recorded) {
      qnav::daemon::Daemon d(cfg);
      const qnav::Status s = d.init(nullptr);
      if (!s) {
        std::fprintf(stderr, "qnavd: start-up failed: %s\n", s.message());
        return 1;
      }
      std::fputs(qnav::daemon::deployment_text(d.static_memory().table()).c_str(), stdout);
    } else {
      std::fputs(qnav::daemon::deployment_text(qnav::daemon::make_deployment(cfg)).c_str(), stdout);
    }
    return 0;
  }
  const qnav::Status ss = qnav::hal::StopSignals::install();
  if (!ss) {
    std::fprintf(stderr, "qnavd: %s\n", ss.message());
    return 1;
  }
  // stdout (the log, kept by journald) gets its buffer now: the first line after start must not
  // allocate one. Line buffered so every event reaches the journal as it happens.
  static char log_buffer[1 << 16];
  std::setvbuf(stdout, log_buffer, _IOLBF, sizeof log_buffer);
  qnav::daemon::Daemon daemon(cfg);
  qnav::Status s = daemon.init(stdout);
  if (s) s = daemon.start();
  if (!s) {
    std::fprintf(stderr, "qnavd: start-up failed: %s\n", s.message());
    return 1;
  }
  return daemon.run();
}
