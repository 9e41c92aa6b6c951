# Registration of one arm sweep of the brick stack and the floor (about 20k points), the paper's
# way (eq. 7) and with the ray residual; and a six-sweep laser calibration.
ifab_add_bench(perception_bench SOURCES perception_bench.cc DEPS ifab::perception)

# Peer comparison, only where Open3D is installed (it is not a dependency of ifab): the same
# sweep registered with Open3D's point-to-plane ICP against a densely sampled model.
find_package(Open3D QUIET)
if(Open3D_FOUND AND TARGET Open3D::Open3D)
  ifab_add_bench(perception_open3d_bench SOURCES perception_open3d_bench.cc DEPS ifab::perception Open3D::Open3D)
else()
  message(STATUS "Open3D not found: the point-to-plane ICP comparison benchmark (perception_open3d_bench) is skipped")
endif()
