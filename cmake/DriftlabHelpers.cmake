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

# A GoogleTest executable registered with ctest; the test name is the file stem.
#   driftlab_test(core/se3_test.cpp LIBS driftlab::core [LABELS slow] [COST seconds]
#                 [DEPENDS target...])
# Label `slow`: left out of the sanitizer run (scripts/test --sanitize, in CI), which builds
# them only with DRIFTLAB_BUILD_SLOW_TESTS. DEPENDS: programs the test runs. COST: the file's
# rough run time; ctest -j starts the costliest first, so that a long file does not start last
# on a fresh checkout (ctest has no timings of its own there).
function(driftlab_test source)
  cmake_parse_arguments(T "" "COST" "LIBS;LABELS;DEPENDS" ${ARGN})
  if("slow" IN_LIST T_LABELS AND NOT DRIFTLAB_BUILD_SLOW_TESTS)
    return()
  endif()
  get_filename_component(stem ${source} NAME_WE)
  get_filename_component(dir ${source} DIRECTORY)
  string(REPLACE "/" "_" prefix "${dir}")
  set(target test_${prefix}_${stem})
  add_executable(${target} ${source})
  driftlab_warnings(${target})
  target_link_libraries(${target} PRIVATE ${T_LIBS} driftlab_test_support GTest::gtest GTest::gtest_main)
  target_compile_definitions(${target} PRIVATE
    DRIFTLAB_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    DRIFTLAB_BINARY_DIR="${PROJECT_BINARY_DIR}")
  set_target_properties(${target} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/tests)
  driftlab_pch(${target} driftlab_test_support)
  if(T_DEPENDS)
    add_dependencies(${target} ${T_DEPENDS})
  endif()
  # One ctest test per file: the whole binary in one process. Most files build expensive
  # fixtures once per process (rendered sequences, scenes, runs); a process per gtest case
  # rebuilt them for each case and took twice the suite's time. Run one case with the
  # binary's --gtest_filter.
  add_test(NAME ${target} COMMAND ${target})
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
  set_tests_properties(${target} PROPERTIES ${props})
endfunction()
