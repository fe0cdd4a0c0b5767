# Install rules and the Debian package (docs/install.md).
#
# Everything the package holds is installed in the component `qnav`; CPack packs that component only
# (CPACK_INSTALL_CMAKE_PROJECTS), so a third-party install() rule never slips into the .deb.
#   /usr/bin/qnavd, /usr/bin/qnavd-sim, /usr/bin/qnav the daemon, with the sim backend, and the tool
#   /usr/lib/systemd/system/qnavd.service             the unit (not enabled, not started on install)
#   /etc/qnav/qnavd.toml                              conffile: the vehicle example the unit reads
#   /usr/share/qnav/examples/{vehicle,sim}.toml       the example configurations, untouched by edits
#   /usr/share/qnav/qnav.dbc                          the CAN interface
#   /usr/share/man/man1/{qnavd,qnavd-sim,qnav}.1.gz            generated from the programs' own --help
#   /usr/share/doc/qnav/*.md                          README, install, qnavd, configuration, interfaces
# The maintainer scripts (toolchain/deb/postinst, prerm, postrm) create the system user `qnav` and
# /var/lib/qnav/routes, and stop/disable the service on removal; they never start it.
#
# Included from the root CMakeLists.txt before the firmware/ folders, which call qnav_install_program();
# the root calls qnav_package() last (the cross Depends need to know whether hal/linux links libgpiod).
# Host builds (QNAV_HOST_TOOLS) and the cross presets' target daemon (QNAV_TARGET_DAEMON: arm64, armhf).
include_guard(GLOBAL)

set(QNAV_PACKAGING_DIR ${CMAKE_CURRENT_LIST_DIR}/deb)
set(QNAV_INSTALL_COMPONENT qnav)

# The unit names /usr/bin/qnavd and /etc/qnav/qnavd.toml, so `cmake --install` defaults to /usr too
# (`--prefix` or CMAKE_INSTALL_PREFIX still choose another place; /etc stays absolute).
if(CMAKE_INSTALL_PREFIX_INITIALIZED_TO_DEFAULT)
  set(CMAKE_INSTALL_PREFIX /usr CACHE PATH "Install prefix (the systemd unit expects /usr)" FORCE)
endif()
set(QNAV_CONFIG_DIR /etc/qnav)
set(QNAV_DATA_DIR share/qnav)
set(QNAV_DOC_DIR share/doc/qnav)
set(QNAV_MAN_DIR share/man/man1)
set(QNAV_UNIT_DIR lib/systemd/system)

# qnav_install_program(TARGET): installs the executable to bin/ and a man page made at build time from
# its own `--help` (and `--version`) output (toolchain/deb/manpage.cmake), so the page cannot drift
# from the program. Cross builds run the program under CMAKE_CROSSCOMPILING_EMULATOR.
function(qnav_install_program target)
  install(TARGETS ${target} RUNTIME DESTINATION bin COMPONENT ${QNAV_INSTALL_COMPONENT})
  set(page ${CMAKE_CURRENT_BINARY_DIR}/${target}.1.gz)
  add_custom_command(OUTPUT ${page}
    COMMAND ${CMAKE_COMMAND} -DPROGRAM=$<TARGET_FILE:${target}> -DNAME=${target}
            "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}" -DVERSION=${PROJECT_VERSION} -DOUT=${page}
            -P ${QNAV_PACKAGING_DIR}/manpage.cmake
    DEPENDS ${target} ${QNAV_PACKAGING_DIR}/manpage.cmake
    COMMENT "man page ${target}.1 from ${target} --help" VERBATIM)
  add_custom_target(${target}_manpage ALL DEPENDS ${page})
  install(FILES ${page} DESTINATION ${QNAV_MAN_DIR} COMPONENT ${QNAV_INSTALL_COMPONENT})
endfunction()

# The files that are not programs.
install(FILES ${PROJECT_SOURCE_DIR}/docs/qnav.dbc DESTINATION ${QNAV_DATA_DIR} COMPONENT ${QNAV_INSTALL_COMPONENT})
install(FILES ${PROJECT_SOURCE_DIR}/README.md ${PROJECT_SOURCE_DIR}/docs/install.md ${PROJECT_SOURCE_DIR}/docs/qnavd.md
              ${PROJECT_SOURCE_DIR}/docs/configuration.md ${PROJECT_SOURCE_DIR}/docs/interfaces.md
        DESTINATION ${QNAV_DOC_DIR} COMPONENT ${QNAV_INSTALL_COMPONENT})

