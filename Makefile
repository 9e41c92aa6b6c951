# ifab: the two commands a user needs are `make run` and `make test`.
# Each installs what is missing (scripts/install-deps), configures and builds first.
BUILD_DIR ?= build
JOBS      ?= 2
CMAKE_ARGS ?=
RUN_ARGS  ?=
PEERS_ARGS ?=

.PHONY: all deps configure build run test bench bench-peers clean

all: build

deps:
	@scripts/install-deps

$(BUILD_DIR)/build.ninja: | deps
	cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=Release $(CMAKE_ARGS)

configure: deps $(BUILD_DIR)/build.ninja

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

run: build
	$(BUILD_DIR)/bin/ifab run $(RUN_ARGS)

test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS) --timeout 900

bench: build
	@for b in $(BUILD_DIR)/bench/*_bench; do echo "== $$b"; $$b --benchmark_min_time=0.2 || exit 1; done

# ifab beside Open3D, OMPL and KDL on the same inputs (bench/peers.cc): one table. Installs the
# peers first (they are not dependencies of ifab) and re-configures so CMake finds them.
bench-peers: build
	@scripts/install-deps --with-peers
	cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=Release $(CMAKE_ARGS)
	cmake --build $(BUILD_DIR) -j $(JOBS) --target peers
	$(BUILD_DIR)/bench/peers $(PEERS_ARGS)

clean:
	rm -rf $(BUILD_DIR)
