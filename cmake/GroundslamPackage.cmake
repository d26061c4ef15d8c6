# The installed package: `cmake --install BUILD --prefix P` puts the static libraries, headers, the
# `groundslam` program and the shipped data (vocabulary, default configuration, report script) under P, with a
# CMake package so that another project can `find_package(groundslam REQUIRED)` and link `groundslam::groundslam`.
include(CMakePackageConfigHelpers)

# The umbrella target: every library of the package (its header: groundslam/groundslam.hpp).
add_library(groundslam_library INTERFACE)
set_target_properties(groundslam_library PROPERTIES EXPORT_NAME groundslam)
target_link_libraries(groundslam_library INTERFACE ${GROUNDSLAM_LIBRARIES})
add_library(groundslam::groundslam ALIAS groundslam_library)

install(TARGETS ${GROUNDSLAM_LIBRARIES} groundslam_library EXPORT groundslamTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/cpp/groundslam DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} FILES_MATCHING PATTERN "*.hpp")
install(FILES ${PROJECT_SOURCE_DIR}/config/vocabulary/ground.gslmvoc DESTINATION ${CMAKE_INSTALL_DATADIR}/groundslam/vocabulary)
install(FILES ${PROJECT_SOURCE_DIR}/config/default.yaml DESTINATION ${CMAKE_INSTALL_DATADIR}/groundslam)
install(FILES ${PROJECT_SOURCE_DIR}/python/groundslam_report.py DESTINATION ${CMAKE_INSTALL_DATADIR}/groundslam/python)

set(GROUNDSLAM_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/groundslam)
install(EXPORT groundslamTargets NAMESPACE groundslam:: DESTINATION ${GROUNDSLAM_CMAKE_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/groundslamConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/groundslamConfig.cmake INSTALL_DESTINATION ${GROUNDSLAM_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/groundslamConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/groundslamConfig.cmake ${PROJECT_BINARY_DIR}/groundslamConfigVersion.cmake
        DESTINATION ${GROUNDSLAM_CMAKE_DIR})
