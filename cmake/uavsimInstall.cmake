# Install rules. `cmake --install build --prefix P` gives a complete uavsim under P:
#   P/bin               uavsim (the front door), uavsim-server, the missions' programs and launchers
#                       (mbzirc2017-*, mbzirc2020-*, coverage-*), uavsim-videolog-export, uavsim-plot
#   P/share/uavsim/models  the shipped vehicles, objects, parts and worlds: an installed program finds them
#                       beside its P/bin (common/install_paths.hpp), with no source tree and no --models-dir
#   P/share/doc/uavsim  the README, the docs and the licence
#   P/share/bash-completion/completions/uavsim
#   the client package: find_package(uavsim) (CMAKE_PREFIX_PATH=P) gives uavsim::client, uavsim::common,
#   uavsim::client_gcs and, when vision/ was built, uavsim::vision; pkg-config uavsim-client
#   (PKG_CONFIG_PATH=P/lib/pkgconfig) gives the flags of the client. The build tree exports the same targets
#   (build/uavsimTargets.cmake). The server's headers are not part of it: the server is a program.
# A new program installs itself beside its add_executable (cmake/README.md): every program in P/bin is
# what the front door and the launchers look for.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# the programs: whichever this configuration builds
foreach(program uavsim-server uavsim-videolog-export mbzirc2017-uav mbzirc2017-run mbzirc2020-uav mbzirc2020-gcs
                mbzirc2020-run coverage-agent coverage-gcs coverage-run)
  if(TARGET ${program})
    install(TARGETS ${program} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  endif()
endforeach()
# the run plotter as a program of its own (the launchers and `uavsim plot` call it by that name)
install(PROGRAMS ${PROJECT_SOURCE_DIR}/scripts/plot_run.py DESTINATION ${CMAKE_INSTALL_BINDIR} RENAME uavsim-plot)
# the models, where find_models_dir() looks beside P/bin (kInstalledModelsSubdir)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/models/ DESTINATION ${CMAKE_INSTALL_DATADIR}/uavsim/models)
install(FILES ${PROJECT_SOURCE_DIR}/README.md ${PROJECT_SOURCE_DIR}/LICENSE DESTINATION ${CMAKE_INSTALL_DOCDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR}/docs)

set(uavsim_package_targets uavsim_common)
set_target_properties(uavsim_common PROPERTIES EXPORT_NAME common)
# the loader of OpenCV's codecs (common/media): the client's camera and vision link it; its module
# installs itself under LIBDIR/uavsim
if(TARGET uavsim_media)
  list(APPEND uavsim_package_targets uavsim_media)
  set_target_properties(uavsim_media PROPERTIES EXPORT_NAME media)
endif()
install(DIRECTORY ${PROJECT_SOURCE_DIR}/common/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})

set(UAVSIM_INSTALL_OPENCV_COMPONENTS "")
set(UAVSIM_PC_REQUIRES "eigen3 nlohmann_json")
set(UAVSIM_PC_CFLAGS "")
if(TARGET uavsim_client)
  list(APPEND uavsim_package_targets uavsim_client)
  set_target_properties(uavsim_client PROPERTIES EXPORT_NAME client)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/client_cpp/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  get_target_property(client_defs uavsim_client INTERFACE_COMPILE_DEFINITIONS)
  if("UAVSIM_CLIENT_HAS_CAMERA=1" IN_LIST client_defs)
    list(APPEND UAVSIM_INSTALL_OPENCV_COMPONENTS core imgproc)
    string(APPEND UAVSIM_PC_REQUIRES " opencv4")
    set(UAVSIM_PC_CFLAGS "-DUAVSIM_CLIENT_HAS_CAMERA=1")
    set(UAVSIM_PC_MEDIA_LIBS "-luavsim_media -ldl")
  endif()
endif()
if(TARGET uavsim_client_gcs)
  list(APPEND uavsim_package_targets uavsim_client_gcs)
  set_target_properties(uavsim_client_gcs PROPERTIES EXPORT_NAME client_gcs)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/client_cpp/gcs_link/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endif()
if(TARGET uavsim_vision)
  list(APPEND uavsim_package_targets uavsim_vision)
  set_target_properties(uavsim_vision PROPERTIES EXPORT_NAME vision)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/vision/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  list(APPEND UAVSIM_INSTALL_OPENCV_COMPONENTS core imgproc)
endif()
list(REMOVE_DUPLICATES UAVSIM_INSTALL_OPENCV_COMPONENTS)
if(UAVSIM_INSTALL_OPENCV_COMPONENTS)
  set(UAVSIM_INSTALL_NEEDS_OPENCV TRUE)
  string(REPLACE ";" " " UAVSIM_INSTALL_OPENCV_COMPONENTS "${UAVSIM_INSTALL_OPENCV_COMPONENTS}")
else()
  set(UAVSIM_INSTALL_NEEDS_OPENCV FALSE)
endif()

install(TARGETS ${uavsim_package_targets} EXPORT uavsimTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
set(uavsim_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/uavsim)
install(EXPORT uavsimTargets NAMESPACE uavsim:: DESTINATION ${uavsim_cmake_dir})
export(EXPORT uavsimTargets NAMESPACE uavsim:: FILE ${PROJECT_BINARY_DIR}/uavsimTargets.cmake)

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/uavsimConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/uavsimConfig.cmake INSTALL_DESTINATION ${uavsim_cmake_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/uavsimConfigVersion.cmake VERSION ${PROJECT_VERSION}
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/uavsimConfig.cmake ${PROJECT_BINARY_DIR}/uavsimConfigVersion.cmake
        DESTINATION ${uavsim_cmake_dir})

configure_file(${PROJECT_SOURCE_DIR}/cmake/uavsim-client.pc.in ${PROJECT_BINARY_DIR}/uavsim-client.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/uavsim-client.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
