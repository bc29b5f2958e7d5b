# `cmake --install build --prefix P`: the libraries, the public headers (include/semap/...),
# the semap executable and a CMake package, so that `find_package(semap REQUIRED)` and
# `target_link_libraries(app PRIVATE semap::semap)` work from P.
include(CMakePackageConfigHelpers)

get_property(SEMAP_LIBRARIES GLOBAL PROPERTY SEMAP_LIBRARIES)
install(TARGETS ${SEMAP_LIBRARIES} semap_all
        EXPORT semapTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS semap RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# Public headers only; src/<module>/*.hpp are internal and stay uninstalled.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/semap DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        FILES_MATCHING PATTERN "*.hpp")

set(SEMAP_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/semap)
install(EXPORT semapTargets NAMESPACE semap:: DESTINATION ${SEMAP_CMAKE_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/semapConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/semapConfig.cmake INSTALL_DESTINATION ${SEMAP_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/semapConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/semapConfig.cmake ${PROJECT_BINARY_DIR}/semapConfigVersion.cmake
        DESTINATION ${SEMAP_CMAKE_DIR})
