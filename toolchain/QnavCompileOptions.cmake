# Project-wide compile options. Every qnav target links qnav_options.
add_library(qnav_options INTERFACE)
target_compile_options(qnav_options INTERFACE
  # (-Wnull-dereference is left out: at -O3 it fires inside gtest.h on the cross compilers.)
  -Wall -Wextra -Werror -Wshadow -Wnon-virtual-dtor -Wcast-align -Wunused -Woverloaded-virtual
  -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough)
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  # gcc 12 warns falsely inside Eigen and libstdc++ (array-bounds/stringop on inlined fixed buffers).
  target_compile_options(qnav_options INTERFACE -Wno-array-bounds -Wno-stringop-overflow -Wno-maybe-uninitialized)
endif()
target_compile_definitions(qnav_options INTERFACE
  # Eigen: no alignment-based heap tricks are needed; fixed-size types only in nav/.
  EIGEN_MPL2_ONLY)
# Builds with assertions (Debug: host-debug, host-clang) compile Eigen's run-time allocation check
# everywhere; the tests' no-allocation regions (QNAV_EXPECT_NO_ALLOC, test::EigenMallocForbidden)
# switch it on, so an Eigen heap allocation on a hot path asserts there (DESIGN.md, fixed allocation).
option(QNAV_EIGEN_NO_MALLOC "Compile EIGEN_RUNTIME_NO_MALLOC (Debug builds)" ON)
if(QNAV_EIGEN_NO_MALLOC AND CMAKE_BUILD_TYPE STREQUAL "Debug")
  target_compile_definitions(qnav_options INTERFACE EIGEN_RUNTIME_NO_MALLOC)
endif()
# libFuzzer builds (QNAV_FUZZ=ON with clang: the host-clang preset): every library carries the coverage
# instrumentation the fuzz targets steer by (test/fuzz links -fsanitize=fuzzer into fuzz_<name> only),
# always with ASan + UBSan.
option(QNAV_FUZZ "Build the libFuzzer targets of test/fuzz (clang)" OFF)
if(QNAV_FUZZ AND CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
  set(QNAV_SANITIZE ON)
  target_compile_options(qnav_options INTERFACE -fsanitize=fuzzer-no-link)
endif()
if(QNAV_SANITIZE)
  target_compile_options(qnav_options INTERFACE -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
  target_link_options(qnav_options INTERFACE -fsanitize=address,undefined)
endif()

# nav/ is built without exceptions and RTTI: errors are values (nav/core/status.hpp).
add_library(qnav_nav_options INTERFACE)
target_link_libraries(qnav_nav_options INTERFACE qnav_options Eigen3::Eigen)
target_compile_options(qnav_nav_options INTERFACE -fno-exceptions -fno-rtti)

# Libraries the qnav tool and the daemon link: every nav/, hal/, drivers/ and firmware/tools library
# registers itself here, so adding a library never means editing the executables' CMakeLists.
function(qnav_register_library target)
  set_property(GLOBAL APPEND PROPERTY QNAV_LIBRARIES ${target})
endfunction()
