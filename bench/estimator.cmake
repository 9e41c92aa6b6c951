# Base state estimator: one update (a 1081-beam scan against three reference scans).
ifab_add_bench(estimator_bench SOURCES estimator_bench.cc DEPS ifab::base_estimator)
