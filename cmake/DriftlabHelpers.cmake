# One module = one folder = one target `driftlab_<name>` with alias `driftlab::<name>`.
#   driftlab_module(NAME core SOURCES a.cpp ... DEPS PUBLIC Eigen3::Eigen PRIVATE fmt::fmt)
# A module without sources yet is an INTERFACE target (headers only).
function(driftlab_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic)
  if(DRIFTLAB_PCH)
    # A precompiled header that GCC cannot use (other macros or flags than it was built with)
    # is otherwise silently parsed again: make that an error, not a slow build.
    target_compile_options(${target} PRIVATE -Winvalid-pch)
  endif()
  # GCC 12 reports -Wrestrict false positives inside libstdc++'s std::string at -O3 (GCC bug
  # 105329, fixed in GCC 13). With precompiled headers it also reports -Wstringop-overflow,
  # -Wstringop-overread and -Warray-bounds ones there (about 30 in a build, all inside
  # std::string's inlined copies): code read from a precompiled header loses the system-header
  # status that hid them. AddressSanitizer checks every such access at run time instead.
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
    target_compile_options(${target} PRIVATE -Wno-restrict)
    if(DRIFTLAB_PCH)
      target_compile_options(${target} PRIVATE -Wno-stringop-overflow -Wno-stringop-overread
                                              -Wno-array-bounds)
    endif()
  endif()
  if(DRIFTLAB_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# Precompiled headers (DRIFTLAB_PCH): the standard library, Eigen, fmt and yaml-cpp headers
# that nearly every translation unit reaches through core/, parsed once per build instead of
# once per file (about 200,000 preprocessed lines and 2-5 s of a file's compile). The modules
# share driftlab_core's; the tests share driftlab_test_support's (which adds GoogleTest).
set(DRIFTLAB_PCH_HEADERS
    <algorithm> <array> <chrono> <cmath> <cstdint> <cstdio> <cstring> <filesystem> <fstream>
    <functional> <limits> <map> <memory> <numbers> <optional> <sstream> <string> <string_view>
    <utility> <vector> <Eigen/Core> <Eigen/Geometry> <fmt/format.h> <yaml-cpp/yaml.h>)

# Gives `target` the precompiled headers of `owner` (its own when target is owner; EXTRA adds
# headers there).
function(driftlab_pch target owner)
  cmake_parse_arguments(P "" "" "EXTRA" ${ARGN})
  if(NOT DRIFTLAB_PCH)
    return()
  endif()
  if(target STREQUAL owner)
    target_precompile_headers(${target} PRIVATE ${DRIFTLAB_PCH_HEADERS} ${P_EXTRA})
  else()
    target_precompile_headers(${target} REUSE_FROM ${owner})
  endif()
endfunction()

function(driftlab_module)
  cmake_parse_arguments(M "" "NAME" "SOURCES;DEPS" ${ARGN})
  set(target driftlab_${M_NAME})
  if(M_SOURCES)
    add_library(${target} STATIC ${M_SOURCES})
    # Linked into the Python module too, a shared library.
    set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ${DRIFTLAB_BUILD_PYTHON})
    # No fused multiply-add contraction: same bytes out on every x86-64 CPU.
    target_compile_options(${target} PRIVATE -ffp-contract=off)
    target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>
                                                $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
    driftlab_warnings(${target})
    if(M_DEPS)
      target_link_libraries(${target} ${M_DEPS})
    endif()
    driftlab_pch(${target} driftlab_core)
  else()
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>
                                                   $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
    if(M_DEPS)
      string(REPLACE "PUBLIC" "INTERFACE" deps "${M_DEPS}")
      list(FILTER deps EXCLUDE REGEX "^PRIVATE$")
      target_link_libraries(${target} ${deps})
    endif()
  endif()
  # Installed as driftlab::<name> too (find_package(driftlab), see cmake/driftlabConfig.cmake.in).
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${M_NAME})
  set_property(GLOBAL APPEND PROPERTY DRIFTLAB_MODULES ${target})
  add_library(driftlab::${M_NAME} ALIAS ${target})
endfunction()

