# The target's own libraries for the cross daemon build (docs/install.md, "Cross packages"): the sysroot
# scripts/fetch-sysroot DEB_ARCH unpacks from Debian 12's packages (libgpiod, libpng, libjpeg, zlib), next
# to the cross toolchain's glibc and libstdc++ in /usr/<triple>. Included by the Linux toolchain files
# after they set QNAV_SYSROOT (/usr/<triple>), with QNAV_TARGET_DEB_ARCH (arm64|armhf) and
# QNAV_TARGET_TRIPLE set. Sets QNAV_TARGET_SYSROOT_FOUND when the sysroot is there; then
#   - CMAKE_FIND_ROOT_PATH searches it too (headers, libraries: <sysroot>/usr/lib/<triple>),
#   - pkg-config reads only its .pc files (PKG_CONFIG_LIBDIR, PKG_CONFIG_SYSROOT_DIR),
#   - the linker finds the libraries' own dependencies there (-rpath-link: libpng16 -> libz),
#   - <sysroot>/usr/include/<triple> is a standard include folder (libjpeg's jconfig.h),
#   - the emulator (toolchain/run-emulator --sysroot) gives qemu's guest its libraries.
# -DQNAV_TARGET_SYSROOT=DIR picks another sysroot; the default is fetch-sysroot's cache folder.
if(NOT QNAV_TARGET_SYSROOT)
  if(DEFINED ENV{QNAV_SYSROOT_CACHE})
    set(_qnav_sysroot_cache "$ENV{QNAV_SYSROOT_CACHE}")
  elseif(DEFINED ENV{XDG_CACHE_HOME})
    set(_qnav_sysroot_cache "$ENV{XDG_CACHE_HOME}/qnav-sysroot")
  else()
    set(_qnav_sysroot_cache "$ENV{HOME}/.cache/qnav-sysroot")
  endif()
  set(QNAV_TARGET_SYSROOT "${_qnav_sysroot_cache}/${QNAV_TARGET_DEB_ARCH}/root")
endif()
# try_compile projects run this file again: they get the same sysroot.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES QNAV_TARGET_SYSROOT)
list(REMOVE_DUPLICATES CMAKE_TRY_COMPILE_PLATFORM_VARIABLES)
set(CMAKE_LIBRARY_ARCHITECTURE ${QNAV_TARGET_TRIPLE})
set(_qnav_libdirs "${QNAV_TARGET_SYSROOT}/usr/lib/${QNAV_TARGET_TRIPLE}:${QNAV_TARGET_SYSROOT}/lib/${QNAV_TARGET_TRIPLE}")
# Never the host's .pc files (they describe x86-64 libraries), with or without the sysroot.
set(ENV{PKG_CONFIG_LIBDIR} "${QNAV_TARGET_SYSROOT}/usr/lib/${QNAV_TARGET_TRIPLE}/pkgconfig:${QNAV_TARGET_SYSROOT}/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${QNAV_TARGET_SYSROOT}")
set(ENV{PKG_CONFIG_PATH} "")
if(EXISTS "${QNAV_TARGET_SYSROOT}/usr/lib/${QNAV_TARGET_TRIPLE}")
  set(QNAV_TARGET_SYSROOT_FOUND TRUE)
  list(APPEND CMAKE_FIND_ROOT_PATH ${QNAV_TARGET_SYSROOT})
  set(CMAKE_EXE_LINKER_FLAGS_INIT "-Wl,-rpath-link,${_qnav_libdirs}")
  # The multiarch include folder a native gcc searches by itself (libjpeg's jconfig.h is there).
  set(CMAKE_C_STANDARD_INCLUDE_DIRECTORIES ${QNAV_TARGET_SYSROOT}/usr/include/${QNAV_TARGET_TRIPLE})
  set(CMAKE_CXX_STANDARD_INCLUDE_DIRECTORIES ${QNAV_TARGET_SYSROOT}/usr/include/${QNAV_TARGET_TRIPLE})
  list(INSERT CMAKE_CROSSCOMPILING_EMULATOR 1 --sysroot ${QNAV_TARGET_SYSROOT})
else()
  set(QNAV_TARGET_SYSROOT_FOUND FALSE)
endif()
