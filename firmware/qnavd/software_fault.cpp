#include "firmware/qnavd/software_fault.hpp"

namespace qnav::daemon {
namespace {
std::atomic<std::uint32_t> g_count{0};
std::atomic<const char*> g_first_what{nullptr}, g_last_what{nullptr};
std::atomic<const char*> g_first_file{nullptr}, g_last_file{nullptr};
std::atomic<int> g_first_line{0}, g_last_line{0};
}  // namespace

void SoftwareFaults::record(const char* what, const char* file, int line) noexcept {
  if (g_count.fetch_add(1) == 0) {
    g_first_what.store(what);
    g_first_file.store(file);
    g_first_line.store(line);
  }
  g_last_what.store(what);
  g_last_file.store(file);
  g_last_line.store(line);
}
std::uint32_t SoftwareFaults::count() noexcept { return g_count.load(); }
SoftwareFaultRecord SoftwareFaults::first() noexcept { return {g_first_what.load(), g_first_file.load(), g_first_line.load()}; }
SoftwareFaultRecord SoftwareFaults::last() noexcept { return {g_last_what.load(), g_last_file.load(), g_last_line.load()}; }
void SoftwareFaults::reset_for_tests() noexcept {
  g_count.store(0);
  g_first_what.store(nullptr);
  g_last_what.store(nullptr);
  g_first_file.store(nullptr);
  g_last_file.store(nullptr);
  g_first_line.store(0);
  g_last_line.store(0);
}

}  // namespace qnav::daemon
