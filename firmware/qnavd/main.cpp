// qnavd: the qnav navigation daemon. See docs/qnavd.md (running it), docs/configuration.md (every
// key) and firmware/qnavd/deployment.hpp (threads, queues, stages).
//   qnavd [--config FILE]          run (default /etc/qnav/qnavd.toml)
//   qnavd --check-config FILE      validate a configuration and exit (0 valid, 1 not)
//   qnavd --print-deployment [--config FILE]   the deployment table with the configured sizes
//   qnavd --print-config-keys      every configuration key (markdown table)
//   qnavd --help | --version
#include <cstdio>
#include <cstring>

#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/daemon.hpp"
#include "firmware/qnavd/deployment.hpp"
#include "hal/linux/process.hpp"

#ifndef QNAV_VERSION
#define QNAV_VERSION "0.0.0"
#endif

namespace {

constexpr const char* kDefaultConfig = "/etc/qnav/qnavd.toml";

void usage(FILE* f) {
  std::fprintf(f,
               "usage: qnavd [--config FILE]                 run the daemon (default config %s)\n"
               "       qnavd --check-config FILE             validate FILE: errors name the key, line and allowed range\n"
               "       qnavd --print-deployment [--config F] threads, queues, stage budgets (us) and static memory for F\n"
               "       qnavd --print-config-keys             every key with type, default, unit and bounds\n"
               "       qnavd --help | --version\n"
               "Signals: SIGTERM/SIGINT finish or discard the route node in progress, fsync, close the route, exit 0.\n"
               "Under systemd (Type=notify) it sends READY=1, pets WatchdogSec on the nav worker's progress, STOPPING=1.\n",
               kDefaultConfig);
}

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
  const char* config_path = kDefaultConfig;
  const char* check = nullptr;
  bool print_deployment = false;
  for (int i = 1; i < argc; ++i) {
    const char* a = argv[i];
    if (std::strcmp(a, "--help") == 0 || std::strcmp(a, "-h") == 0) {
      usage(stdout);
      return 0;
    } else if (std::strcmp(a, "--version") == 0) {
      std::printf("qnavd %s\n", QNAV_VERSION);
      return 0;
    } else if (std::strcmp(a, "--print-config-keys") == 0) {
      std::fputs(qnav::daemon::config_keys_markdown().c_str(), stdout);
      return 0;
    } else if (std::strcmp(a, "--print-deployment") == 0) {
      print_deployment = true;
    } else if ((std::strcmp(a, "--config") == 0 || std::strcmp(a, "--check-config") == 0) && i + 1 < argc) {
      if (std::strcmp(a, "--check-config") == 0) check = argv[i + 1];
      config_path = argv[++i];
    } else {
      std::fprintf(stderr, "qnavd: unknown or incomplete option '%s' (qnavd --help)\n", a);
      return 2;
    }
  }
  qnav::daemon::DaemonConfig cfg;
  if (!load(config_path, cfg)) return 1;
  if (check) {
    std::printf("%s: valid\n", check);
    return 0;
  }
  if (print_deployment) {
    std::fputs(qnav::daemon::deployment_text(qnav::daemon::make_deployment(cfg)).c_str(), stdout);
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
