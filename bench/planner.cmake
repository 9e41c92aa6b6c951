# Base planning and control (issue 3): the STOMP planner on a typical repositioning maneuver around
# the stack (one thread and all threads), one footprint cost evaluation, one controller update.
ifab_add_bench(planner_bench SOURCES planner_bench.cc DEPS ifab::base_planner_site ifab::base_controller)

# Peer comparison, only where OMPL is installed (it is not a dependency of ifab): the same cases
# planned with OMPL in a Reeds-Shepp state space, for plan time and path length.
find_package(ompl QUIET)
if(ompl_FOUND OR OMPL_FOUND)
  ifab_add_bench(planner_ompl_bench SOURCES planner_ompl_bench.cc DEPS ifab::base_planner_site)
  if(TARGET ompl::ompl)
    target_link_libraries(planner_ompl_bench PRIVATE ompl::ompl)
  else()
    target_include_directories(planner_ompl_bench SYSTEM PRIVATE ${OMPL_INCLUDE_DIRS})
    target_link_libraries(planner_ompl_bench PRIVATE ${OMPL_LIBRARIES})
  endif()
else()
  message(STATUS "OMPL not found: the Reeds-Shepp comparison benchmark (planner_ompl_bench) is skipped")
endif()
