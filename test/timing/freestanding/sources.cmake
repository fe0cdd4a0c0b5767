# The workload of the freestanding LEON3 image and of its host reference: the SAME canned stages as the
# hosted timing program (test/timing/canned.cpp), with everything it calls compiled from source:
# nav/ (every stage), the simulators that render the canned inputs, the route defaults, and the
# byte-order-sensitive decoders of drivers/sidescan (XTF, JSF parsers; pure code over byte spans).
# Needs QNAV_FS_ROOT (the source tree); sets QNAV_FREESTANDING_SOURCES.
file(GLOB QNAV_FREESTANDING_SOURCES CONFIGURE_DEPENDS ${QNAV_FS_ROOT}/nav/*/*.cpp ${QNAV_FS_ROOT}/drivers/stereo_sim/*.cpp)
list(APPEND QNAV_FREESTANDING_SOURCES
  ${QNAV_FS_ROOT}/drivers/sidescan/sim_seabed.cpp
  ${QNAV_FS_ROOT}/drivers/sidescan/sim_sidescan.cpp
  ${QNAV_FS_ROOT}/drivers/sidescan/sim_trajectory.cpp
  ${QNAV_FS_ROOT}/drivers/sidescan/xtf_parser.cpp
  ${QNAV_FS_ROOT}/drivers/sidescan/xtf_writer.cpp
  ${QNAV_FS_ROOT}/drivers/sidescan/jsf_parser.cpp
  ${QNAV_FS_ROOT}/firmware/pipeline/route_defaults.cpp
  ${QNAV_FS_ROOT}/test/timing/canned.cpp
  ${QNAV_FS_ROOT}/test/timing/freestanding/workload.cpp)