# Debian architecture of the build's target (not of the machine running cpack).
if(CMAKE_SYSTEM_PROCESSOR MATCHES "^(x86_64|AMD64|amd64)$")
  set(QNAV_DEB_ARCH amd64)
elseif(CMAKE_SYSTEM_PROCESSOR MATCHES "^(aarch64|arm64)$")
  set(QNAV_DEB_ARCH arm64)
elseif(CMAKE_SYSTEM_PROCESSOR MATCHES "^arm")
  set(QNAV_DEB_ARCH armhf)
else()
  set(QNAV_DEB_ARCH ${CMAKE_SYSTEM_PROCESSOR})
endif()

set(QNAV_PACKAGE_MAINTAINER "qnav developers <qnav@localhost>" CACHE STRING "Maintainer field of the .deb")
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME qnav)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_VENDOR qnav)
set(CPACK_PACKAGE_CONTACT ${QNAV_PACKAGE_MAINTAINER})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "GPS-free navigation daemon (qnavd) and tool (qnav) for AUVs and rovers")
set(CPACK_PACKAGE_DESCRIPTION
  "qnavd follows a taught route on side-scan sonar or camera tiles, estimates motion by stereo visual
odometry with external attitude, and talks to the autopilot on CAN (qnav.dbc). qnav is the engineers'
tool over recorded files. The service is installed but neither enabled nor started: configure
/etc/qnav/qnavd.toml first, then systemctl enable --now qnavd.")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_INSTALL_CMAKE_PROJECTS "${CMAKE_BINARY_DIR};${PROJECT_NAME};${QNAV_INSTALL_COMPONENT};/")
set(CPACK_PACKAGE_DIRECTORY ${CMAKE_BINARY_DIR}/packages)
set(CPACK_STRIP_FILES TRUE)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # qnav_<version>_<arch>.deb
set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE ${QNAV_DEB_ARCH})
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
# adduser for the postinst; the shared libraries come from dpkg-shlibdeps (appended by CPack).
set(CPACK_DEBIAN_PACKAGE_DEPENDS "adduser")
find_program(QNAV_DPKG_SHLIBDEPS dpkg-shlibdeps)
if(QNAV_DPKG_SHLIBDEPS AND NOT CMAKE_CROSSCOMPILING)
  set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
else()
  # No dpkg-shlibdeps (or a cross build, whose target libraries dpkg does not know): a fixed list,
  # glibc + libstdc++ and, in the target daemon build, the sysroot's libraries the programs link (the
  # minimum versions are the packages' shlibs files). test/package checks it against the programs' NEEDED.
  set(CPACK_DEBIAN_PACKAGE_DEPENDS "adduser, libc6 (>= 2.36), libstdc++6 (>= 12), libgcc-s1")
endif()
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
  ${QNAV_PACKAGING_DIR}/postinst ${QNAV_PACKAGING_DIR}/prerm ${QNAV_PACKAGING_DIR}/postrm
  ${QNAV_PACKAGING_DIR}/conffiles)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION TRUE)

# qnav_package(): the last call of the root CMakeLists.txt, when every program is defined. A macro: CPack
# reads the CPACK_* variables of the root scope.
macro(qnav_package)
  if(CMAKE_CROSSCOMPILING AND NOT CPACK_DEBIAN_PACKAGE_SHLIBDEPS)
    # qnav_tools (qnav, and qnavd's recorded-file backends) links libpng and libjpeg (zlib comes with
    # libpng16-16; the programs do not load libz themselves).
    string(APPEND CPACK_DEBIAN_PACKAGE_DEPENDS
      ", libpng16-16 (>= 1.6.2-1), libjpeg62-turbo (>= 1:2.1.5)")
    if(TARGET qnav_hal_linux)
      get_target_property(_qnav_hal_defs qnav_hal_linux INTERFACE_COMPILE_DEFINITIONS)
      if("QNAV_HAVE_GPIOD=1" IN_LIST _qnav_hal_defs)
        string(APPEND CPACK_DEBIAN_PACKAGE_DEPENDS ", libgpiod2 (>= 1.6.3)")
      endif()
    endif()
  endif()
  include(CPack)
endmacro()
