#include "hal/linux/process.hpp"

#include <cerrno>
#include <cstddef>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

namespace qnav::hal {
namespace {

thread_local char t_reason[256];

Status os_error(StatusCode code, const char* what, int err, const char* hint = nullptr) noexcept {
  std::snprintf(t_reason, sizeof t_reason, "%s: %s%s%s", what, std::strerror(err), hint ? " (" : "", hint ? hint : "");
  if (hint) std::strncat(t_reason, ")", sizeof t_reason - std::strlen(t_reason) - 1);
  return Status(code, t_reason);
}

std::atomic<int> g_signal{0};

extern "C" void on_stop_signal(int sig) {
  int expected = 0;
  g_signal.compare_exchange_strong(expected, sig);
}

}  // namespace

Status lock_memory() noexcept {
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
    return os_error(StatusCode::kUnsupported, "mlockall", errno, errno == EPERM || errno == ENOMEM ? "needs CAP_IPC_LOCK or a higher RLIMIT_MEMLOCK" : nullptr);
  return Status::ok();
}

Status set_thread_realtime(int priority, int cpu) noexcept {
  if (cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(cpu, &set);
    const int rc = pthread_setaffinity_np(pthread_self(), sizeof set, &set);
    if (rc != 0) return os_error(StatusCode::kUnsupported, "pthread_setaffinity_np", rc, "is the CPU online?");
  }
  sched_param sp{};
  sp.sched_priority = priority;
  const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
  if (rc != 0) return os_error(StatusCode::kUnsupported, "SCHED_FIFO", rc, rc == EPERM ? "needs CAP_SYS_NICE or an RLIMIT_RTPRIO" : nullptr);
  return Status::ok();
}

Status ensure_dir(const char* path) noexcept {
  char buf[512];
  const std::size_t n = std::strlen(path);
  if (n == 0 || n >= sizeof buf) return Status(StatusCode::kInvalidArgument, "directory path empty or too long");
  std::memcpy(buf, path, n + 1);
  for (std::size_t i = 1; i <= n; ++i) {
    if (buf[i] == '/' || buf[i] == '\0') {
      const char c = buf[i];
      buf[i] = '\0';
      if (mkdir(buf, 0755) != 0 && errno != EEXIST) return os_error(StatusCode::kIoError, "mkdir", errno);
      buf[i] = c;
    }
  }
  struct stat st{};
  if (stat(path, &st) != 0) return os_error(StatusCode::kIoError, "stat", errno);
  if (!S_ISDIR(st.st_mode)) return Status(StatusCode::kIoError, "exists and is not a directory");
  return Status::ok();
}

Status exec_sibling(const char* name, char* const argv[]) noexcept {
  static char path[4096];
  const ssize_t n = ::readlink("/proc/self/exe", path, sizeof path - 1);
  if (n <= 0) return os_error(StatusCode::kIoError, "readlink /proc/self/exe", errno);
  path[n] = '\0';
  char* slash = std::strrchr(path, '/');
  const std::size_t dir = slash != nullptr ? static_cast<std::size_t>(slash - path) + 1 : 0;
  if (dir + std::strlen(name) + 1 > sizeof path) return Status(StatusCode::kInvalidArgument, "exec_sibling: path too long");
  std::memcpy(path + dir, name, std::strlen(name) + 1);
  ::execv(path, argv);
  static char what[160];
  std::snprintf(what, sizeof what, "cannot run %.140s", path);
  return os_error(StatusCode::kNotFound, what, errno, "is the package's qnavd-sim installed beside qnavd?");
}

bool path_exists(const char* path) noexcept {
  struct stat st{};
  return stat(path, &st) == 0;
}

Status StopSignals::install() noexcept {
  struct sigaction sa{};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  if (sigaction(SIGTERM, &sa, nullptr) != 0 || sigaction(SIGINT, &sa, nullptr) != 0) return os_error(StatusCode::kIoError, "sigaction", errno);
  std::signal(SIGPIPE, SIG_IGN);
  return Status::ok();
}
bool StopSignals::requested() noexcept { return g_signal.load() != 0; }
int StopSignals::signal_number() noexcept { return g_signal.load(); }
void StopSignals::request(int sig) noexcept { on_stop_signal(sig); }

ServiceNotifier::ServiceNotifier() noexcept {
  const char* sock = std::getenv("NOTIFY_SOCKET");
  if (const char* wd = std::getenv("WATCHDOG_USEC")) {
    const char* pid = std::getenv("WATCHDOG_PID");
    if (pid == nullptr || std::strtol(pid, nullptr, 10) == static_cast<long>(getpid())) watchdog_usec_ = std::strtoull(wd, nullptr, 10);
  }
  if (sock == nullptr || (sock[0] != '/' && sock[0] != '@')) return;
  sockaddr_un sa{};
  sa.sun_family = AF_UNIX;
  const std::size_t n = std::strlen(sock);
  if (n >= sizeof sa.sun_path) return;
  std::memcpy(sa.sun_path, sock, n);
  if (sa.sun_path[0] == '@') sa.sun_path[0] = '\0';  // abstract namespace
  static_assert(sizeof(sockaddr_un) <= sizeof addr_, "address buffer");
  std::memcpy(addr_, &sa, sizeof sa);
  addr_len_ = static_cast<unsigned>(offsetof(sockaddr_un, sun_path) + n);
  fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
}

ServiceNotifier::~ServiceNotifier() {
  if (fd_ >= 0) close(fd_);
}

Status ServiceNotifier::notify(const char* state) noexcept {
  if (fd_ < 0) return Status::ok();
  // Through void*: addr_ is aligned for the sockaddr it holds (alignas in process.hpp), which a char*
  // cast cannot show (-Wcast-align on armhf, a strict-alignment target).
  const auto* to = static_cast<const sockaddr*>(static_cast<const void*>(addr_));
  const ssize_t n = sendto(fd_, state, std::strlen(state), MSG_NOSIGNAL, to, addr_len_);
  if (n < 0) return os_error(StatusCode::kIoError, "sd_notify sendto", errno);
  return Status::ok();
}

}  // namespace qnav::hal

#include <poll.h>
#include <sys/resource.h>

namespace qnav::hal {
bool wait_readable(const int* fds, int n, int timeout_ms) noexcept {
  pollfd p[8];
  int k = 0;
  for (int i = 0; i < n && k < 8; ++i)
    if (fds[i] >= 0) p[k++] = pollfd{fds[i], POLLIN, 0};
  if (k == 0) {
    ::poll(nullptr, 0, timeout_ms);
    return false;
  }
  const int r = ::poll(p, static_cast<nfds_t>(k), timeout_ms);
  return r != 0;
}
}  // namespace qnav::hal

namespace qnav::hal {
ProcessUsage process_usage() noexcept {
  ProcessUsage u;
  rusage r{};
  if (getrusage(RUSAGE_SELF, &r) == 0) {
    u.max_rss_kb = r.ru_maxrss;
    u.cpu_s = static_cast<double>(r.ru_utime.tv_sec + r.ru_stime.tv_sec) + 1e-6 * static_cast<double>(r.ru_utime.tv_usec + r.ru_stime.tv_usec);
  }
  return u;
}
}  // namespace qnav::hal

namespace qnav::hal {
void exit_now(int code) noexcept { ::_exit(code); }
}  // namespace qnav::hal
