# LEON3 (SPARC V8, big-endian) flight computers. Debian has no sparc32 cross compiler; its sparc64
# compiler with -m32 -mcpu=leon3 emits 32-bit SPARC code for the LEON3 pipeline. Debian's 32-bit SPARC
# glibc is V8+ code, so the static test binaries run under qemu-sparc32plus (plain qemu-sparc rejects
# them). On a real LEON3 board the same nav/ objects link against a LEON BSP or RTEMS libc instead.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR sparc)
set(CMAKE_C_COMPILER sparc64-linux-gnu-gcc-12)
set(CMAKE_CXX_COMPILER sparc64-linux-gnu-g++-12)
#
# Atomics: for -mcpu=leon3 gcc inlines `casa [addr] 0x0A` (LEON3's user-data ASI). A real LEON3 runs
# it in user mode, but qemu-sparc32plus applies SPARC V9 rules, where an ASI below 0x80 is privileged,
# and traps (trap 0x37, privileged_action). QNAV_LEON3_EMULATED (default ON, the build the tests run)
# routes atomics through libatomic instead (-fno-inline-atomics). Set it OFF for a flight build.
option(QNAV_LEON3_EMULATED "LEON3 build for qemu-sparc32plus (atomics through libatomic)" ON)
if(QNAV_LEON3_EMULATED)
  set(_qnav_leon3_atomics "-fno-inline-atomics")
  set(_qnav_leon3_atomics_link "-latomic")
endif()
set(CMAKE_C_FLAGS_INIT "-m32 -mcpu=leon3 ${_qnav_leon3_atomics}")
set(CMAKE_CXX_FLAGS_INIT "-m32 -mcpu=leon3 ${_qnav_leon3_atomics}")
set(CMAKE_EXE_LINKER_FLAGS_INIT "-m32 -static")
set(CMAKE_CXX_STANDARD_LIBRARIES "${_qnav_leon3_atomics_link}")
set(CMAKE_C_STANDARD_LIBRARIES "${_qnav_leon3_atomics_link}")
set(QNAV_TARGET_STATIC ON CACHE BOOL "" FORCE)
set(QNAV_SYSROOT /usr/sparc64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH ${QNAV_SYSROOT})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)
set(CMAKE_CROSSCOMPILING_EMULATOR ${CMAKE_CURRENT_LIST_DIR}/run-emulator;sparc32plus)
