# Installation of the libraries as a CMake package (find_package(noctua CONFIG)), a pkg-config
# file and a Debian package (cpack -G DEB). Included after every module has added its library.
include(CMakePackageConfigHelpers)

set(noctua_summary
    "Feature points for visual SLAM in low light and dynamic scenes, with an RGB-D SLAM")

get_property(noctua_modules GLOBAL PROPERTY NOCTUA_INSTALLED_MODULES)

# noctua::noctua: every installed module at once.
add_library(noctua_all INTERFACE)
add_library(noctua::noctua ALIAS noctua_all)
set_target_properties(noctua_all PROPERTIES EXPORT_NAME noctua)
foreach(module IN LISTS noctua_modules)
  target_link_libraries(noctua_all INTERFACE noctua::${module})
endforeach()
install(TARGETS noctua_all EXPORT noctuaTargets)

set(noctua_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/noctua)
install(EXPORT noctuaTargets NAMESPACE noctua:: DESTINATION ${noctua_cmake_dir})
configure_package_config_file(cmake/noctuaConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/package/noctuaConfig.cmake
                              INSTALL_DESTINATION ${noctua_cmake_dir})
# 0.x: a new minor version may change the interface.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/package/noctuaConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/package/noctuaConfig.cmake
              ${PROJECT_BINARY_DIR}/package/noctuaConfigVersion.cmake
        DESTINATION ${noctua_cmake_dir})

# pkg-config: the libraries are static, so a module must come before the modules it uses. The
# modules are added in that order (src/noctua/CMakeLists.txt), so the reverse of it is one.
set(noctua_pc_libs "")
foreach(module IN LISTS noctua_modules)
  set(noctua_pc_libs "-lnoctua_${module} ${noctua_pc_libs}")
endforeach()
string(STRIP "${noctua_pc_libs}" noctua_pc_libs)
# The prefix is found from the .pc file's own place, so that an install moved elsewhere (or made
# with cmake --install --prefix) still points at itself.
file(RELATIVE_PATH noctua_pc_to_prefix /prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig /prefix)
string(REGEX REPLACE "/$" "" noctua_pc_to_prefix "${noctua_pc_to_prefix}")
configure_file(cmake/noctua.pc.in ${PROJECT_BINARY_DIR}/package/noctua.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/package/noctua.pc
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

# The camera presets, for the examples and for running the installed command on TUM/OpenLORIS.
install(DIRECTORY config/ DESTINATION ${CMAKE_INSTALL_DATADIR}/noctua/config
        FILES_MATCHING PATTERN "*.yaml")
# The default place-recognition vocabulary, found by place::FindDefaultVocabulary.
install(DIRECTORY data/vocabulary/ DESTINATION ${CMAKE_INSTALL_DATADIR}/noctua/vocabulary
        FILES_MATCHING PATTERN "*.vocab")
install(FILES LICENSE README.md DESTINATION ${CMAKE_INSTALL_DOCDIR})

set(CPACK_PACKAGE_NAME noctua)
set(CPACK_PACKAGE_VENDOR noctua)
set(CPACK_PACKAGE_CONTACT "noctua maintainers <noctua@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY ${noctua_summary})
set(CPACK_RESOURCE_FILE_LICENSE ${PROJECT_SOURCE_DIR}/LICENSE)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION libdevel)
# The command's shared libraries come from dpkg-shlibdeps; the static libraries and headers need
# the development packages of what they use, which no tool can find.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS
    "libopencv-dev (>= 4.6), libeigen3-dev (>= 3.4), libceres-dev (>= 2.1), libyaml-cpp-dev, \
nlohmann-json3-dev (>= 3.10), libspdlog-dev, libfftw3-dev")
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "cmake, pkg-config")
include(CPack)
