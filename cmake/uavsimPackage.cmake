# The Debian package: `cpack -G DEB` in the build folder (or `cmake --build build --target package`) makes
# uavsim_VERSION_ARCH.deb of the whole install (cmake/uavsimInstall.cmake) under /usr.
# Depends is computed from the binaries (dpkg-shlibdeps: which Debian packages hold the shared libraries
# they link), not listed by hand. What the programs only run or open at run time, and can do without,
# is recommended: ffmpeg (videos: without it the recorder falls back to OpenCV's writer),
# python3-matplotlib (uavsim-plot, the launchers' pictures), and libegl1 with Mesa's EGL (--gl egl|auto
# opens libEGL.so.1 itself; the default, OSMesa, is linked).
set(CPACK_PACKAGE_NAME uavsim)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "uavsim maintainers <uavsim@localhost>")
set(uavsim_package_summary "multi-UAV simulator: server, missions, worlds and client SDK")
set(CPACK_PACKAGE_DESCRIPTION "uavsim simulates multirotors on MuJoCo with an ArduCopter-like flight controller \
on MAVLink 2 and rendered cameras. The package holds uavsim-server, the MBZIRC 2017, MBZIRC 2020 and \
coverage missions with their launchers, the shipped models and worlds, the uavsim front door, and the \
C++ client SDK (headers, static libraries, CMake and pkg-config files).")
set(CPACK_RESOURCE_FILE_LICENSE ${PROJECT_SOURCE_DIR}/LICENSE)
set(CPACK_GENERATOR DEB)
set(CPACK_SOURCE_GENERATOR "")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "ffmpeg, python3-matplotlib, libegl1, libegl-mesa0")

# One package per install component: `uavsim` (everything above, Apache-2.0) and, when ns-3 is
# installed at build time, `uavsim-ns3-radio`, the ns3 radio backend's helper program. ns-3 is
# GPL-2.0-only: its program is a package of its own, with its own licence and source, so the
# uavsim package neither holds GPL code nor depends on ns-3; `apt install ./uavsim-ns3-radio_*.deb`
# adds the backend to an installed uavsim.
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_GROUPING IGNORE)
set(CPACK_COMPONENTS_ALL uavsim)
set(CPACK_DEBIAN_UAVSIM_PACKAGE_NAME uavsim)
# each package's description is its summary line, then the long text; no CPACK_PACKAGE_DESCRIPTION_
# SUMMARY, which CPack would put on top of both packages' descriptions
set(CPACK_DEBIAN_UAVSIM_DESCRIPTION "${uavsim_package_summary}\n${CPACK_PACKAGE_DESCRIPTION}")
if(TARGET uavsim-ns3-radio)
  list(APPEND CPACK_COMPONENTS_ALL ns3radio)
  set(CPACK_DEBIAN_NS3RADIO_PACKAGE_NAME uavsim-ns3-radio)
  set(CPACK_COMPONENT_NS3RADIO_DEPENDS uavsim)  # Depends: uavsim (= this version)
  set(CPACK_DEBIAN_ENABLE_COMPONENT_DEPENDS ON)
  set(CPACK_DEBIAN_NS3RADIO_PACKAGE_RECOMMENDS "")
  set(CPACK_DEBIAN_NS3RADIO_PACKAGE_SECTION net)
  set(CPACK_DEBIAN_NS3RADIO_DESCRIPTION "uavsim's ns3 radio backend (GPL-2.0-only)\n\
uavsim-ns3-radio runs the vehicles' air-to-air radio of uavsim-server --radio-backend ns3 on ns-3's \
IEEE 802.15.4 model: CSMA-CA contention, hidden terminals, capture and SINR errors. It is a separate \
program, licensed GPL-2.0-only like ns-3, which the server starts and talks to over a socket pair.")
endif()
include(CPack)
