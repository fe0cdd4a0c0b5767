// qnavd_soak: a long simulated mission through the real daemon (threads, queues, CAN codec, DVL
// driver, route file), compressed (the sim backend runs as fast as the pipeline takes it), with the
// allocation guard on. It prints what a vehicle engineer needs before trusting a long dive:
//   mission_hours, allocations_after_start, rss_start_kb (after the first tenth of the mission, once
//   every buffer has been touched), rss_end_kb, deadline_misses, tiles, nodes, and the accounting of
//   every input: received = processed + dropped + rejected + still queued at the end.
// --check makes violations the exit status (ctest runs a short soak with it; scripts/soak the long one):
// a heap allocation after start (where the build counts them), RSS growing more than 1 MiB, an input
// not accounted for, a software fault, or the mission not completed.
//   qnavd_soak [--hours H] [--json] [--check] [--seed N]
// Built a second time as qnavd_soak_tsan (QNAV_SOAK_TSAN): the daemon's own code under
// ThreadSanitizer (its threads, atomics and SPSC queues), without the allocation guard, whose malloc
// interposition ThreadSanitizer owns.
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "drivers/qnavcan/messages.hpp"
#include "firmware/qnavd/daemon.hpp"
#include "firmware/qnavd/software_fault.hpp"
#include "firmware/tools/route_file.hpp"
#ifndef QNAV_SOAK_TSAN
#include "test/support/alloc_guard.hpp"
#endif

namespace {

using namespace qnav;
using namespace qnav::daemon;
namespace qc = qnav::drivers::qnavcan;

// Resident set size from /proc/self/status, without touching the heap (read into a stack buffer).
long rss_kb() noexcept {
  const int fd = ::open("/proc/self/status", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return -1;
  char buf[4096];
  const ssize_t n = ::read(fd, buf, sizeof buf - 1);
  ::close(fd);
  if (n <= 0) return -1;
  buf[n] = '\0';
  const char* p = std::strstr(buf, "VmRSS:");
  return p ? std::strtol(p + 6, nullptr, 10) : -1;
}

struct Watch {
  std::int64_t mission_ns = 0;          // the planned mission length in sample time
  std::atomic<long> rss_start_kb{-1};   // taken once sample time passes a tenth of the mission
  std::atomic<std::int64_t> last_ns{0};
};

void on_frame(void* ctx, const hal::CanRxFrame& f) {
  auto* w = static_cast<Watch*>(ctx);
  w->last_ns.store(f.stamp.sample_ns, std::memory_order_relaxed);
  if (w->rss_start_kb.load(std::memory_order_relaxed) < 0 && f.stamp.sample_ns > w->mission_ns / 10) w->rss_start_kb.store(rss_kb());
}

struct Options {
  double hours = 10.0;
  bool json = false, check = false;
  long seed = 1;
};

bool parse(int argc, char** argv, Options& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    char* end = nullptr;
    if (a == "--json") o.json = true;
    else if (a == "--check") o.check = true;
    else if (a == "--hours" && i + 1 < argc) {
      o.hours = std::strtod(argv[++i], &end);
      if (*end != '\0' || !std::isfinite(o.hours) || o.hours < 0.5 || o.hours > 200.0) return false;
    } else if (a == "--seed" && i + 1 < argc) {
      o.seed = std::strtol(argv[++i], &end, 10);
      if (*end != '\0' || o.seed < 0) return false;
    } else return false;
  }
  return true;
}

// One teach pass and 15 repeats (forward and reverse, offsets across the swath), on a line long
// enough for the passes to take `hours` of vehicle time (~0.69 s of mission per metre of pass,
// turns and idle included, at the simulator's survey speed).
DaemonConfig soak_config(const std::string& dir, const Options& o) {
  DaemonConfig c;
  c.backend = Backend::kSim;
  c.route_dir = dir;
  c.log = LogFormat::kOff;
  c.realtime = false;
  c.sim_seed = static_cast<std::uint32_t>(o.seed);
  c.sim_speed = SimSpeed::kFast;
  c.tile_budget_us = 10000000;  // sanitizer builds are slow; the budgets are measured by the bench
  c.ping_budget_us = 1000000;
  const std::size_t passes = c.sim_mission.capacity();
  c.sim_length_m = std::clamp(o.hours * 3600.0 / (static_cast<double>(passes) * 0.69), 200.0, 50000.0);
  const double offsets[] = {10.0, -20.0, 30.0, -5.0, 0.0};
  SimPass teach;
  teach.mode = qc::Mode::kTeach;
  (void)c.sim_mission.push_back(teach);
  for (std::size_t i = 1; i < passes; ++i) {
    SimPass p;
    p.mode = qc::Mode::kRepeat;
    p.offset_pct = offsets[i % 5];
    p.reverse = (i % 2) == 0;
    (void)c.sim_mission.push_back(p);
  }
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parse(argc, argv, o)) {
    std::fprintf(stderr, "usage: qnavd_soak [--hours H (0.5..200, default 10)] [--json] [--check] [--seed N]\n");
    return 2;
  }
  char tmpl[] = "/tmp/qnavd_soak_XXXXXX";
  const char* dir = mkdtemp(tmpl);
  if (dir == nullptr) {
    std::perror("qnavd_soak: mkdtemp");
    return 1;
  }
  const DaemonConfig cfg = soak_config(dir, o);
  Watch watch;
  watch.mission_ns = static_cast<std::int64_t>(o.hours * 3600e9);
  Daemon d(cfg);
  d.set_bus_observer(on_frame, &watch);
  if (const Status s = d.init(nullptr); !s) {
    std::fprintf(stderr, "qnavd_soak: init: %s\n", s.message());
    return 1;
  }
  if (const Status s = d.start(); !s) {
    std::fprintf(stderr, "qnavd_soak: start: %s\n", s.message());
    return 1;
  }
  std::uint64_t allocations = 0;
  int rc = 0;
#ifdef QNAV_SOAK_TSAN
  const bool counted = false;
  rc = d.run();
#else
  const bool counted = test::malloc_counted();
  {
    test::AllocationGuard guard;
    rc = d.run();
    allocations = guard.allocations();
  }
#endif
  const long rss_end = rss_kb();
  const long rss_start = watch.rss_start_kb.load();
  const double mission_hours = static_cast<double>(d.sample_clock().now_ns()) / 3600e9;

