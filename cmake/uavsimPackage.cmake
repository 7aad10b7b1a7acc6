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
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "multi-UAV simulator: server, missions, worlds and client SDK")
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
include(CPack)
