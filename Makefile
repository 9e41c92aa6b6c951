# ifab: the two commands a user needs are `make run` and `make test`.
# Each installs what is missing (scripts/install-deps), configures and builds first.
BUILD_DIR ?= build
JOBS      ?= 2
CMAKE_ARGS ?=
RUN_ARGS  ?=
# test-sanitize: the ctest suite with AddressSanitizer + UndefinedBehaviorSanitizer
# (IFAB_SANITIZE; gcc, the compiler of `make test`, so the tests see the same floating point and the
# same draws; -O1 with line tables only, which compiles the instrumented code about a fifth faster than -O2 and computes the same floating point (no fast-math at either), no benchmarks, build-sanitize/; without the whole-mission
# tests, ctest label "mission", which `make test` runs; and six tests that repeat what a cheaper
# test runs skip themselves there, each naming that test: src/ifab/core/testing/sanitized.h).
# Stack-use-after-return is not checked (ASan's default; with it on, every call of the Eigen-heavy
# loops went through ASan's fake stack: EstimateLog.MitCsail 99 s -> 72 s without it, and CI went
# over 30 min). Any UB report ends its
# program (-fno-sanitize-recover=all), failing the test. The fuzz harnesses replay their corpora
# there. fuzz: libFuzzer needs clang, and coverage everywhere (IFAB_FUZZ), in its own folder
# (build-fuzz/), so the sanitized test build stays free of the coverage instrumentation that made
# it several times slower.
SANITIZE_DIR ?= build-sanitize
FUZZ_DIR     ?= build-fuzz
FUZZ_SECONDS ?= 60
FUZZ_ARGS    ?=

PEERS_ARGS ?=

.PHONY: all deps fuzz-deps configure build bundle run test bench bench-peers clean test-sanitize fuzz fuzz-build

all: build

deps:
	@scripts/install-deps

$(BUILD_DIR)/build.ninja: | deps
	cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=Release $(CMAKE_ARGS)

configure: deps $(BUILD_DIR)/build.ninja

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

# The report page's script (web/ with three.js and plotly.js, bundled by esbuild); `build` makes
# it too, since ifab inlines it into every report.html.
bundle: configure
	cmake --build $(BUILD_DIR) --target report_bundle

run: build
	$(BUILD_DIR)/bin/ifab run $(RUN_ARGS)

test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS) --timeout 900

bench: build
	@for b in $(BUILD_DIR)/bench/*_bench; do echo "== $$b"; $$b --benchmark_min_time=0.2 || exit 1; done

$(SANITIZE_DIR)/build.ninja: | deps
	cmake -S . -B $(SANITIZE_DIR) -G Ninja -DCMAKE_BUILD_TYPE=Release -DIFAB_SANITIZE=ON \
	  -DIFAB_BUILD_BENCHMARKS=OFF "-DCMAKE_CXX_FLAGS_RELEASE=-O1 -g1 -DNDEBUG" $(CMAKE_ARGS)

test-sanitize: $(SANITIZE_DIR)/build.ninja
	cmake --build $(SANITIZE_DIR) -j $(JOBS)
	cd $(SANITIZE_DIR) && ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=0 \
	  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  ctest --output-on-failure -j $(JOBS) --timeout 1800 --label-exclude mission

fuzz-deps:
	@scripts/install-deps --with-fuzz

$(FUZZ_DIR)/build.ninja: | deps fuzz-deps
	cmake -S . -B $(FUZZ_DIR) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DCMAKE_CXX_COMPILER=clang++ -DIFAB_BUILD_BENCHMARKS=OFF -DIFAB_FUZZ=ON -DBUILD_TESTING=OFF \
	  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -gline-tables-only" $(CMAKE_ARGS)

fuzz-build: $(FUZZ_DIR)/build.ninja
	cmake --build $(FUZZ_DIR) -j $(JOBS) --target fuzzers

# Each harness for FUZZ_SECONDS from its corpus (new inputs are kept in $(FUZZ_DIR)/fuzz/corpus/).
fuzz: fuzz-build
	@scripts/run-fuzzers $(FUZZ_DIR) $(FUZZ_SECONDS) $(FUZZ_ARGS)

# ifab beside Open3D, OMPL and KDL on the same inputs (bench/peers.cc): one table. Installs the
# peers first (they are not dependencies of ifab) and re-configures so CMake finds them.
bench-peers: build
	@scripts/install-deps --with-peers
	cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=Release $(CMAKE_ARGS)
	cmake --build $(BUILD_DIR) -j $(JOBS) --target peers
	$(BUILD_DIR)/bench/peers $(PEERS_ARGS)

clean:
	rm -rf $(BUILD_DIR) $(SANITIZE_DIR) $(FUZZ_DIR)
