# One module = one folder = one target `driftlab_<name>` with alias `driftlab::<name>`.
#   driftlab_module(NAME core SOURCES a.cpp ... DEPS PUBLIC Eigen3::Eigen PRIVATE fmt::fmt)
# A module without sources yet is an INTERFACE target (headers only).
function(driftlab_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic)
  # GCC 12 reports -Wrestrict false positives inside libstdc++'s std::string at -O3
  # (GCC bug 105329, fixed in GCC 13).
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
    target_compile_options(${target} PRIVATE -Wno-restrict)
  endif()
  if(DRIFTLAB_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
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
#   driftlab_test(core/se3_test.cpp LIBS driftlab::core [LABELS slow] [COST seconds])
# Label `slow`: left out of the sanitizer run (scripts/test --sanitize, in CI). COST: the file's
# rough run time; ctest -j starts the costliest first, so that a long file does not start last
# on a fresh checkout (ctest has no timings of its own there).
function(driftlab_test source)
  cmake_parse_arguments(T "" "COST" "LIBS;LABELS" ${ARGN})
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
