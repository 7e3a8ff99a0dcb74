# `cmake --install BUILD --prefix PREFIX`: the driftlab command line, every module's static
# library and headers, and a CMake package, so that a project of a user's builds against it:
#   find_package(driftlab REQUIRED)
#   target_link_libraries(my_vo PRIVATE driftlab::vo)      # or driftlab::app for the whole CLI
# (examples/custom_vo/ is such a project; tests/app/install_test.cpp builds it).
include(CMakePackageConfigHelpers)

get_property(driftlab_modules GLOBAL PROPERTY DRIFTLAB_MODULES)
install(TARGETS ${driftlab_modules} EXPORT driftlabTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS driftlab driftlab-gate RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
foreach(dir core sim scenes dataset vo fusion eval record report pipeline study gate app)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${dir}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/${dir}
          FILES_MATCHING PATTERN "*.hpp" PATTERN "assets" EXCLUDE)
endforeach()
set(driftlab_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/driftlab)
install(EXPORT driftlabTargets NAMESPACE driftlab:: DESTINATION ${driftlab_cmake_dir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/driftlabConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/driftlabConfig.cmake
                              INSTALL_DESTINATION ${driftlab_cmake_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/driftlabConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/driftlabConfig.cmake
              ${PROJECT_BINARY_DIR}/driftlabConfigVersion.cmake
        DESTINATION ${driftlab_cmake_dir})
