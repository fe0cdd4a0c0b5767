# Test helpers. GoogleTest comes from Debian: the prebuilt libgtest-dev on the host, and the source
# Debian ships in /usr/src/googletest (same package) compiled with the cross compiler for the targets.
if(CMAKE_CROSSCOMPILING)
  set(INSTALL_GTEST OFF CACHE BOOL "" FORCE)
  set(BUILD_GMOCK ON CACHE BOOL "" FORCE)
  if(QNAV_TARGET_STATIC)
    # Static glibc + pthread under qemu-user is fragile; gtest does not need threads for our tests.
    set(gtest_disable_pthreads ON CACHE BOOL "" FORCE)
  endif()
  add_subdirectory(/usr/src/googletest ${CMAKE_BINARY_DIR}/_googletest EXCLUDE_FROM_ALL)
  # googletest's own CMake defines the GTest::gtest / GTest::gtest_main / GTest::gmock aliases.
else()
  find_package(GTest REQUIRED)
endif()
include(GoogleTest)

# qnav_add_test(NAME name SOURCES a.cpp b.cpp LIBS lib1 lib2 [LABELS l1 l2] [NO_TARGET])
# One executable per module; on the host each TEST is a ctest test (discovered before the run), under
# an emulator the whole executable is one ctest test (discovery under qemu costs a start-up per test).
# NO_TARGET: host-only test (needs kernel devices or host libraries), not built for cross targets.
function(qnav_add_test)
  cmake_parse_arguments(T "NO_TARGET" "NAME" "SOURCES;LIBS;LABELS" ${ARGN})
  if(T_NO_TARGET AND CMAKE_CROSSCOMPILING)
    return()
  endif()
  add_executable(${T_NAME} ${T_SOURCES})
  target_link_libraries(${T_NAME} PRIVATE ${T_LIBS} qnav_test_support GTest::gtest_main qnav_options)
  target_compile_definitions(${T_NAME} PRIVATE QNAV_SHARED_DIR="${QNAV_SHARED_DIR}")
  if(CMAKE_CROSSCOMPILING)
    add_test(NAME ${T_NAME} COMMAND ${T_NAME})
    set_tests_properties(${T_NAME} PROPERTIES LABELS "${T_LABELS};target" TIMEOUT 900)
  else()
    # The labels and the timeout are set by a script ctest runs after the discovery, on the list of
    # discovered tests: gtest_discover_tests(PROPERTIES LABELS "a;b") splits the list (CMake issue
    # 17812), so a second label became a property name and both it and TIMEOUT were lost.
    gtest_discover_tests(${T_NAME} DISCOVERY_MODE PRE_TEST TEST_LIST ${T_NAME}_TESTS)
    set(_props ${CMAKE_CURRENT_BINARY_DIR}/${T_NAME}_properties.cmake)
    file(WRITE ${_props} "if(${T_NAME}_TESTS)\n  set_tests_properties(\${${T_NAME}_TESTS} PROPERTIES LABELS \"${T_LABELS}\" TIMEOUT 600)\nendif()\n")
    set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES ${_props})
  endif()
endfunction()
