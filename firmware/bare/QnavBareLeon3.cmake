# Freestanding LEON3 images (no OS, no glibc, no libstdc++ linked): see firmware/bare/README.md.
# include() this file from a cross build with the leon3 toolchain (toolchain/leon3.cmake); it defines
#   qnav_bare_newlib_libm(<target> [C_COMPILER <cc>] [C_FLAGS ...])
#       a static library of newlib's fdlibm functions that nav/ and the simulators call, compiled
#       from /usr/src/newlib/newlib-*.tar.xz (Debian newlib-source), extracted into the build tree.
#       Used for the image and, built with the host compiler, for the host reference (same numbers).
#   qnav_add_bare_leon3_executable(<name> SOURCES <file>... [INCLUDES <dir>...] [RAM_MIB <n>])
#       <name>.elf: the sources + the runtime (crt0.S, runtime.cpp, uart.cpp) + the libm above,
#       linked -nostdlib with firmware/bare/leon3/leon3.ld. Every source is compiled here with the
#       freestanding flags (no object of the hosted libraries is reused).
#   qnav_bare_newlib_sources(<out-var>)   the list of newlib .c files (for the host reference build)
include_guard(GLOBAL)

set(QNAV_BARE_DIR ${CMAKE_CURRENT_LIST_DIR} CACHE INTERNAL "")
set(QNAV_NEWLIB_TARBALL "" CACHE FILEPATH "newlib source tarball (default: /usr/src/newlib/newlib-*.tar.xz)")

# The libm functions nav/, drivers/ and the canned inputs use (double and float), their kernels and
# the helpers those call. fdlibm ("__OBSOLETE_MATH") implementations throughout, wrappers without
# errno (_IEEE_LIBM).
set(QNAV_NEWLIB_LIBM_FILES
  math/w_sqrt.c math/e_sqrt.c math/wf_sqrt.c math/ef_sqrt.c
  math/s_floor.c math/sf_floor.c math/s_ceil.c math/sf_ceil.c math/s_fabs.c math/sf_fabs.c
  math/s_sin.c math/sf_sin.c math/s_cos.c math/sf_cos.c math/s_tan.c math/sf_tan.c
  math/k_sin.c math/kf_sin.c math/k_cos.c math/kf_cos.c math/k_tan.c math/kf_tan.c
  math/e_rem_pio2.c math/ef_rem_pio2.c math/k_rem_pio2.c math/kf_rem_pio2.c
  math/w_exp.c math/e_exp.c math/wf_exp.c math/ef_exp.c
  math/w_log.c math/e_log.c math/wf_log.c math/ef_log.c
  math/w_pow.c math/e_pow.c math/wf_pow.c math/ef_pow.c
  math/w_atan2.c math/e_atan2.c math/wf_atan2.c math/ef_atan2.c math/s_atan.c math/sf_atan.c
  math/w_asin.c math/e_asin.c math/wf_asin.c math/ef_asin.c
  math/w_acos.c math/e_acos.c math/wf_acos.c math/ef_acos.c
  math/w_fmod.c math/e_fmod.c math/wf_fmod.c math/ef_fmod.c math/w_sincos.c math/wf_sincos.c
  common/s_lround.c common/sf_lround.c common/s_round.c common/sf_round.c
  common/s_scalbn.c common/sf_scalbn.c common/s_copysign.c common/sf_copysign.c
  common/s_finite.c common/sf_finite.c common/s_nan.c common/sf_nan.c
  common/s_rint.c common/sf_rint.c common/s_trunc.c common/sf_trunc.c)

