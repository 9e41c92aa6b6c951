# Fails if an algorithm module includes a simulator header, if its link line (as CMake generated
# it) names the sim or experiments library, or if an algorithm-side loader opens the simulator's
# parameters: a path under data/sim/, a `sim:` section of a config, or the as-built tolerances
# (the stack reads design files only, DESIGN.md "The world and the model"), or if an algorithm
# module's own (non-test) code opens a file for writing: algorithm modules write no files
# (issue 12); experiments/ and app/ save their results. Run by ctest.
set(algorithms core msgs model hal sync base arm perception sequencer)
set(bad "")
foreach(m IN LISTS algorithms)
  file(GLOB_RECURSE sources "${SOURCE_DIR}/src/ifab/${m}/*.h" "${SOURCE_DIR}/src/ifab/${m}/*.cc")
  foreach(f IN LISTS sources)
    file(STRINGS "${f}" hits REGEX "#include *[<\"]ifab/(sim|experiments)/")
    if(hits)
      list(APPEND bad "${f} includes ${hits}")
    endif()
    # Simulator parameters: data/sim/ paths, a "sim" config key, the as-built tolerances.
    file(STRINGS "${f}" opens REGEX "[\"/]sim/|\\[ *\"sim\" *\\]|(Find|Has|Get[<>a-z:]*)\\( *\"sim\"|as_built")
    if(opens)
      list(APPEND bad "${f} opens the simulator's parameters: ${opens}")
    endif()
    # Writing files: an output stream or C file opened by path (tests and their helpers may).
    if(NOT f MATCHES "/(test|testing)/")
      file(STRINGS "${f}" writes REGEX "std::(o|)fstream[ >]|fopen *\\(|FILE *\\*")
      if(writes)
        list(APPEND bad "${f} writes a file: ${writes}")
      endif()
    endif()
  endforeach()
  # The transitive link closure of the module's library, written at configure time.
  set(links_file "${BINARY_DIR}/layering/ifab_${m}.links")
  if(EXISTS "${links_file}")
    file(READ "${links_file}" links)
    if(links MATCHES "ifab_(sim|experiments)")
      list(APPEND bad "ifab_${m} links the simulator: ${links}")
    endif()
  elseif(EXISTS "${SOURCE_DIR}/src/ifab/${m}/CMakeLists.txt")
    list(APPEND bad "no link record for ifab_${m} (reconfigure the build)")
  endif()
endforeach()
if(bad)
  message(FATAL_ERROR "Layering violations (algorithm modules must not see the simulator, nor write files):\n${bad}")
endif()
message(STATUS "layering ok: no algorithm module includes or links sim/ or experiments/, or writes a file")
