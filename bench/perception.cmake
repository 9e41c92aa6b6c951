# Registration of one arm sweep of the brick stack and the floor (about 20k points), the paper's
# way (eq. 7) and with the ray residual; and a six-sweep laser calibration. Open3D's ICP would be
# the peer to compare with (find_package(Open3D QUIET)); it is not installed here, so no
# side-by-side is built.
ifab_add_bench(perception_bench SOURCES perception_bench.cc DEPS ifab::perception)
