// Region markers for the instruction counter (toolchain/insn-count): syscall 0x1f00 is unused on
// aarch64, arm and sparc Linux, so qemu-user returns -ENOSYS and the plugin's syscall callback
// snapshots its counter. Between region_begin(id) and region_end(id) only the code under test runs;
// start-up, argument parsing and printing stay outside. On a real board (no plugin) the markers are
// two failing syscalls and cost nothing else. Test code only: nav/ never calls this.
#pragma once

#include <sys/syscall.h>
#include <unistd.h>

namespace qnav::timing {

constexpr long kRegionSyscall = 0x1f00;

inline void region_begin(int id) noexcept { (void)syscall(kRegionSyscall, 1L, static_cast<long>(id)); }
inline void region_end(int id) noexcept { (void)syscall(kRegionSyscall, 2L, static_cast<long>(id)); }

}  // namespace qnav::timing
