# The fixture of deb_package_tests: a fresh uavsim_VERSION_ARCH.deb in DEB_DIR from BUILD_DIR's CPack
# configuration (cmake/uavsimPackage.cmake).
file(REMOVE_RECURSE ${DEB_DIR})
file(MAKE_DIRECTORY ${DEB_DIR})
execute_process(COMMAND ${CPACK} -G DEB -B ${DEB_DIR} --config ${BUILD_DIR}/CPackConfig.cmake
                RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "cpack -G DEB failed (${result}):\n${out}")
endif()
