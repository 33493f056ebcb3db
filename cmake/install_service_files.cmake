# SPDX-License-Identifier: BSD-3-Clause
# Installs raymapd's systemd unit and default configuration (run by `cmake --install` and by
# CPack; see cmake/packaging.cmake). Paths are decided at install time: the configuration goes to
# /etc/raymapd for the prefix /usr (the Debian package), else to PREFIX/etc/raymapd; the unit to
# PREFIX/lib/systemd/system with ExecStart naming PREFIX/BINDIR/raymapd. An existing
# configuration is never overwritten (the package marks it a conffile instead).
# Expects RAYMAP_SOURCE_DIR, RAYMAP_BINARY_DIR and RAYMAP_BINDIR (set by install(CODE)).
if(CMAKE_INSTALL_PREFIX STREQUAL "/usr")
  set(raymap_etc "/etc/raymapd")
else()
  set(raymap_etc "${CMAKE_INSTALL_PREFIX}/etc/raymapd")
endif()
foreach(pair "config/cpu.yaml:raymapd.yaml" "config/cyclonedds-loopback.xml:cyclonedds.xml")
  string(REPLACE ":" ";" pair "${pair}")
  list(GET pair 0 from)
  list(GET pair 1 to)
  if(EXISTS "$ENV{DESTDIR}${raymap_etc}/${to}")
    message(STATUS "Keeping: $ENV{DESTDIR}${raymap_etc}/${to}")
  else()
    file(INSTALL "${RAYMAP_SOURCE_DIR}/${from}" DESTINATION "${raymap_etc}" RENAME "${to}"
      PERMISSIONS OWNER_READ OWNER_WRITE GROUP_READ WORLD_READ)
  endif()
endforeach()
file(READ "${RAYMAP_SOURCE_DIR}/systemd/raymapd.service" raymap_unit)
string(REPLACE "/usr/local/bin/raymapd" "${CMAKE_INSTALL_PREFIX}/${RAYMAP_BINDIR}/raymapd"
  raymap_unit "${raymap_unit}")
string(REPLACE "/etc/raymapd/" "${raymap_etc}/" raymap_unit "${raymap_unit}")
file(WRITE "${RAYMAP_BINARY_DIR}/raymapd.service" "${raymap_unit}")
file(INSTALL "${RAYMAP_BINARY_DIR}/raymapd.service"
  DESTINATION "${CMAKE_INSTALL_PREFIX}/lib/systemd/system"
  PERMISSIONS OWNER_READ OWNER_WRITE GROUP_READ WORLD_READ)