  const IoCounters& io = d.io_counters();
  const NavWorker& nav = d.nav();
  std::uint32_t nodes = 0;
  {
    tools::RouteFileReader r;
    if (r.open((std::string(dir) + "/route_1.qroute").c_str())) nodes = r.node_count();
  }
  // Every input accounted for: what is neither processed nor dropped nor rejected is still queued,
  // and a queue holds at most its capacity.
  const long long ping_rest = static_cast<long long>(io.pings_in.load()) - nav.pings() - io.ping_overflow.load() - io.sonar_rejected.load();
  const long long dvl_rest = static_cast<long long>(io.dvl_in.load()) - static_cast<long long>(nav.inputs().dvl_samples()) - io.dvl_overflow.load();
  const long long can_rest = static_cast<long long>(io.can_rx_in.load()) - static_cast<long long>(nav.inputs().can_frames()) - io.can_rx_overflow.load();
  const bool accounted = ping_rest >= 0 && ping_rest <= static_cast<long long>(cfg.ping_queue) && dvl_rest >= 0 && dvl_rest <= static_cast<long long>(kDvlQueueCapacity) && can_rest >= 0 &&
                         can_rest <= static_cast<long long>(cfg.can_rx_queue);

  if (o.json) {
    std::printf(
        "{\"mission_hours\": %.2f, \"allocations_after_start\": %llu, \"allocations_counted\": %s, \"rss_start_kb\": %ld, "
        "\"rss_end_kb\": %ld, \"deadline_misses\": %u, \"tiles\": %u, \"nodes\": %u, \"pings_in\": %llu, \"pings_processed\": %u, "
        "\"pings_dropped\": %u, \"pings_rejected\": %u, \"pings_queued_at_end\": %lld, \"dvl_in\": %llu, \"dvl_processed\": %llu, "
        "\"dvl_dropped\": %u, \"dvl_rejected_sentences\": %u, \"can_in\": %llu, \"can_processed\": %llu, \"can_dropped\": %u, "
        "\"software_faults\": %u, \"writer_errors\": %u, \"mission_done\": %s, \"accounted\": %s}\n",
        mission_hours, static_cast<unsigned long long>(allocations), counted ? "true" : "false", rss_start, rss_end,
        nav.deadline_misses(), nav.tiles(), nodes, static_cast<unsigned long long>(io.pings_in.load()), nav.pings(),
        io.ping_overflow.load(), io.sonar_rejected.load(), ping_rest, static_cast<unsigned long long>(io.dvl_in.load()),
        static_cast<unsigned long long>(nav.inputs().dvl_samples()), io.dvl_overflow.load(), io.dvl_rejected.load(),
        static_cast<unsigned long long>(io.can_rx_in.load()), static_cast<unsigned long long>(nav.inputs().can_frames()), io.can_rx_overflow.load(),
        SoftwareFaults::count(), nav.writer_errors(), d.mission_done() ? "true" : "false", accounted ? "true" : "false");
  } else {
    std::printf("qnavd soak: %.2f mission hours, %llu heap allocations after start, RSS %ld -> %ld kB, %u deadline misses, %u tiles, "
                "%u route nodes, pings %llu in = %u processed + %u dropped + %u rejected + %lld queued\n",
                mission_hours, static_cast<unsigned long long>(allocations), rss_start, rss_end, nav.deadline_misses(), nav.tiles(), nodes,
                static_cast<unsigned long long>(io.pings_in.load()), nav.pings(), io.ping_overflow.load(), io.sonar_rejected.load(),
                ping_rest);
  }
  std::string cleanup = std::string(dir) + "/route_1.qroute";
  std::remove(cleanup.c_str());
  ::rmdir(dir);
  if (!o.check) return rc;
  int bad = rc != 0 ? 1 : 0;
  auto fail = [&bad](const char* why) {
    std::fprintf(stderr, "qnavd_soak: FAIL: %s\n", why);
    bad = 1;
  };
  if (!d.mission_done()) fail("the mission did not complete");
  if (mission_hours < 0.9 * o.hours) fail("the mission was shorter than asked");
  if (counted && allocations != 0) fail("heap allocations after start");
  if (rss_start < 0 || rss_end < 0 || rss_end - rss_start > 1024) fail("RSS grew by more than 1 MiB after the first tenth of the mission");
  if (!accounted) fail("an input is not accounted for (received != processed + dropped + rejected + queued)");
  if (SoftwareFaults::count() != 0) fail("software faults");
  if (nodes < 3) fail("the taught route has fewer than 3 nodes");
  if (nav.tiles() < 16 * nodes / 2) fail("fewer tiles than the passes should give");
  return bad;
}
