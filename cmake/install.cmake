# SPDX-License-Identifier: BSD-3-Clause
# `cmake --install`: the executables (where built), the map library as static libraries with the
# public headers (include/raymap) and an exported CMake package, raymapConfig.cmake, that other
# projects use with find_package(raymap) and target_link_libraries(app raymap::raymap).
include(CMakePackageConfigHelpers)

# raymap::raymap: the map library with every backend this build has, and the public API.
add_library(raymap_library INTERFACE)
set_target_properties(raymap_library PROPERTIES EXPORT_NAME raymap)
target_link_libraries(raymap_library INTERFACE raymap_mapper)
target_compile_features(raymap_library INTERFACE cxx_std_20)
add_library(raymap::raymap ALIAS raymap_library)

# The version header of the public API.
configure_file(${PROJECT_SOURCE_DIR}/cmake/version.hpp.in
  ${PROJECT_BINARY_DIR}/include/raymap/version.hpp @ONLY)
target_include_directories(raymap_core PUBLIC $<BUILD_INTERFACE:${PROJECT_BINARY_DIR}/include>)

# Every static library raymap::raymap links, and the INTERFACE targets they name.
set(raymap_exported raymap_library raymap_mapper raymap_backends raymap_io raymap_heightmap
  raymap_device_staging raymap_map raymap_platform raymap_core raymap_kernels raymap_warnings
  raymap_bag raymap_pipeline raymap_msgs raymap_record raymap_config)
if(RAYMAP_HAVE_OPENCL)
  list(APPEND raymap_exported raymap_opencl)
endif()
if(RAYMAP_HAVE_CUDA)
  list(APPEND raymap_exported raymap_cuda)
endif()
install(TARGETS ${raymap_exported} EXPORT raymapTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/raymap ${PROJECT_BINARY_DIR}/include/raymap
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT dev)

set(raymap_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/raymap)
install(EXPORT raymapTargets NAMESPACE raymap:: DESTINATION ${raymap_cmake_dir} COMPONENT dev)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/raymapConfig.cmake.in
  ${PROJECT_BINARY_DIR}/raymapConfig.cmake INSTALL_DESTINATION ${raymap_cmake_dir})
# 0.x: a minor release may change the API, so only the same major.minor is compatible.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/raymapConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/raymapConfig.cmake ${PROJECT_BINARY_DIR}/raymapConfigVersion.cmake
  DESTINATION ${raymap_cmake_dir} COMPONENT dev)
include(${PROJECT_SOURCE_DIR}/cmake/packaging.cmake)
