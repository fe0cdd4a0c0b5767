// Power cut while teaching (issue 19): real teaching processes are killed with SIGKILL at random,
// seeded moments, and after every kill the route on disk is checked:
//  - every node the process reported durable (it prints the index after append() returned, i.e.
//    after fdatasync) is present and decodes -- bit for bit what was taught;
//  - a torn tail is detected and reported (torn_bytes), open_append() cuts it, says so, and appending
//    continues; the result closes cleanly and reads back whole;
//  - a route closed cleanly (end mark) is told apart from a cut-off one;
//  - a replacement (qnav route train --force, a new teach of the same route id in qnavd) leaves the
//    old route intact until the new one is committed: the final name holds the old route or the
//    complete new one, never anything in between.
// kill -9 alone seldom tears a write (every byte written is in the page cache and survives the
// process; only a write stopped between pages by the signal is torn), so after every other kill the
// test also makes it a power cut before reopening: a random
// part of what was not yet reported durable is dropped, or, when nothing was, a random part of the
// node in progress is left on the medium. Two processes are killed:
//  - SyntheticTeach: route_power_cut_child, a synthetic route through the route store exactly as
//    `qnav route train` writes one (create_replacement, append + fdatasync, commit), as fast as the
//    disk allows; killed 0-50 ms after it created the route (one in eight: after it started),
//    QNAV_POWER_CUT_KILLS times (default 200);
//  - Qnavd: the real daemon teaching on its sim backend, killed at random moments of the teach pass,
//    QNAV_POWER_CUT_DAEMON_KILLS times (default 20).
// Each prints one summary line (kills, nodes reported durable, nodes recovered, torn tails seen, ...)
// for docs/reliability.md. QnavdReportsACutOffRouteItRepeats: qnavd logs route_cut_off (nodes, torn
// bytes, the partial node dropped) when told to repeat such a route, and uses its complete nodes. QNAV_POWER_CUT_SEED (default 19) seeds the kill moments.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "firmware/tools/route_file.hpp"
#include "test/integration/route_power_cut/synthetic_nodes.hpp"

