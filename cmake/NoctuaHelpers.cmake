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

# noctua_add_library(NAME <module> SRCS ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...])
# Creates the static library noctua_<module> with the alias noctua::<module>.
function(noctua_add_library)
  cmake_parse_arguments(ARG "" "NAME" "SRCS;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  set(target noctua_${ARG_NAME})
  add_library(${target} STATIC ${ARG_SRCS})
  add_library(noctua::${ARG_NAME} ALIAS ${target})
  target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/src>)
  target_link_libraries(${target} PUBLIC ${ARG_PUBLIC_DEPS}
                                  PRIVATE noctua_compile_options ${ARG_PRIVATE_DEPS})
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
