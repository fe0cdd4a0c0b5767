// qnavd_sim_pacing: the sim backend paced against the wall clock (sim.speed), measured. It flies a
// teach pass and a repeat through the real daemon (threads, lockstep, CAN codec) at --speed (default 1,
// real time) for --minutes of wall time and prints what a person flying along needs to know:
//   - the interval between consecutive QNAV_NAV_STATUS frames as the simulated autopilot read them off
//     the bus, on the monotonic clock: p50 / p99 / max (and min) against nominal (100 ms / speed);
//   - drift: the wall time between the first and the last NAV_STATUS minus their mission time / speed;
//   - the steps the pacer took late (> 10 ms after their deadline) and the latest one;
//   - the CPU the process used (getrusage) as a share of one core over the run.
// --realtime runs the daemon as a vehicle does (daemon.realtime = true: mlockall, io and nav threads
// SCHED_FIFO); whether that took is read back from the threads (/proc/self/task, sched_getscheduler)
// near the end of the run and printed as realtime_threads (2 = io and nav both SCHED_FIFO).
// A measurement, not a test: `scripts/sim-pacing --minutes 10` runs it; docs/fly-along.md has the numbers.
//   qnavd_sim_pacing [--minutes M] [--speed S] [--realtime] [--json]
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>
#include <dirent.h>
#include <sched.h>
#include <unistd.h>

#include "drivers/qnavcan/messages.hpp"
#include "firmware/qnavd/daemon.hpp"
#include "hal/linux/monotonic_clock.hpp"
#include "hal/linux/process.hpp"

namespace {

using namespace qnav;
using namespace qnav::daemon;
namespace qc = qnav::drivers::qnavcan;

struct Record {
  std::vector<std::int64_t> wall_ns, mission_ns;  // reserved up front: the observer runs in the io thread
  std::atomic<std::size_t> n{0};
};

void on_frame(void* ctx, const hal::CanRxFrame& f) {
  if (f.frame.id != qc::kIdNavStatus) return;
  auto* r = static_cast<Record*>(ctx);
  const std::size_t i = r->n.load(std::memory_order_relaxed);
  if (i >= r->wall_ns.size()) return;
  r->wall_ns[i] = hal::monotonic_now_ns();
  r->mission_ns[i] = f.stamp.sample_ns;
  r->n.store(i + 1, std::memory_order_release);
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(std::ceil(p / 100.0 * static_cast<double>(v.size())) - 1));
  return v[k];
}

// The threads of this process running SCHED_FIFO (the daemon's io and nav threads when
// daemon.realtime took; 0 when it was off or not permitted).
int fifo_threads() {
  DIR* d = opendir("/proc/self/task");
  if (d == nullptr) return -1;
  int n = 0;
  while (const dirent* e = readdir(d)) {
    char* end = nullptr;
    const long tid = std::strtol(e->d_name, &end, 10);
    if (end == e->d_name || *end != '\0') continue;
    if (sched_getscheduler(static_cast<pid_t>(tid)) == SCHED_FIFO) ++n;
  }
  closedir(d);
  return n;
}

}  // namespace

