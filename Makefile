# ifab: the two commands a user needs are `make run` and `make test`.
# Each installs what is missing (scripts/install-deps), configures and builds first.
BUILD_DIR ?= build
JOBS      ?= 2
CMAKE_ARGS ?=
RUN_ARGS  ?=

.PHONY: all deps configure build bundle run test bench clean

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

clean:
	rm -rf $(BUILD_DIR)
