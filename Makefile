# Two commands for a newcomer on a fresh Debian 12 machine:
#   make demo   installs what is missing, builds, runs the main job and prints a leaderboard
#   make test   installs what is missing, builds, runs the test suite (ctest, slow tests excluded)
BUILD ?= build
JOBS ?= $(shell nproc)

.PHONY: all deps configure build test test-slow demo bench clean

all: build

deps:
	bash scripts/install-deps.sh

configure: deps
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release

build: configure
	cmake --build $(BUILD) -j $(JOBS)

test: build
	cd $(BUILD) && ctest --output-on-failure --label-exclude slow -j $(JOBS)

test-slow: build
	cd $(BUILD) && ctest --output-on-failure --label-regex slow

demo: build
	bash scripts/demo.sh $(BUILD)/apps/weathergs demo_out

bench: build
	bash scripts/bench.sh $(BUILD)

clean:
	rm -rf $(BUILD) demo_out
