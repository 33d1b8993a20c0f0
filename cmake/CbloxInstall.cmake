# Installation in FHS places (`cmake --install build` to CMAKE_INSTALL_PREFIX, /usr/local by
# default; scripts/package.sh configures /usr and builds the DEB with cpack). The systemd units
# get the configured prefix's paths in ExecStart, so install to the prefix you configured:
#   <prefix>/bin/                       cblox-capture, -tracker, -mapper, -viewer, -calib, -ctl, -eval,
#                                       -integrate, -vocabulary; cblox-launch (scripts/,
#                                       with CBLOX_CONFIG_DIR as its default config folder)
#   /etc/cblox/                         capture.yaml, tracker.yaml, mapper.yaml, viewer.yaml, integrate.yaml,
#                                       calibration/ (CBLOX_CONFIG_DIR; /etc even for /usr/local,
#                                       where operators look for it)
#   <prefix>/share/cblox/               cblox_orb.vocab (the place-recognition vocabulary),
#                                       examples/ (capture configs for real cameras; tracker
#                                       settings for street drives)
#   <prefix>/share/cblox/viewer/        cblox-viewer's page (index.html, viewer.js, viewer.css;
#                                       three.js comes from Debian's libjs-three)
#   <prefix>/share/java/                cblox_lcmtypes.jar (for lcm-spy)
#   <prefix>/lib/systemd/system/        cblox-{capture,tracker,mapper,viewer}.service,
#                                       cblox.target
#   <prefix>/lib/sysctl.d/              60-cblox-lcm.conf (socket buffers for LCM images)
include(GNUInstallDirs)
set(CBLOX_CONFIG_DIR "/etc/cblox" CACHE PATH "Where the installed YAML configuration lives")
set(CBLOX_BINDIR "${CMAKE_INSTALL_FULL_BINDIR}")
set(CBLOX_DATADIR "${CMAKE_INSTALL_FULL_DATADIR}/cblox")

install(TARGETS cblox-capture cblox-tracker cblox-mapper cblox-viewer cblox-calib cblox-ctl cblox-eval cblox-integrate
  cblox-vocabulary cblox-map-verify RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# The launcher: its default config folder becomes CBLOX_CONFIG_DIR (it finds the binaries
# next to itself).
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS
  ${PROJECT_SOURCE_DIR}/scripts/cblox-launch)
file(READ ${PROJECT_SOURCE_DIR}/scripts/cblox-launch cblox_launch_text)
string(REPLACE "\ninstalled_config_dir=/etc/cblox\n" "\ninstalled_config_dir=${CBLOX_CONFIG_DIR}\n"
  cblox_launch_text "${cblox_launch_text}")
file(WRITE ${CMAKE_BINARY_DIR}/scripts/cblox-launch "${cblox_launch_text}")
install(PROGRAMS ${CMAKE_BINARY_DIR}/scripts/cblox-launch DESTINATION ${CMAKE_INSTALL_BINDIR})
install(FILES config/capture.yaml config/tracker.yaml config/mapper.yaml config/viewer.yaml
  config/integrate.yaml DESTINATION ${CBLOX_CONFIG_DIR})
install(FILES daemon/viewer/web/index.html daemon/viewer/web/viewer.js daemon/viewer/web/viewer.css
  DESTINATION ${CMAKE_INSTALL_DATADIR}/cblox/viewer)
install(DIRECTORY config/calibration/ DESTINATION ${CBLOX_CONFIG_DIR}/calibration)
install(DIRECTORY config/examples/ DESTINATION ${CMAKE_INSTALL_DATADIR}/cblox/examples)
if(CBLOX_BUILD_VOCABULARY)
  install(FILES ${CBLOX_VOCABULARY_FILE} DESTINATION ${CMAKE_INSTALL_DATADIR}/cblox)
endif()
if(CBLOX_LCM_JAR)
  install(FILES ${CBLOX_LCM_JAR} DESTINATION ${CMAKE_INSTALL_DATADIR}/java)
endif()

# systemd units: the installed paths are written into ExecStart.
foreach(unit cblox-capture cblox-tracker cblox-mapper cblox-viewer)
  configure_file(config/systemd/${unit}.service.in ${CMAKE_BINARY_DIR}/systemd/${unit}.service
    @ONLY)
  install(FILES ${CMAKE_BINARY_DIR}/systemd/${unit}.service DESTINATION lib/systemd/system)
endforeach()
configure_file(config/systemd/cblox.target ${CMAKE_BINARY_DIR}/systemd/cblox.target COPYONLY)
install(FILES ${CMAKE_BINARY_DIR}/systemd/cblox.target DESTINATION lib/systemd/system)
install(FILES config/sysctl/60-cblox-lcm.conf DESTINATION lib/sysctl.d)

# Debian package: cpack -G DEB in a build folder configured with prefix /usr
# (scripts/package.sh).
set(CPACK_GENERATOR "DEB")
set(CPACK_PACKAGE_NAME "cblox")
set(CPACK_PACKAGE_VENDOR "cblox")
set(CPACK_PACKAGE_CONTACT "cblox developers <cblox@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
  "Consistent, bounded dense TSDF mapping for small robots (capture, tracker, mapper over LCM)")
set(CPACK_PACKAGING_INSTALL_PREFIX "${CMAKE_INSTALL_PREFIX}")
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION "science")
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# libjs-three: the viewer page draws with it (not found by shlibdeps: it is JavaScript).
set(CPACK_DEBIAN_PACKAGE_DEPENDS "liblcm-bin, libjs-three")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "liblcm-java, openjdk-17-jre, libjchart2d-java")
# /etc/cblox is the operator's: dpkg keeps local edits on upgrade (conffiles).
set(cblox_conffiles "")
foreach(f capture.yaml tracker.yaml mapper.yaml viewer.yaml integrate.yaml)
  string(APPEND cblox_conffiles "${CBLOX_CONFIG_DIR}/${f}\n")
endforeach()
file(GLOB cblox_calibrations RELATIVE ${PROJECT_SOURCE_DIR}/config/calibration
  ${PROJECT_SOURCE_DIR}/config/calibration/*)
foreach(f IN LISTS cblox_calibrations)
  string(APPEND cblox_conffiles "${CBLOX_CONFIG_DIR}/calibration/${f}\n")
endforeach()
file(WRITE ${CMAKE_BINARY_DIR}/debian/conffiles "${cblox_conffiles}")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA "${CMAKE_BINARY_DIR}/debian/conffiles")
include(CPack)
