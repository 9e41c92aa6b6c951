# Arm dynamics and planning (issue 6): inverse dynamics, one forward-dynamics derivative
# evaluation, one full iLQG plan.
ifab_add_bench(arm_bench SOURCES arm_bench.cc DEPS ifab::arm)
