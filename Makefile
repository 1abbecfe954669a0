# Two commands for a newcomer on a fresh Debian 12 machine:
#   make demo   installs what is missing, builds, runs the main job and prints a leaderboard
#   make test   installs what is missing, builds, runs the test suite (ctest, slow tests excluded)
SHELL := /bin/bash
BUILD ?= build
JOBS ?= $(shell nproc)

.PHONY: all deps configure build test test-slow test-slurm test-asan fuzz interop suite demo check-baseline regression-baseline clean training-data validation-data adapted-led-rule models archive-status archive-commit results

all: build

deps:
	bash scripts/install-deps.sh

configure: deps
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release

build: configure
	cmake --build $(BUILD) -j $(JOBS)

# A test that skips (e.g. a missing tool) is reported as skipped, never as passed; with
# FAIL_ON_SKIP=1 (CI, where `make test` installed every tool) any skipped test fails the run.
FAIL_ON_SKIP ?= 0
test: build
	cd $(BUILD) && ctest --output-on-failure --label-exclude slow -j $(JOBS) | tee ctest.log; \
	  status=$${PIPESTATUS[0]}; \
	  if [ "$(FAIL_ON_SKIP)" = 1 ] && grep -q '\*\*\*Skipped' ctest.log; then \
	    echo "make test: tests were skipped, which CI does not allow:"; grep '\*\*\*Skipped' ctest.log; exit 1; fi; \
	  exit $$status

