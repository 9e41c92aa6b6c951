# `make bench-peers` (issue 15): bench/peers.cc prints one table of ifab beside Open3D
# (registration), OMPL (base planning) and KDL (dynamics) on the same inputs. Built only where
# Open3D and OMPL are installed (scripts/install-deps --with-peers); a plain program, not a Google
# Benchmark, so `make bench` does not run it.
find_package(Open3D QUIET)
find_package(ompl QUIET)
if(Open3D_FOUND AND TARGET Open3D::Open3D AND (ompl_FOUND OR OMPL_FOUND))
  add_executable(peers EXCLUDE_FROM_ALL peers.cc)  # built by `make bench-peers` only
  target_link_libraries(peers PRIVATE ifab::experiments ifab::perception ifab::base_planner_site ifab::arm Open3D::Open3D)
  if(TARGET ompl::ompl)
    target_link_libraries(peers PRIVATE ompl::ompl)
  else()
    target_include_directories(peers SYSTEM PRIVATE ${OMPL_INCLUDE_DIRS})
    target_link_libraries(peers PRIVATE ${OMPL_LIBRARIES})
  endif()
  target_compile_definitions(peers PRIVATE IFAB_DATA_DIR="${IFAB_DATA_DIR}")
  set_target_properties(peers PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/bench)
  ifab_set_warnings(peers)
else()
  message(STATUS "Open3D or OMPL not found: `make bench-peers` needs scripts/install-deps --with-peers")
endif()
