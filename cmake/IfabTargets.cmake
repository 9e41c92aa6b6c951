# Helpers shared by every ifab target: warnings, module libraries, tests.

# One place sets the warnings for every target (KISS-ICP's habit); -Werror with IFAB_WERROR.
function(ifab_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic
                         -Wnon-virtual-dtor -Wcast-align -Wunused -Woverloaded-virtual
                         -Wno-deprecated-copy)
  # GCC's local-only shadowing check; clang (the sanitizer and fuzz builds) has no such option.
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    target_compile_options(${target} PRIVATE -Wshadow=local)
  endif()
  if(IFAB_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# ifab_add_module(NAME SOURCES ... DEPS ...): library ifab_NAME with alias ifab::NAME.
# Headers are included as "ifab/NAME/x.h" from src/.
function(ifab_add_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  set(target ifab_${name})
  if(ARG_SOURCES)
    add_library(${target} STATIC ${ARG_SOURCES})
    target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR}/src)
    target_link_libraries(${target} PUBLIC ${ARG_DEPS})
    ifab_set_warnings(${target})
  else()
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE ${PROJECT_SOURCE_DIR}/src)
    target_link_libraries(${target} INTERFACE ${ARG_DEPS})
  endif()
  add_library(ifab::${name} ALIAS ${target})
endfunction()

# ifab_add_test(NAME SOURCES ... DEPS ... [LABELS ...] [COST seconds]): one GoogleTest program,
# tests registered with ctest. COST (the program's longest test under the sanitizers, roughly) lets
# `ctest -j` start the long programs first on a fresh clone, which has no timings of its own yet:
# started last, one 60 s test left a core idle for a minute of CI.
function(ifab_add_test name)
  if(NOT BUILD_TESTING)
    return()
  endif()
  cmake_parse_arguments(ARG "" "COST" "SOURCES;DEPS;LABELS" ${ARGN})
  # An empty LABELS value would swallow the next key when gtest_discover_tests writes the
  # properties out, so each is passed only when set.
  set(props)
  if(ARG_LABELS)
    list(APPEND props LABELS "${ARG_LABELS}")
  endif()
  if(ARG_COST)
    list(APPEND props COST ${ARG_COST})
  endif()
  if(props)
    list(PREPEND props PROPERTIES)
  endif()
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gtest_main GTest::gmock)
  target_compile_definitions(${name} PRIVATE IFAB_DATA_DIR="${IFAB_DATA_DIR}"
                             IFAB_TEST_DATA_DIR="${CMAKE_CURRENT_SOURCE_DIR}/data"
                             IFAB_SHARED_DIR="${PROJECT_SOURCE_DIR}/../shared")
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/tests)
  ifab_set_warnings(${name})
  gtest_discover_tests(${name} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
                       DISCOVERY_TIMEOUT 60 ${props})
endfunction()

# Collect every library a target links, directly or through other targets.
function(_ifab_collect_links target out)
  set(seen ${${out}})
  if(NOT TARGET ${target})
    set(${out} ${seen} PARENT_SCOPE)
    return()
  endif()
  get_target_property(aliased ${target} ALIASED_TARGET)
  if(aliased)
    set(target ${aliased})
  endif()
  get_target_property(type ${target} TYPE)
  set(links)
  if(NOT type STREQUAL "INTERFACE_LIBRARY")
    get_target_property(l ${target} LINK_LIBRARIES)
    if(l)
      list(APPEND links ${l})
    endif()
  endif()
  get_target_property(il ${target} INTERFACE_LINK_LIBRARIES)
  if(il)
    list(APPEND links ${il})
  endif()
  foreach(dep IN LISTS links)
    string(REPLACE "ifab::" "ifab_" dep "${dep}")
    if(NOT dep IN_LIST seen)
      list(APPEND seen ${dep})
      _ifab_collect_links(${dep} seen)
    endif()
  endforeach()
  set(${out} ${seen} PARENT_SCOPE)
endfunction()

# The one rule that keeps results honest: no algorithm module links the simulator; and none links
# a JSON library (file formats live in experiments/ and app/).
# Fails the configure step if any algorithm target reaches a forbidden target.
function(ifab_check_layering)
  cmake_parse_arguments(ARG "" "" "ALGORITHMS;FORBIDDEN" ${ARGN})
  foreach(t IN LISTS ARG_ALGORITHMS)
    if(TARGET ${t})
      set(all)
      _ifab_collect_links(${t} all)
      # Written for the layering test (tests/check_layering.cmake) to read back.
      file(WRITE ${CMAKE_BINARY_DIR}/layering/${t}.links "${all}")
      foreach(f IN LISTS ARG_FORBIDDEN)
        if(f IN_LIST all)
          message(FATAL_ERROR "Layering violation: algorithm target ${t} links ${f}. "
                              "Only experiments and app may see the simulator or a JSON library (DESIGN.md).")
        endif()
      endforeach()
    endif()
  endforeach()
endfunction()
