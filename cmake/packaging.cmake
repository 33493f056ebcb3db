# SPDX-License-Identifier: BSD-3-Clause
# The Debian package: `cpack -G DEB` in a Release build directory gives raymap_<version>_<arch>.deb
# with raymap, raymapd, raymap-load (and its scenes in /usr/share/raymap/scenes), the systemd unit, /etc/raymapd/{raymapd.yaml,cyclonedds.xml} (conffiles),
# /usr/share/raymap/cyclonedds-realtime-receive.xml, the static libraries, include/raymap and the
# CMake package, installed under /usr. Depends: is computed from the executables' shared libraries (dpkg-shlibdeps, from dpkg-dev), plus adduser
# for the raymapd system user that postinst creates. docs/packaging.md.
if(RAYMAP_BUILD_SERVICE)
  install(CODE "set(RAYMAP_SOURCE_DIR \"${PROJECT_SOURCE_DIR}\")
set(RAYMAP_BINARY_DIR \"${PROJECT_BINARY_DIR}\")
set(RAYMAP_BINDIR \"${CMAKE_INSTALL_BINDIR}\")" COMPONENT runtime)
  install(SCRIPT ${PROJECT_SOURCE_DIR}/cmake/install_service_files.cmake COMPONENT runtime)
  # For a planner taking the height maps (not for raymapd): Cyclone's receive path at real-time
  # priority (docs/raymapd.md, "On the planner's side").
  install(FILES ${PROJECT_SOURCE_DIR}/config/cyclonedds-realtime-receive.xml
    DESTINATION ${CMAKE_INSTALL_DATADIR}/raymap COMPONENT runtime)
endif()

set(CPACK_PACKAGE_NAME raymap)
set(CPACK_PACKAGE_VENDOR "raymap")
set(CPACK_PACKAGE_CONTACT "raymap maintainers <raymap@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
  "real-time 3D occupancy and 2.5D height maps from lidar: service, tools and C++ library")
set(CPACK_PACKAGE_DESCRIPTION "raymap integrates lidar rays into 3D occupancy maps on the CPU, \
OpenCL or CUDA and publishes robot-centric height maps over DDS (raymapd, a systemd service). \
The raymap command line builds maps from files and rosbag2 bags; the C++ library \
(find_package(raymap), raymap::Mapper) embeds the mapper in other programs, and the Python \
module (import raymap, with NumPy) scripts it.")
set(CPACK_GENERATOR DEB)
# Install as `cmake --install --prefix /usr` would, into the package's staging tree (DESTDIR), so
# that the install-time paths (/etc/raymapd, the unit's ExecStart) are the final ones.
set(CPACK_SET_DESTDIR ON)
set(CPACK_INSTALL_PREFIX /usr)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# CPack asks the build host's dpkg for the architecture: a cross build names its target's
# (docs/arm64.md: raymap_<version>_arm64.deb, its Depends: from the arm64 libraries it links).
if(CMAKE_CROSSCOMPILING AND CMAKE_SYSTEM_PROCESSOR MATCHES "^(aarch64|arm64)$")
  set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE arm64)
endif()
set(CPACK_DEBIAN_PACKAGE_DEPENDS "adduser")
# The Python module (/usr/lib/python3/dist-packages/raymap, where built) needs Debian's python3
# and NumPy; the service and the command line do not, so they are recommended, not required.
if(RAYMAP_HAVE_PYTHON)
  set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "python3 (>= 3.11), python3 (<< 3.12), python3-numpy")
endif()
# Building against the installed library needs Eigen, zlib, zstd and libpng headers (its static
# libraries link them), for bags yaml-cpp's, lz4's, SQLite's and Boost's, and OpenCL's where the
# package was built with OpenCL.
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "libeigen3-dev, zlib1g-dev, libzstd-dev, libpng-dev, libyaml-cpp-dev, liblz4-dev, libsqlite3-dev, libboost-dev, ocl-icd-opencl-dev, pocl-opencl-icd")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
  ${PROJECT_SOURCE_DIR}/cmake/debian/postinst
  ${PROJECT_SOURCE_DIR}/cmake/debian/prerm
  ${PROJECT_SOURCE_DIR}/cmake/debian/postrm
  ${PROJECT_SOURCE_DIR}/cmake/debian/conffiles)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
include(CPack)