# The fast suite under AddressSanitizer + UndefinedBehaviorSanitizer (separate build tree; reports are
# fatal). Last clean run: docs/reliability.md.
ASAN_BUILD ?= build-asan
# fast_unwind_on_malloc=0: libstdc++ has no frame pointers, so the fast unwinder stops after two frames
# and a leak inside OpenImageIO would not match its suppression (tests/lsan.supp) by name.
test-asan: deps
	cmake -S . -B $(ASAN_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DWEATHERGS_SANITIZE=ON \
	  -DWEATHERGS_BUILD_BENCHMARKS=OFF
	cmake --build $(ASAN_BUILD) -j $(JOBS)
	cd $(ASAN_BUILD) && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
	  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:fast_unwind_on_malloc=0 \
	  ctest --output-on-failure --label-exclude slow -j $(JOBS)

# The restoration training set (docs/restoration.md): four training scenes (scenes/training/), rendered
# clear once and re-weathered with a fixed table of specs, and the randomized scenes that calibrate
# the LED; a cache (existing datasets are kept).
TRAINING_DATA ?= data/training
MAKE_TRAINING_DATA = bash scripts/make-training-data.sh $(BUILD)/apps/weathergs $(TRAINING_DATA) 12 quick
training-data: build
	$(MAKE_TRAINING_DATA)

# The LED's validation scenes station and village (docs/record/led_scenes.md, "A third draw"):
# no network trains on them (only the adapted peak rule is calibrated on them: adapted-led-rule, below);
# benchmarks/restoration_led_validation.py scores and
# compares LED weights on them. An OUT of their own.
VALIDATION_DATA ?= data/validation
validation-data: build
	TRAINING_PART=validation bash scripts/make-training-data.sh $(BUILD)/apps/weathergs $(VALIDATION_DATA) 12 quick

# The peak rule `detect --adapt` uses, calibrated on the validation scenes' adapted maps
# (docs/record/led_adaptation.md, "A rule for adapted maps"; ~13 min on 2 cores with the default
# 100 adaptation iterations; needs validation-data). Writes the LED weights in place (LED_WEIGHTS)
# with that rule added.
LED_WEIGHTS ?= models/led/led
ADAPTED_MAPS ?= data/validation_adapted_maps
adapted-led-rule: build
	bash scripts/calibrate-adapted-led.sh $(BUILD)/apps/weathergs $(VALIDATION_DATA) $(ADAPTED_MAPS) $(LED_WEIGHTS)

# Retrains every weight file in models/ from scratch (models/README.md); MODELS_DIR=DIR writes them
# there instead, leaving the shipped weights alone (e.g. to compare sha256s). The training set's
# assorted scenes are made beside the LED's training (scripts/train-models.sh), not before it.
MODELS_DIR ?= models
models: build
	TRAINING_PART=base $(MAKE_TRAINING_DATA)
	bash scripts/train-models.sh $(BUILD)/apps/weathergs $(TRAINING_DATA) $(MODELS_DIR)

# libFuzzer harnesses (fuzz/README.md) in a clang build; FUZZ_SECONDS per harness (600 for the
# documented runs).
FUZZ_BUILD ?= build-fuzz
FUZZ_SECONDS ?= 60
fuzz: deps
	bash scripts/install-deps.sh fuzz
	cmake -S . -B $(FUZZ_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++-14 \
	  -DWEATHERGS_FUZZ=ON -DWEATHERGS_BUILD_TESTS=OFF -DWEATHERGS_BUILD_BENCHMARKS=OFF
	cmake --build $(FUZZ_BUILD) -j $(JOBS)
	bash fuzz/run.sh $(FUZZ_BUILD) $(FUZZ_SECONDS)

# Real clients read what we write (docs/interop.md): splat-transform, a Three.js splat viewer and the
# HTML leaderboard in headless Debian Chromium. npm packages (pinned by interop/package-lock.json) go
# to interop/node_modules; results to $(BUILD)/interop/report.json.
interop: build
	bash scripts/install-deps.sh interop
	@if [ ! -f interop/node_modules/.package-lock.json ] || [ interop/package-lock.json -nt interop/node_modules/.package-lock.json ]; then \
	  cd interop && npm ci --no-audit --no-fund; fi
	bash interop/run.sh $(BUILD)

# The benchmark suite (workflow/Snakefile, docs/methods.md): SUITE_CONFIG="profile=quick iterations=7000 ..."
SUITE_CONFIG ?=
suite: build
	USER=$${USER:-weathergs} snakemake -s workflow/Snakefile --cores $(JOBS) \
	  --config weathergs=$(CURDIR)/$(BUILD)/apps/weathergs scenes=$(CURDIR)/scenes $(SUITE_CONFIG)

# The results archive (docs/archive.md): per cell of the suite's matrix, done, stale or missing, and the
# CPU-hours spent and left; ARCHIVE_DATA=OUT/data also checks the runs' datasets. archive-commit
# commits what the suite added to benchmarks/results/$(ARCHIVE_SUITE) (every few runs, so that a
# machine that goes away loses little).
ARCHIVE_SUITE ?= quick
ARCHIVE_DATA ?=
archive-status: build
	$(BUILD)/apps/weathergs archive status --root benchmarks/results --suite $(ARCHIVE_SUITE) \
	  $(if $(ARCHIVE_DATA),--data $(ARCHIVE_DATA))
# docs/results.md's tables from the committed archive (scripts/results-tables.sh): its state, the
# paper's tables with intervals and the agreement with the paper, the curves (docs/images/results/).
results: build
	bash scripts/results-tables.sh $(BUILD)/apps/weathergs benchmarks/results/$(ARCHIVE_SUITE)

archive-commit: build
	git add -- benchmarks/results/$(ARCHIVE_SUITE)
	git commit -m "results archive $(ARCHIVE_SUITE): $$($(BUILD)/apps/weathergs archive status --root benchmarks/results \
	  --suite $(ARCHIVE_SUITE) | grep '^done ')" -- benchmarks/results/$(ARCHIVE_SUITE)

# The slow tests, with every tool they need installed (the Slurm group too); a skip is a failure here,
# as in CI.
test-slow: build
	bash scripts/install-deps.sh slurm
	cd $(BUILD) && ctest --output-on-failure --label-regex slow | tee ctest-slow.log; \
	  status=$${PIPESTATUS[0]}; \
	  if grep -q '\*\*\*Skipped' ctest-slow.log; then echo "make test-slow: tests were skipped:"; grep '\*\*\*Skipped' ctest-slow.log; exit 1; fi; \
	  exit $$status

# The suite on a real one-node Slurm started by the test (docs/cluster.md); needs root. Skips are failures here.
test-slurm: build
	bash scripts/install-deps.sh slurm
	cd $(BUILD) && ctest --output-on-failure -R '^methods/slurm$$' | tee ctest-slurm.log; \
	  status=$${PIPESTATUS[0]}; if grep -q '\*\*\*Skipped' ctest-slurm.log; then exit 1; fi; exit $$status

# CI's regression check by hand: WeatherGS on the committed fixture against benchmarks/baselines/regression/.
check-baseline: build
	bash scripts/check_baseline.sh $(BUILD)/apps/weathergs out/check_baseline

# Regenerates that baseline and its tolerances for the current recipes (benchmarks/baselines/README.md):
# after any change of a default that moves the numbers. SEEDS (at least 5) set the spread.
SEEDS ?= 6
regression-baseline: build
	bash scripts/regression-baseline.sh $(BUILD)/apps/weathergs $(SEEDS)

demo: build
	bash scripts/demo.sh $(BUILD)/apps/weathergs demo_out

clean:
	rm -rf $(BUILD) $(ASAN_BUILD) $(FUZZ_BUILD) demo_out