int main(int argc, char** argv) {
  double minutes = 10.0, speed = 1.0;
  bool json = false, realtime = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    char* end = nullptr;
    if (a == "--json") {
      json = true;
    } else if (a == "--realtime") {
      realtime = true;
    } else if ((a == "--minutes" || a == "--speed") && i + 1 < argc) {
      const double v = std::strtod(argv[++i], &end);
      if (*end != '\0' || !std::isfinite(v) || v <= 0.0 || v > (a == "--speed" ? SimSpeed::kMax : 1440.0)) {
        std::fprintf(stderr, "qnavd_sim_pacing: %s must be a number in (0, %g]\n", a.c_str(), a == "--speed" ? SimSpeed::kMax : 1440.0);
        return 2;
      }
      (a == "--speed" ? speed : minutes) = v;
    } else {
      std::fprintf(stderr, "usage: qnavd_sim_pacing [--minutes M] [--speed S] [--realtime] [--json]\n");
      return 2;
    }
  }
  char dir[] = "/tmp/qnavd_pacing_XXXXXX";
  if (mkdtemp(dir) == nullptr) return 1;
  DaemonConfig c;
  c.backend = Backend::kSim;
  c.route_dir = dir;
  c.log = LogFormat::kOff;
  c.realtime = realtime;  // a vehicle runs true (mlockall, SCHED_FIFO io and nav threads)
  c.sim_speed = speed;
  // A teach pass and a repeat of a line long enough to outlast the run (~0.69 s of mission per metre
  // of pass at the survey's 1.5 m/s, handshakes included); the run stops after --minutes of wall time.
  c.sim_length_m = std::clamp(minutes * 60.0 * speed / 0.69 + 100.0, 200.0, 50000.0);
  SimPass teach, repeat;
  teach.mode = qc::Mode::kTeach;
  repeat.mode = qc::Mode::kRepeat;
  repeat.offset_pct = 10.0;
  (void)c.sim_mission.push_back(teach);
  (void)c.sim_mission.push_back(repeat);

  Record rec;
  const std::size_t cap = static_cast<std::size_t>(minutes * 60.0 * 10.0 * speed * 1.5) + 1000;
  rec.wall_ns.assign(cap, 0);
  rec.mission_ns.assign(cap, 0);
  Daemon d(c);
  d.set_bus_observer(on_frame, &rec);
  Status s = d.init(nullptr);
  if (s) s = d.start();
  if (!s) {
    std::fprintf(stderr, "qnavd_sim_pacing: start-up failed: %s\n", s.message());
    return 1;
  }
  const hal::ProcessUsage u0 = hal::process_usage();
  const std::int64_t t0 = hal::monotonic_now_ns();
  std::atomic<int> rt_threads{-1};
  std::thread stopper([&d, &rt_threads, minutes] {
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<long long>(minutes * 60000.0));
    while (std::chrono::steady_clock::now() < until && !d.mission_done()) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    rt_threads.store(fifo_threads());  // the io and nav threads are still running here
    d.stop();
  });
  const int rc = d.run();
  stopper.join();
  const double wall_s = static_cast<double>(hal::monotonic_now_ns() - t0) * 1e-9;
  const hal::ProcessUsage u1 = hal::process_usage();

  const std::size_t n = rec.n.load(std::memory_order_acquire);
  const double nominal_ms = 100.0 / speed;
  std::vector<double> iv;
  iv.reserve(n);
  for (std::size_t i = 1; i < n; ++i) iv.push_back(static_cast<double>(rec.wall_ns[i] - rec.wall_ns[i - 1]) * 1e-6);
  double drift_ms = 0.0;
  if (n >= 2)
    drift_ms = static_cast<double>(rec.wall_ns[n - 1] - rec.wall_ns[0]) * 1e-6 -
               static_cast<double>(rec.mission_ns[n - 1] - rec.mission_ns[0]) * 1e-6 / speed;
  const double p50 = percentile(iv, 50.0), p99 = percentile(iv, 99.0);
  const double mx = iv.empty() ? 0.0 : *std::max_element(iv.begin(), iv.end());
  const double mn = iv.empty() ? 0.0 : *std::min_element(iv.begin(), iv.end());
  const double cpu_pct = wall_s > 0 ? 100.0 * (u1.cpu_s - u0.cpu_s) / wall_s : 0.0;
  const IoCounters& io = d.io_counters();
  const unsigned late = io.sim_late_steps.load(), max_late_us = io.sim_max_late_us.load();
  const int rt = rt_threads.load();
  const bool rt_in_force = realtime && rt >= 2;
  if (realtime && !rt_in_force)
    std::fprintf(stderr, "qnavd_sim_pacing: --realtime asked but only %d thread(s) ran SCHED_FIFO (needs CAP_SYS_NICE)\n", rt);
  if (json) {
    std::printf(
        "{\"speed\":%g,\"realtime_requested\":%s,\"realtime_in_force\":%s,\"realtime_threads\":%d,\"wall_s\":%.1f,\"nav_status_frames\":%zu,\"nominal_ms\":%.3f,\"p50_ms\":%.3f,\"p99_ms\":%.3f,\"max_ms\":%.3f,"
        "\"min_ms\":%.3f,\"p99_error_pct\":%.2f,\"drift_ms\":%.3f,\"sim_late_steps\":%u,\"max_late_ms\":%.3f,\"cpu_pct_of_one_core\":%.2f,"
        "\"tiles\":%u,\"exit\":%d}\n",
        speed, realtime ? "true" : "false", rt_in_force ? "true" : "false", rt, wall_s, n, nominal_ms, p50, p99, mx, mn, 100.0 * (p99 - nominal_ms) / nominal_ms, drift_ms, late, max_late_us * 1e-3, cpu_pct,
        d.nav().tiles(), rc);
  } else {
    std::printf("speed                %g x real time\n", speed);
    std::printf("realtime             %s (requested %s; %d thread(s) SCHED_FIFO near the end)\n", rt_in_force ? "in force" : "off",
                realtime ? "yes" : "no", rt);
    std::printf("wall_s               %.1f\n", wall_s);
    std::printf("nav_status_frames    %zu\n", n);
    std::printf("interval_ms          nominal %.3f  p50 %.3f  p99 %.3f (%+.2f %%)  max %.3f  min %.3f\n", nominal_ms, p50, p99,
                100.0 * (p99 - nominal_ms) / nominal_ms, mx, mn);
    std::printf("drift_ms             %.3f over the run (wall - mission / speed, first to last NAV_STATUS)\n", drift_ms);
    std::printf("sim_late_steps       %u (latest %.3f ms late)\n", late, max_late_us * 1e-3);
    std::printf("cpu                  %.2f %% of one core (getrusage over the run)\n", cpu_pct);
    std::printf("tiles                %u\n", d.nav().tiles());
  }
  return rc;
}
