# Compiler settings shared by every noctua target.
add_library(noctua_compile_options INTERFACE)
target_compile_options(noctua_compile_options INTERFACE -Wall -Wextra -Wpedantic -Wshadow
                                                        -Wnon-virtual-dtor)
if(NOCTUA_WERROR)
  target_compile_options(noctua_compile_options INTERFACE -Werror)
endif()
if(NOCTUA_SANITIZE)
  target_compile_options(noctua_compile_options INTERFACE -fsanitize=address,undefined
                                                          -fno-omit-frame-pointer
                                                          -fno-sanitize-recover=undefined)
  target_link_options(noctua_compile_options INTERFACE -fsanitize=address,undefined)
endif()

# noctua_add_library(NAME <module> SRCS ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...]
#                    [INTERNAL_HEADERS ...] [NO_INSTALL])
# Creates the static library noctua_<module> with the alias noctua::<module>, installed and
# exported as noctua::<module> with its headers in include/noctua/<module>/ (test headers and
# INTERNAL_HEADERS, those that need a private dependency, stay out). NO_INSTALL: helpers of the
# tests and fuzz targets, which are no part of the package.
function(noctua_add_library)
  cmake_parse_arguments(ARG "NO_INSTALL" "NAME" "SRCS;PUBLIC_DEPS;PRIVATE_DEPS;INTERNAL_HEADERS"
                        ${ARGN})
  set(target noctua_${ARG_NAME})
  add_library(${target} STATIC ${ARG_SRCS})
  add_library(noctua::${ARG_NAME} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${ARG_NAME})
  target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/src>
                                              $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  # Warnings-as-errors and sanitizers are this build's choice, not one to impose on the users of
  # the installed libraries.
  target_link_libraries(${target} PUBLIC ${ARG_PUBLIC_DEPS}
                                  PRIVATE $<BUILD_INTERFACE:noctua_compile_options>
                                          ${ARG_PRIVATE_DEPS})
  if(ARG_NO_INSTALL)
    return()
  endif()
  install(TARGETS ${target} EXPORT noctuaTargets
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
  file(GLOB headers CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.h)
  list(FILTER headers EXCLUDE REGEX "_test[^/]*\\.h$")
  foreach(header IN LISTS ARG_INTERNAL_HEADERS)
    list(REMOVE_ITEM headers ${CMAKE_CURRENT_SOURCE_DIR}/${header})
  endforeach()
  install(FILES ${headers} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/noctua/${ARG_NAME})
  set_property(GLOBAL APPEND PROPERTY NOCTUA_INSTALLED_MODULES ${ARG_NAME})
endfunction()

# noctua_add_test(NAME <name> SRCS ... DEPS ...): one GoogleTest executable registered with ctest.
function(noctua_add_test)
  if(NOT NOCTUA_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "NAME" "SRCS;DEPS" ${ARGN})
  add_executable(${ARG_NAME} ${ARG_SRCS})
  target_link_libraries(${ARG_NAME} PRIVATE noctua_compile_options noctua::testing ${ARG_DEPS}
                                            GTest::gtest GTest::gmock GTest::gtest_main)
  gtest_discover_tests(${ARG_NAME} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
                       DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT 900)
endfunction()