namespace qnav {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

long env_long(const char* name, long def) {
  const char* v = std::getenv(name);
  return v != nullptr && *v != '\0' ? std::strtol(v, nullptr, 10) : def;
}

std::string temp_dir() {
  const char* t = std::getenv("TMPDIR");
  std::string tmpl = std::string(t ? t : "/tmp") + "/qnav_power_cut_XXXXXX";
  std::vector<char> b(tmpl.begin(), tmpl.end());
  b.push_back('\0');
  const char* d = ::mkdtemp(b.data());
  return d ? std::string(d) : std::string();
}

bool exists(const std::string& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0;
}
std::uint64_t inode(const std::string& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0 ? static_cast<std::uint64_t>(st.st_ino) : 0;
}
std::uint64_t file_size(const std::string& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0 ? static_cast<std::uint64_t>(st.st_size) : 0;
}
std::string read_all(const std::string& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}
void remove_route_files(const std::string& final_path) {
  std::remove(final_path.c_str());
  std::remove((final_path + ".new").c_str());
  for (int n = 1; n < 20; ++n) std::remove((final_path + ".new.kept." + std::to_string(n)).c_str());
}

// A child process with its stdout on a pipe, killed with SIGKILL kill_after_ms after it printed
// start_line (or after it was started when start_line is empty); kill_after_ms < 0: runs to the end.
struct RunResult {
  std::vector<std::string> lines;  // every complete line it printed before it died
  std::vector<double> line_ms;     // when each arrived, from the start
  bool killed = false;             // the SIGKILL ended it (it had not exited by itself)
  int exit_code = -1;
  double ms = 0.0;                 // from start to death
};

RunResult run_and_kill(const std::vector<std::string>& args, double kill_after_ms, const std::string& start_line, const std::string& stderr_path) {
  RunResult r;
  int fds[2];
  if (::pipe(fds) != 0) return r;
  const auto t0 = Clock::now();
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::dup2(fds[1], 1);
    const int e = ::open(stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (e >= 0) ::dup2(e, 2);
    ::close(fds[0]);
    ::close(fds[1]);
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  ::close(fds[1]);
  std::string buf;
  bool armed = start_line.empty();
  auto deadline = t0 + std::chrono::microseconds(static_cast<long>(kill_after_ms * 1000.0));
  const auto hard_stop = t0 + std::chrono::seconds(120);
  bool sent = false, eof = false;
  while (!eof) {
    int timeout_ms = 1000;
    const auto now = Clock::now();
    if (now >= hard_stop && !sent) {
      ::kill(pid, SIGKILL);
      sent = true;
    }
    if (armed && kill_after_ms >= 0 && !sent) {
      if (now >= deadline) {
        ::kill(pid, SIGKILL);
        sent = true;
      } else {
        timeout_ms = static_cast<int>(std::chrono::duration_cast<std::chrono::microseconds>(deadline - now).count() / 1000);
      }
    }
    pollfd p{fds[0], POLLIN, 0};
    const int n = ::poll(&p, 1, timeout_ms);
    if (n <= 0) continue;
    char chunk[4096];
    const ssize_t got = ::read(fds[0], chunk, sizeof chunk);
    if (got <= 0) {
      eof = true;
      break;
    }
    buf.append(chunk, static_cast<std::size_t>(got));
    std::size_t nl;
    while ((nl = buf.find('\n')) != std::string::npos) {
      r.lines.push_back(buf.substr(0, nl));
      r.line_ms.push_back(ms_since(t0));
      if (!armed && r.lines.back() == start_line) {
        armed = true;
        deadline = Clock::now() + std::chrono::microseconds(static_cast<long>(kill_after_ms * 1000.0));
      }
      buf.erase(0, nl + 1);
    }
  }
  ::close(fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  r.ms = ms_since(t0);
  r.killed = WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// Bit for bit, but for the stamp when !with_stamp (qnavd stamps tiles with the monotonic clock).
bool nodes_equal(const route::RouteNode& a, const route::RouteNode& b, bool with_stamp = true) {
  if (a.meta.index != b.meta.index || a.meta.pose.x_m != b.meta.pose.x_m || a.meta.pose.y_m != b.meta.pose.y_m ||
      static_cast<float>(a.meta.pose.heading_rad) != static_cast<float>(b.meta.pose.heading_rad) || a.meta.along_m != b.meta.along_m ||
      (with_stamp && a.meta.stamp_ns != b.meta.stamp_ns) || a.keypoints.size() != b.keypoints.size())
    return false;
  for (std::size_t k = 0; k < a.keypoints.size(); ++k) {
    const route::RouteKeypoint &p = a.keypoints[k], &q = b.keypoints[k];
    if (p.x_m != q.x_m || p.y_m != q.y_m || p.score != q.score || std::memcmp(p.descriptor, q.descriptor, route::kDescriptorBytes) != 0) return false;
  }
  return true;
}

// Every node of an open route equals the synthetic route (seed); "" or what differs.
std::string check_synthetic(tools::RouteFileReader& r, std::uint64_t seed) {
  route::RouteNode out;
  for (std::uint32_t i = 0; i < r.node_count(); ++i) {
    const Status s = r.load(i, out);
    if (!s) return "node " + std::to_string(i) + ": " + s.message();
    route::RouteNode want = test::power_cut_node(seed, i);
    if (!nodes_equal(out, want)) return "node " + std::to_string(i) + " differs from what was taught";
  }
  return "";
}

// A power cut: what was written after the last node reported durable may be lost in part, and the
// write in progress may have reached the medium in part. When the file holds bytes beyond the
// durable ones, a random part of them is dropped; otherwise a random prefix (1 byte to the whole
// record but one) of the node that was being written is left after them. Returns the bytes changed.
std::uint64_t emulate_power_cut(const std::string& path, std::uint64_t durable_end, const route::RouteParams& p, const route::RouteNode& next,
                                std::mt19937_64& rng) {
  const std::uint64_t size = file_size(path);
  if (size > durable_end) {
    const std::uint64_t keep = std::uniform_int_distribution<std::uint64_t>(durable_end, size)(rng);
    if (::truncate(path.c_str(), static_cast<off_t>(keep)) != 0) return 0;
    return size - keep;
  }
  std::vector<std::uint8_t> rec(route::record_bytes(p.max_keypoints));
  if (!route::encode_node(p, next, Span<std::uint8_t>(rec.data(), rec.size()))) return 0;
  const std::size_t part = std::uniform_int_distribution<std::size_t>(1, rec.size() - 1)(rng);
  std::ofstream f(path, std::ios::binary | std::ios::app);
  f.write(reinterpret_cast<const char*>(rec.data()), static_cast<std::streamsize>(part));
  return f ? part : 0;
}

struct Tally {
  long kills = 0, durable = 0, recovered = 0, torn = 0, torn_natural = 0, cut_off = 0, closed_not_committed = 0, committed = 0,
       before_create = 0, old_intact = 0, appended = 0, lost = 0, emulated = 0;
};

// Reopen a cut-off (not committed) route: what the reader says, then open_append, one more node,
// close. durable: nodes reported durable; planned: nodes the process meant to teach.
template <typename NodeFor, typename Check>
void check_reopen(const std::string& path, std::uint32_t durable, std::uint32_t planned, Tally& t, NodeFor node_for, Check check_nodes,
                  const std::string& where) {
  std::uint32_t count = 0;
  std::uint64_t torn = 0;
  bool closed = false;
  {
    tools::RouteFileReader r;
    const Status s = r.open(path.c_str());
    ASSERT_TRUE(s.is_ok()) << where << ": " << s.message();
    count = r.node_count();
    torn = r.torn_bytes();
    closed = r.closed_cleanly();
    const std::uint64_t rb = route::record_bytes(r.params().max_keypoints);
    ASSERT_GE(count, durable) << where << ": a node reported durable is missing";
    ASSERT_LE(count, planned) << where;
    ASSERT_EQ(file_size(path), route::kHeaderBytes + count * rb + (closed ? route::kEndMarkBytes : torn)) << where;
    if (closed) {
      ASSERT_EQ(count, planned) << where << ": closed cleanly before every node was taught";
      ASSERT_EQ(torn, 0u) << where;
      ++t.closed_not_committed;
    } else {
      ASSERT_EQ(r.end(), tools::RouteEnd::kCutOff) << where << ": a cut-off route must not read as complete";
      ++t.cut_off;
    }
    if (torn > 0) {
      ++t.torn;
      ASSERT_GT(r.counters().get(route::RouteFormatCounter::kTornTail), 0u) << where;
    }
    const std::string bad = check_nodes(r);
    ASSERT_EQ(bad, "") << where;
  }
  t.recovered += count;
  t.durable += durable;
  if (count < durable) t.lost += durable - count;
  // Teaching resumes: the torn tail (or the end mark) is cut, reported, and appending goes on.
  tools::RouteFileWriter w;
  tools::RouteAppendReport rep;
  const Status s = w.open_append(path.c_str(), &rep);
  ASSERT_TRUE(s.is_ok()) << where << ": " << s.message();
  ASSERT_EQ(rep.nodes, count) << where;
  ASSERT_EQ(rep.torn_bytes, torn) << where << ": open_append must report the torn tail it cuts";
  ASSERT_EQ(rep.end_mark_cut, closed) << where;
  ASSERT_TRUE(w.append(node_for(count)).is_ok()) << where;
  ASSERT_TRUE(w.close().is_ok()) << where;
  tools::RouteFileReader r;
  ASSERT_TRUE(r.open(path.c_str()).is_ok()) << where;
  ASSERT_TRUE(r.closed_cleanly()) << where;
  ASSERT_EQ(r.node_count(), count + 1) << where;
  ASSERT_EQ(r.torn_bytes(), 0u) << where;
  ASSERT_EQ(check_nodes(r), "") << where << " after appending";
  ++t.appended;
}

int count_prefix(const std::vector<std::string>& lines, const char* prefix) {
  int n = 0;
  for (const std::string& l : lines) n += l.rfind(prefix, 0) == 0;
  return n;
}

TEST(RoutePowerCut, SyntheticTeachKilledAtRandomMoments) {
  const long kills = env_long("QNAV_POWER_CUT_KILLS", 200);
  const std::uint64_t seed = static_cast<std::uint64_t>(env_long("QNAV_POWER_CUT_SEED", 19));
  std::mt19937_64 rng(seed);
  const std::string dir = temp_dir();
  ASSERT_FALSE(dir.empty());
  const std::string final_path = dir + "/route.qroute", err = dir + "/child.err";
  const route::RouteParams params = test::power_cut_params();
  const std::uint64_t rec = route::record_bytes(params.max_keypoints);
  const auto t_all = Clock::now();
  // Calibration: how fast this disk takes a node (append + fdatasync), to size the routes so that
  // about a third of the runs commit before their kill.
  RunResult cal = run_and_kill({QNAV_POWER_CUT_CHILD, final_path, "30", "1"}, -1.0, "", err);
  ASSERT_EQ(cal.exit_code, 0) << read_all(err);
  ASSERT_EQ(count_prefix(cal.lines, "durable "), 30);
  ASSERT_EQ(cal.lines.size(), cal.line_ms.size());
  ASSERT_GE(cal.lines.size(), 33u);  // start, created, 30 x durable, committed
  const double node_ms = std::max(0.05, (cal.line_ms[cal.lines.size() - 2] - cal.line_ms[1]) / 30.0);
  const long max_nodes = std::max(2L, std::min(400L, static_cast<long>(50.0 / node_ms * 3.0)));
  remove_route_files(final_path);
  Tally t;
  for (long k = 0; k < kills; ++k) {
    const bool replace = (k % 2) == 1;
    const std::uint64_t new_seed = 10000 + static_cast<std::uint64_t>(k), old_seed = 50000 + static_cast<std::uint64_t>(k);
    const std::string where = "kill " + std::to_string(k) + " (seed " + std::to_string(seed) + ")";
    remove_route_files(final_path);
    std::uint32_t old_nodes = 0;
    if (replace) {  // the route being replaced, complete
      old_nodes = 2 + static_cast<std::uint32_t>(rng() % 5);
      tools::RouteFileWriter w;
      tools::RouteWriterOptions o;
      o.sync_each_node = false;
      ASSERT_TRUE(w.create(final_path.c_str(), params, o).is_ok());
      for (std::uint32_t i = 0; i < old_nodes; ++i) ASSERT_TRUE(w.append(test::power_cut_node(old_seed, i)).is_ok());
      ASSERT_TRUE(w.close().is_ok());
    }
    const std::uint32_t planned = 1 + static_cast<std::uint32_t>(rng() % static_cast<std::uint64_t>(max_nodes));
    const double delay_ms = std::uniform_real_distribution<double>(0.0, 50.0)(rng);
    std::vector<std::string> args{QNAV_POWER_CUT_CHILD, final_path, std::to_string(planned), std::to_string(new_seed)};
    if (replace) args.push_back("--replace");
    // Most kills land while nodes are taught (0-50 ms after the route was created); one in eight
    // 0-50 ms after the process started (creating the route, or moving a leftover aside).
    const RunResult r = run_and_kill(args, delay_ms, k % 8 == 0 ? "start" : "created", err);
    ++t.kills;
    const bool created = count_prefix(r.lines, "created") > 0;
    const auto durable = static_cast<std::uint32_t>(count_prefix(r.lines, "durable "));
    const bool committed = count_prefix(r.lines, "committed ") > 0;
    ASSERT_TRUE(r.killed || r.exit_code == 0) << where << ": " << read_all(err);
    // The final name: the old route whole, or the complete new one; nothing in between.
    bool final_is_new = false;
    if (exists(final_path)) {
      tools::RouteFileReader f;
      ASSERT_TRUE(f.open(final_path.c_str()).is_ok()) << where;
      ASSERT_TRUE(f.closed_cleanly()) << where << ": the route under the final name is not complete";
      const bool is_old = replace && f.node_count() == old_nodes && check_synthetic(f, old_seed).empty();
      final_is_new = !is_old;
      if (is_old) {
        ++t.old_intact;
      } else {
        ASSERT_EQ(f.node_count(), planned) << where;
        ASSERT_EQ(check_synthetic(f, new_seed), "") << where;
      }
    } else {
      ASSERT_FALSE(replace) << where << ": the old route is gone";
    }
    ASSERT_TRUE(!committed || final_is_new) << where << ": committed, but the new route is not under the final name";
    if (final_is_new) {  // renamed (committed): nothing left to recover
      ++t.committed;
      t.durable += durable;
      t.recovered += planned;
      ASSERT_FALSE(exists(final_path + ".new")) << where;
      continue;
    }
    const std::string temp = final_path + ".new";
    if (!created) {  // killed before create_replacement() returned: nothing was reported durable
      ++t.before_create;
      ASSERT_EQ(durable, 0u);
      continue;
    }
    // Half of the kills are power cuts: a random part of what was not reported durable is lost.
    if (rng() % 2 == 0) {
      ++t.emulated;
      route::RouteNode next = test::power_cut_node(new_seed, durable);
      emulate_power_cut(temp, route::kHeaderBytes + durable * rec, params, next, rng);
    } else if ((file_size(temp) - route::kHeaderBytes) % rec != 0 && (file_size(temp) - route::kHeaderBytes) % rec != route::kEndMarkBytes) {
      ++t.torn_natural;  // a torn tail left by the kill alone
    }
    check_reopen(
        temp, durable, planned, t, [&](std::uint32_t i) { return test::power_cut_node(new_seed, i); },
        [&](tools::RouteFileReader& rd) {
          std::string bad = check_synthetic(rd, new_seed);
          return bad;
        },
        where);
    if (HasFatalFailure()) return;
  }
  const double s = ms_since(t_all) / 1000.0;
  std::printf(
      "power cut (synthetic teach): %ld kills, %ld nodes reported durable, %ld nodes recovered, %ld lost; %ld torn tails seen (%ld from kill -9 "
      "alone, %ld power losses emulated), %ld cut off, %ld closed not committed, %ld committed, %ld killed before create, old route intact %ld of "
      "%ld replacements; %ld resumed by open_append; %.1f ms/node, routes of 1..%ld nodes; %.1f s\n",
      t.kills, t.durable, t.recovered, t.lost, t.torn, t.torn_natural, t.emulated, t.cut_off, t.closed_not_committed, t.committed, t.before_create,
      t.old_intact, kills / 2, t.appended, node_ms, max_nodes, s);
  EXPECT_EQ(t.lost, 0);
  EXPECT_GT(t.torn, 0) << "no torn tail was ever seen: the torn-tail path was not exercised";
  EXPECT_GT(t.cut_off, 0);
  EXPECT_GT(t.committed, 0);
  EXPECT_GT(t.old_intact, 0);
  remove_route_files(final_path);
  std::remove(err.c_str());
  ::rmdir(dir.c_str());
}

// qnavd teaching on its sim backend: every kill leaves route_1.qroute as it was (the route taught by
// the complete run before) and the nodes logged as written in route_1.qroute.new.
TEST(RoutePowerCut, QnavdTeachKilledAtRandomMoments) {
  const long kills = env_long("QNAV_POWER_CUT_DAEMON_KILLS", 20);
  const std::uint64_t seed = static_cast<std::uint64_t>(env_long("QNAV_POWER_CUT_SEED", 19));
  std::mt19937_64 rng(seed + 1);
  const std::string dir = temp_dir();
  ASSERT_FALSE(dir.empty());
  const std::string routes = dir + "/routes", cfg = dir + "/teach.toml", err = dir + "/qnavd.err";
  ASSERT_EQ(::mkdir(routes.c_str(), 0755), 0);
  {
    std::ofstream f(cfg);
    f << "[daemon]\nbackend = \"sim\"\nroute_dir = \"" << routes << "\"\nlog = \"json\"\nrealtime = false\nhealth_period_s = 60.0\n"
      << "[sim]\nlength_m = 300.0\nspeed = \"fast\"\nexit_at_end = true\n[[sim.pass]]\nmode = \"teach\"\n";
  }
  const std::string final_path = routes + "/route_1.qroute", temp = final_path + ".new";
  const auto t_all = Clock::now();
  // The complete run: the route every later (killed) teach replaces.
  RunResult full = run_and_kill({QNAVD_PATH, "--config", cfg}, -1.0, "", err);
  ASSERT_EQ(full.exit_code, 0) << read_all(err);
  auto tile_nodes = [](const RunResult& r) {
    long d = 0;
    for (const std::string& l : r.lines) {
      const std::size_t at = l.find("\"node_written\":");
      if (l.find("\"event\":\"tile\"") == std::string::npos || at == std::string::npos) continue;
      const long n = std::strtol(l.c_str() + at + 15, nullptr, 10);
      if (n >= 0) d = std::max(d, n + 1);  // printed after append() returned
    }
    return static_cast<std::uint32_t>(d);
  };
  const std::uint32_t full_nodes = tile_nodes(full);
  const std::string old_bytes = read_all(final_path);
  const std::string full_copy = dir + "/full.qroute";
  {
    std::ofstream c(full_copy, std::ios::binary);
    c << old_bytes;
  }
  {
    tools::RouteFileReader r;
    ASSERT_TRUE(r.open(final_path.c_str()).is_ok());
    ASSERT_TRUE(r.closed_cleanly()) << "qnavd's committed route has no end mark";
    ASSERT_EQ(r.node_count(), full_nodes);
    ASSERT_GE(full_nodes, 4u);
  }
  // Every node read back decodes in full. Its content is compared with the node the complete run
  // taught (same seed) and a difference is counted, not failed: under a loaded machine (the ASan
  // build, a parallel ctest) a seeded sim teach was seen to give a different first node (issue #19's
  // closing note), so the content check is reported rather than asserted.
  tools::RouteFileReader full_route;
  ASSERT_TRUE(full_route.open(full_copy.c_str()).is_ok());
  long content_differs = 0;
  auto same_as_full = [&](tools::RouteFileReader& rd) -> std::string {
    route::RouteNode out, want;
    for (std::uint32_t i = 0; i < rd.node_count(); ++i) {
      const Status s = rd.load(i, out);
      if (!s) return "node " + std::to_string(i) + ": " + s.message();
      if (i < full_nodes && (!full_route.load(i, want) || !nodes_equal(out, want, false))) ++content_differs;
    }
    return "";
  };
  Tally t;
  for (long k = 0; k < kills; ++k) {
    const std::string before_bytes = read_all(final_path);
    const std::uint64_t before_inode = inode(final_path);
    const std::string where = "qnavd kill " + std::to_string(k) + " (seed " + std::to_string(seed) + ")";
    std::remove(temp.c_str());
    for (int n = 1; n < 20; ++n) std::remove((temp + ".kept." + std::to_string(n)).c_str());
    const double delay_ms = std::uniform_real_distribution<double>(0.0, full.ms)(rng);
    const RunResult r = run_and_kill({QNAVD_PATH, "--config", cfg}, delay_ms, "", err);
    ++t.kills;
    const std::uint32_t durable = tile_nodes(r);
    ASSERT_TRUE(r.killed || r.exit_code == 0) << where << ": " << read_all(err);
    // The final name holds a complete route: the old one untouched, or the new one once committed
    // (the simulator is seeded: the same nodes, but for the stamps).
    {
      tools::RouteFileReader f;
      ASSERT_TRUE(f.open(final_path.c_str()).is_ok()) << where;
      ASSERT_TRUE(f.closed_cleanly()) << where;
      ASSERT_EQ(f.node_count(), full_nodes) << where;
      ASSERT_EQ(same_as_full(f), "") << where;
    }
    // A commit renames the new file over the old one: another inode (the bytes may even be equal:
    // the seeded simulator can fly the same mission to the nanosecond).
    const bool replaced = inode(final_path) != before_inode;
    if (!replaced) {
      ASSERT_EQ(read_all(final_path), before_bytes) << where << ": the route under the final name was changed in place";
      ++t.old_intact;
    }
    if (!exists(temp)) {  // killed before the teach began, or committed (renamed)
      if (!replaced) {
        ASSERT_EQ(durable, 0u) << where << ": nodes were written, but there is neither a .new nor a new route";
        ++t.before_create;
      } else {
        ASSERT_GE(durable, 1u) << where;
        ++t.committed;
        t.durable += durable;
        t.recovered += full_nodes;
      }
      continue;
    }
    ASSERT_FALSE(replaced) << where << ": the route was replaced but its .new is still there";
    if (file_size(temp) < route::kHeaderBytes) {  // killed inside create(): nothing reported
      ASSERT_EQ(durable, 0u) << where;
      ++t.before_create;
      continue;
    }
    tools::RouteFileReader probe;
    ASSERT_TRUE(probe.open(temp.c_str()).is_ok()) << where;
    const route::RouteParams params = probe.params();
    const std::uint64_t rec = route::record_bytes(params.max_keypoints);
    probe.close();
    // Teaching resumes with the node the complete run taught next.
    auto next_node = [&](std::uint32_t i) {
      route::RouteNode n;
      if (!full_route.load(i < full_nodes ? i : 0, n)) n = route::RouteNode{};
      return n;
    };
    if (rng() % 2 == 0) {
      ++t.emulated;
      emulate_power_cut(temp, route::kHeaderBytes + durable * rec, params, next_node(durable), rng);
    }
    check_reopen(temp, durable, full_nodes, t, next_node, same_as_full, where);
    if (HasFatalFailure()) return;
  }
  std::printf(
      "power cut (qnavd teach, sim backend): %ld kills, %ld nodes reported durable, %ld nodes recovered (each decoded in full), "
      "%ld lost; %ld torn tails seen (%ld power losses emulated), %ld cut off, %ld closed not committed, %ld committed, "
      "%ld killed before the route was created; route_1.qroute complete after every kill (%ld untouched, %ld replaced by a committed teach); "
      "%ld resumed by open_append; %ld nodes read back differing from the complete run's content; teach pass %.0f ms, %u nodes; %.1f s\n",
      t.kills, t.durable, t.recovered, t.lost, t.torn, t.emulated, t.cut_off, t.closed_not_committed, t.committed, t.before_create, t.old_intact,
      t.kills - t.old_intact, t.appended, content_differs, full.ms, full_nodes, ms_since(t_all) / 1000.0);
  EXPECT_EQ(t.lost, 0);
  remove_route_files(final_path);
  full_route.close();
  std::remove(full_copy.c_str());
  std::remove(cfg.c_str());
  std::remove(err.c_str());
  ::rmdir(routes.c_str());
  ::rmdir(dir.c_str());
}


// qnavd says so when the route it is told to repeat was cut off or has a torn tail (and still uses
// its complete nodes); a clean route raises nothing.
TEST(RoutePowerCut, QnavdReportsACutOffRouteItRepeats) {
  const std::string dir = temp_dir();
  ASSERT_FALSE(dir.empty());
  const std::string routes = dir + "/routes", err = dir + "/qnavd.err";
  ASSERT_EQ(::mkdir(routes.c_str(), 0755), 0);
  auto config = [&](const char* name, const char* mode) {
    const std::string path = dir + "/" + name;
    std::ofstream f(path);
    f << "[daemon]\nbackend = \"sim\"\nroute_dir = \"" << routes << "\"\nlog = \"json\"\nrealtime = false\nhealth_period_s = 60.0\n"
      << "[sim]\nlength_m = 300.0\nspeed = \"fast\"\nexit_at_end = true\n[[sim.pass]]\nmode = \"" << mode << "\"\n";
    return path;
  };
  const std::string teach = config("teach.toml", "teach"), repeat = config("repeat.toml", "repeat");
  const std::string route = routes + "/route_1.qroute";
  RunResult r = run_and_kill({QNAVD_PATH, "--config", teach}, -1.0, "", err);
  ASSERT_EQ(r.exit_code, 0) << read_all(err);
  auto events = [](const RunResult& run, const char* what) {
    std::vector<std::string> out;
    for (const std::string& l : run.lines)
      if (l.find(std::string("\"event\":\"") + what + "\"") != std::string::npos) out.push_back(l);
    return out;
  };
  auto repeat_tiles = [](const RunResult& run) {
    int n = 0;
    for (const std::string& l : run.lines) n += l.find("\"event\":\"tile\"") != std::string::npos && l.find("\"mode\":\"repeat\"") != std::string::npos;
    return n;
  };
  std::uint32_t nodes = 0;
  std::uint64_t rec = 0;
  {
    tools::RouteFileReader rd;
    ASSERT_TRUE(rd.open(route.c_str()).is_ok());
    ASSERT_TRUE(rd.closed_cleanly());
    nodes = rd.node_count();
    rec = route::record_bytes(rd.params().max_keypoints);
  }
  ASSERT_GE(nodes, 4u);
  r = run_and_kill({QNAVD_PATH, "--config", repeat}, -1.0, "", err);
  ASSERT_EQ(r.exit_code, 0) << read_all(err);
  EXPECT_TRUE(events(r, "route_cut_off").empty()) << "a clean route reported cut off";
  EXPECT_GT(repeat_tiles(r), 0);
  // The end mark and the second half of the last node lost to a power cut.
  ASSERT_EQ(::truncate(route.c_str(), static_cast<off_t>(route::kHeaderBytes + nodes * rec - rec / 2)), 0);
  r = run_and_kill({QNAVD_PATH, "--config", repeat}, -1.0, "", err);
  ASSERT_EQ(r.exit_code, 0) << read_all(err);
  const std::vector<std::string> cut = events(r, "route_cut_off");
  ASSERT_EQ(cut.size(), 1u) << "qnavd did not report the cut-off route";
  EXPECT_NE(cut[0].find("\"nodes\":" + std::to_string(nodes - 1) + ","), std::string::npos) << cut[0];
  EXPECT_NE(cut[0].find("\"torn_bytes\":" + std::to_string(rec - rec / 2) + ","), std::string::npos) << cut[0];
  EXPECT_NE(cut[0].find("\"partial_node_dropped\":true"), std::string::npos) << cut[0];
  EXPECT_NE(cut[0].find("cut off: no end mark"), std::string::npos) << cut[0];
  EXPECT_GT(repeat_tiles(r), 0) << "the cut-off route's complete nodes were not used";
  remove_route_files(route);
  for (const char* f : {"teach.toml", "repeat.toml", "qnavd.err"}) std::remove((dir + "/" + f).c_str());
  ::rmdir(routes.c_str());
  ::rmdir(dir.c_str());
}

}  // namespace
}  // namespace qnav