# Extracts libm/ and libc/include/ of newlib once per build tree; sets QNAV_NEWLIB_ROOT (.../newlib).
function(_qnav_newlib_extract)
  if(QNAV_NEWLIB_ROOT AND EXISTS ${QNAV_NEWLIB_ROOT}/libm/common/fdlibm.h)
    return()
  endif()
  set(tarball ${QNAV_NEWLIB_TARBALL})
  if(NOT tarball)
    file(GLOB tarball /usr/src/newlib/newlib-*.tar.xz /usr/src/newlib/newlib-*.tar.gz)
    if(tarball)
      list(SORT tarball)
      list(GET tarball -1 tarball)
    endif()
  endif()
  if(NOT tarball OR NOT EXISTS "${tarball}")
    message(FATAL_ERROR "newlib sources not found: install newlib-source (scripts/packages.txt) or set QNAV_NEWLIB_TARBALL")
  endif()
  set(dest ${CMAKE_BINARY_DIR}/_deps/newlib-src)
  file(REMOVE_RECURSE ${dest})
  file(ARCHIVE_EXTRACT INPUT ${tarball} DESTINATION ${dest} PATTERNS "*/newlib/libm/math" "*/newlib/libm/common" "*/newlib/libc/include")
  file(GLOB top ${dest}/*/newlib)
  if(NOT EXISTS ${top}/libm/common/fdlibm.h)
    message(FATAL_ERROR "unexpected layout in ${tarball}")
  endif()
  set(QNAV_NEWLIB_ROOT ${top} CACHE INTERNAL "extracted newlib tree")
endfunction()

function(qnav_bare_newlib_sources out)
  _qnav_newlib_extract()
  set(files)
  foreach(f IN LISTS QNAV_NEWLIB_LIBM_FILES)
    list(APPEND files ${QNAV_NEWLIB_ROOT}/libm/${f})
  endforeach()
  set(${out} ${files} PARENT_SCOPE)
endfunction()

# The compile options of the newlib files for a compiler: newlib's own headers (not glibc's), the
# compiler's include directory for stddef.h/float.h.
function(qnav_bare_newlib_options out compiler)
  _qnav_newlib_extract()
  execute_process(COMMAND ${compiler} ${ARGN} -print-file-name=include OUTPUT_VARIABLE gccinc OUTPUT_STRIP_TRAILING_WHITESPACE)
  set(${out} -nostdinc "SHELL:-isystem ${QNAV_NEWLIB_ROOT}/libc/include" "SHELL:-isystem ${gccinc}" -I${QNAV_NEWLIB_ROOT}/libm/common
      -D_IEEE_LIBM -D__OBSOLETE_MATH=1 -D_COMPILING_NEWLIB -O2 -ffp-contract=off -fno-builtin -w PARENT_SCOPE)
endfunction()

# Compile flags of every freestanding object (nav/, drivers/, the workload, the runtime).
set(QNAV_BARE_CXX_FLAGS
  -std=c++17 -O2 -DNDEBUG -DEIGEN_NO_DEBUG -DEIGEN_MPL2_ONLY -DQNAV_FREESTANDING=1
  -fno-exceptions -fno-rtti -fno-threadsafe-statics -fno-asynchronous-unwind-tables -fno-unwind-tables
  -fno-stack-protector -fno-pic -fno-pie -ffp-contract=off -finline-atomics -ffunction-sections -fdata-sections
  CACHE INTERNAL "")

function(qnav_bare_newlib_libm target)
  qnav_bare_newlib_sources(srcs)
  qnav_bare_newlib_options(opts ${CMAKE_C_COMPILER} -m32 -mcpu=leon3)
  add_library(${target} STATIC EXCLUDE_FROM_ALL ${srcs})
  target_compile_options(${target} PRIVATE ${opts} -fno-pic -fno-pie -ffunction-sections -fdata-sections)
  # The toolchain's -fno-inline-atomics etc. are harmless here; the libm has no atomics.
endfunction()

function(qnav_add_bare_leon3_executable name)
  cmake_parse_arguments(A "" "RAM_MIB" "SOURCES;INCLUDES" ${ARGN})
  if(NOT A_RAM_MIB)
    set(A_RAM_MIB 64)
  endif()
  if(NOT TARGET qnav_bare_leon3_libm)
    qnav_bare_newlib_libm(qnav_bare_leon3_libm)
    add_library(qnav_bare_leon3_runtime STATIC EXCLUDE_FROM_ALL
      ${QNAV_BARE_DIR}/leon3/crt0.S ${QNAV_BARE_DIR}/leon3/uart.cpp ${QNAV_BARE_DIR}/leon3/runtime.cpp
      ${QNAV_BARE_DIR}/leon3/libgcc_shims.c)
    target_compile_options(qnav_bare_leon3_runtime PRIVATE $<$<COMPILE_LANGUAGE:CXX>:${QNAV_BARE_CXX_FLAGS}>
      $<$<COMPILE_LANGUAGE:ASM>:-m32 -mcpu=leon3 -fno-pic>)
    # No loop in memcpy/memset may be recognised as a call to itself.
    target_compile_options(qnav_bare_leon3_runtime PRIVATE $<$<COMPILE_LANGUAGE:C>:-O2 -fno-pic -ffp-contract=off>)
    set_source_files_properties(${QNAV_BARE_DIR}/leon3/runtime.cpp ${QNAV_BARE_DIR}/leon3/libgcc_shims.c PROPERTIES COMPILE_OPTIONS "-fno-builtin;-fno-tree-loop-distribute-patterns")
    target_include_directories(qnav_bare_leon3_runtime PUBLIC ${QNAV_BARE_DIR}/leon3)
  endif()
  add_executable(${name} EXCLUDE_FROM_ALL ${A_SOURCES})
  set_target_properties(${name} PROPERTIES SUFFIX ".elf" LINKER_LANGUAGE CXX)
  target_include_directories(${name} PRIVATE ${A_INCLUDES} ${QNAV_BARE_DIR}/leon3)
  target_include_directories(${name} SYSTEM PRIVATE ${EIGEN3_INCLUDE_DIR} /usr/include/eigen3)
  target_compile_options(${name} PRIVATE ${QNAV_BARE_CXX_FLAGS})
  # No start files, no glibc, no libstdc++, and no libgcc either: Debian's 32-bit sparc libgcc.a is
  # V8+ code. The runtime provides the few helpers the link needs (firmware/bare/README.md).
  target_link_options(${name} PRIVATE -nostdlib -nostartfiles -static -no-pie -Wl,--gc-sections -Wl,--build-id=none
    -Wl,-T,${QNAV_BARE_DIR}/leon3/leon3.ld -Wl,--defsym=__ram_bytes_override=${A_RAM_MIB}M -Wl,-Map=$<TARGET_FILE:${name}>.map)
  # Whole runtime archive: crt0's _start is not referenced by anything.
  target_link_libraries(${name} PRIVATE -Wl,--whole-archive qnav_bare_leon3_runtime -Wl,--no-whole-archive qnav_bare_leon3_libm)
  set_target_properties(${name} PROPERTIES LINK_DEPENDS ${QNAV_BARE_DIR}/leon3/leon3.ld QNAV_BARE_RAM_MIB ${A_RAM_MIB})
endfunction()