# A GoogleTest file registered with ctest as test_<dir>_<stem>.
#   driftlab_test(core/se3_test.cpp LIBS driftlab::core [LABELS slow] [COST seconds]
#                 [DEPENDS target...] [DEFINES NAME=VALUE...])
# The files of one folder (its slow ones apart) are linked into one executable, test_<dir>
# (test_<dir>_slow), compiled in unity batches (DRIFTLAB_UNITY), so that GoogleTest's and the
# libraries' header code is compiled once per batch; driftlab_test_executables() makes them,
# after the last driftlab_test(). Each file is still its own ctest test, in its own process: the
# executable with a --gtest_filter of the file's test suites. Label `slow`: left out of the
# sanitizer run (scripts/test --sanitize, in CI), which builds them only with
# DRIFTLAB_BUILD_SLOW_TESTS. DEPENDS: programs the test runs. COST: the file's rough run time;
# ctest -j starts the costliest first, so that a long file does not start last on a fresh
# checkout (ctest has no timings of its own there). With DRIFTLAB_SANITIZE the cases named in
# DRIFTLAB_SANITIZER_SKIPS (Suite.Case) are left out.
function(driftlab_test source)
  cmake_parse_arguments(T "" "COST" "LIBS;LABELS;DEPENDS;DEFINES" ${ARGN})
  if("slow" IN_LIST T_LABELS AND NOT DRIFTLAB_BUILD_SLOW_TESTS)
    return()
  endif()
  get_filename_component(stem ${source} NAME_WE)
  get_filename_component(dir ${source} DIRECTORY)
  string(REPLACE "/" "_" prefix "${dir}")
  set(group test_${prefix})
  if("slow" IN_LIST T_LABELS)
    string(APPEND group _slow)
  endif()
  set_property(GLOBAL APPEND PROPERTY DRIFTLAB_TEST_GROUPS ${group})
  set_property(GLOBAL APPEND PROPERTY ${group}_SOURCES ${source})
  set_property(GLOBAL APPEND PROPERTY ${group}_LIBS ${T_LIBS})
  set_property(GLOBAL APPEND PROPERTY ${group}_DEPENDS ${T_DEPENDS})
  set_property(GLOBAL APPEND PROPERTY ${group}_DEFINES ${T_DEFINES})

  # The file's suites, from its TEST, TEST_F, TEST_P and TYPED_TEST lines (typed and
  # instantiated suites carry a /suffix or prefix/).
  file(STRINGS ${CMAKE_CURRENT_SOURCE_DIR}/${source} lines
       REGEX "^(TEST|TEST_F|TEST_P|TYPED_TEST)\\( *[A-Za-z0-9_]+ *,")
  set(suites)
  foreach(line IN LISTS lines)
    string(REGEX REPLACE "^[A-Z_]+\\( *([A-Za-z0-9_]+) *,.*" "\\1" suite "${line}")
    list(APPEND suites ${suite})
  endforeach()
  list(REMOVE_DUPLICATES suites)
  if(NOT suites)
    message(FATAL_ERROR "driftlab_test(${source}): no TEST, TEST_F, TEST_P or TYPED_TEST line")
  endif()
  get_property(taken GLOBAL PROPERTY ${group}_SUITES)
  set(patterns)
  foreach(suite IN LISTS suites)
    if(suite IN_LIST taken)
      message(FATAL_ERROR "driftlab_test(${source}): test suite ${suite} is in another file of "
                          "${group}; name it after this file")
    endif()
    list(APPEND patterns "${suite}.*" "${suite}/*" "*/${suite}.*" "*/${suite}/*")
  endforeach()
  set_property(GLOBAL APPEND PROPERTY ${group}_SUITES ${suites})
  set_property(GLOBAL APPEND PROPERTY ${group}_PATTERNS ${patterns})
  list(JOIN patterns ":" filter)
  if(DRIFTLAB_SANITIZE AND DRIFTLAB_SANITIZER_SKIPS)
    list(JOIN DRIFTLAB_SANITIZER_SKIPS ":" skips)
    string(APPEND filter "-${skips}")
  endif()

  set(name test_${prefix}_${stem})
  add_test(NAME ${name} COMMAND ${group} --gtest_filter=${filter})
  set(props WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  if(T_LABELS)
    list(APPEND props LABELS ${T_LABELS})
  endif()
  if(T_COST)
    list(APPEND props COST ${T_COST})
  endif()
  if(DRIFTLAB_SANITIZER_ENV)
    list(APPEND props ENVIRONMENT ${DRIFTLAB_SANITIZER_ENV})
  endif()
  set_tests_properties(${name} PROPERTIES ${props})
endfunction()

# The executables of the files given to driftlab_test(), one per folder (and its slow files).
function(driftlab_test_executables)
  get_property(groups GLOBAL PROPERTY DRIFTLAB_TEST_GROUPS)
  list(REMOVE_DUPLICATES groups)
  foreach(group IN LISTS groups)
    foreach(what SOURCES LIBS DEPENDS DEFINES)
      get_property(${what} GLOBAL PROPERTY ${group}_${what})
      list(REMOVE_DUPLICATES ${what})
    endforeach()
    add_executable(${group} ${SOURCES})
    driftlab_warnings(${group})
    target_link_libraries(${group} PRIVATE ${LIBS} driftlab_test_support GTest::gtest
                                           GTest::gtest_main)
    target_compile_definitions(${group} PRIVATE DRIFTLAB_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
                                                DRIFTLAB_BINARY_DIR="${PROJECT_BINARY_DIR}" ${DEFINES})
    set_target_properties(${group} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/tests)
    driftlab_pch(${group} driftlab_test_support)
    if(DEPENDS)
      add_dependencies(${group} ${DEPENDS})
    endif()
    # Every case of the executable is some file's: listing the cases that no file's filter
    # selects must list none (a case that only the executable knows would never run).
    get_property(patterns GLOBAL PROPERTY ${group}_PATTERNS)
    list(JOIN patterns ":" all)
    add_test(NAME ${group}_every_case_has_its_file
             COMMAND ${group} --gtest_list_tests "--gtest_filter=-${all}")
    set_tests_properties(${group}_every_case_has_its_file PROPERTIES
                         FAIL_REGULAR_EXPRESSION "(^|\n)[A-Za-z0-9_/]+\\.(\n|  #)")
  endforeach()
endfunction()
