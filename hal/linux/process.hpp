// Process services qnavd needs from Linux, so nothing above hal/ calls the OS for them:
//  - lock_memory(): mlockall(MCL_CURRENT | MCL_FUTURE) (no page faults on the hot path).
//  - set_thread_realtime(): SCHED_FIFO at a priority, optionally pinned to one CPU, for the calling thread.
//  - StopSignals: SIGTERM/SIGINT set a flag (async-signal-safe) that the daemon polls.
//  - ServiceNotifier: the sd_notify protocol spoken directly on $NOTIFY_SOCKET (AF_UNIX datagram,
//    abstract or path), no libsystemd: READY=1, STATUS=..., WATCHDOG=1, STOPPING=1. Without
//    $NOTIFY_SOCKET every call is a no-op. watchdog_usec() reads $WATCHDOG_USEC (0 = no watchdog).
//  - ensure_dir(): mkdir -p.
// Each call returns a Status whose message carries strerror(errno) and, for EPERM, the capability
// that is missing. No heap after construction.
#pragma once

#include <atomic>
#include <cstdint>

#include "nav/core/status.hpp"

namespace qnav::hal {

// Message buffers for the OS reason live in thread-local storage (Status keeps a static message).
Status lock_memory() noexcept;
Status set_thread_realtime(int priority, int cpu) noexcept;
Status ensure_dir(const char* path) noexcept;
bool path_exists(const char* path) noexcept;
// Replaces this process with the program `name` from this executable's own directory
// (/proc/self/exe), with the same arguments: qnavd runs qnavd-sim for a simulated vehicle. Returns
// only on failure, with the path it tried and the OS reason.
Status exec_sibling(const char* name, char* const argv[]) noexcept;

class StopSignals {
 public:
  // Installs the handlers (SIGTERM, SIGINT; SIGPIPE ignored). One instance per process.
  static Status install() noexcept;
  static bool requested() noexcept;
  static int signal_number() noexcept;  // the first signal received (0 = none)
  static void request(int sig) noexcept;  // the same as a received signal (tests, mission end)
};

class ServiceNotifier {
 public:
  ServiceNotifier() noexcept;
  ~ServiceNotifier();
  ServiceNotifier(const ServiceNotifier&) = delete;
  ServiceNotifier& operator=(const ServiceNotifier&) = delete;
  bool active() const noexcept { return fd_ >= 0; }
  std::uint64_t watchdog_usec() const noexcept { return watchdog_usec_; }
  // Sends one datagram ("READY=1", "WATCHDOG=1", "STATUS=text", "STOPPING=1"); no-op when inactive.
  Status notify(const char* state) noexcept;

 private:
  int fd_ = -1;
  std::uint64_t watchdog_usec_ = 0;
  alignas(8) char addr_[128] = {};  // a sockaddr_un (alignment 2), without the socket headers here
  unsigned addr_len_ = 0;
};

}  // namespace qnav::hal

namespace qnav::hal {
// Waits until one of fds (negative entries ignored) is readable, at most timeout_ms. Returns true
// when one is (or on EINTR), false on timeout. The I/O thread's wait on all its devices at once.
bool wait_readable(const int* fds, int n, int timeout_ms) noexcept;
// Ends the process now (_exit): no destructors, no atexit handlers; what was fsync'ed stays.
[[noreturn]] void exit_now(int code) noexcept;

// This process's resource use so far (getrusage): peak resident set, CPU time (user + system).
struct ProcessUsage {
  long max_rss_kb = 0;
  double cpu_s = 0.0;
};
ProcessUsage process_usage() noexcept;
}  // namespace qnav::hal
