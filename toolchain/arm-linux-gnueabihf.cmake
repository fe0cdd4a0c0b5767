# 32-bit ARM Linux boards, hard float (Debian's g++-arm-linux-gnueabihf). Tests run under qemu-arm.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(CMAKE_C_COMPILER arm-linux-gnueabihf-gcc)
set(CMAKE_CXX_COMPILER arm-linux-gnueabihf-g++)
set(QNAV_SYSROOT /usr/arm-linux-gnueabihf)
set(CMAKE_FIND_ROOT_PATH ${QNAV_SYSROOT})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)
set(CMAKE_CROSSCOMPILING_EMULATOR ${CMAKE_CURRENT_LIST_DIR}/run-emulator;arm)
# The target's libgpiod, libpng, libjpeg (scripts/fetch-sysroot armhf): the daemon build (QNAV_TARGET_DAEMON).
set(QNAV_TARGET_DEB_ARCH armhf)
set(QNAV_TARGET_TRIPLE arm-linux-gnueabihf)
include(${CMAKE_CURRENT_LIST_DIR}/QnavTargetSysroot.cmake)
# gcc notes that the ARM parameter-passing ABI for some std:: iterators changed in GCC 7.1 (-Wpsabi).
# Every object in a qnav image is built by this one compiler, so the note is noise.
set(CMAKE_CXX_FLAGS_INIT "-Wno-psabi")
