# vcut: `make demo` sets up and runs the bundled example; `make test` checks the formatting,
# sets up and runs every test (also under AddressSanitizer/UBSan) and fuzzes the program
# readers for a minute;
# `make bench` measures.
BUILD ?= build
BUILD_SAN ?= build-sanitize
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=

.PHONY: deps build demo test test-format test-release test-sanitize test-fuzz bench clean

deps:
	@scripts/install-deps

build: deps
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) > $(BUILD).configure.log || (cat $(BUILD).configure.log; exit 1)
	cmake --build $(BUILD) -j $(JOBS)

demo: build
	./$(BUILD)/cli/vcut simulate examples/demo/job.yaml
	./$(BUILD)/cli/vcut simulate examples/machine-collision/job.yaml
	@echo "Open examples/demo/out/demo/report.html in a browser (the part coloured by deviation, gouges and their NC lines; Play below the view)"
	@echo "and examples/machine-collision/out/crash/report.html (the machine played back: Next event poses it at each collision)"

# The peers the tests compare with (LinuxCNC's rs274, Chromium) are installed here, so a
# missing one fails its test instead of skipping it (VCUT_REQUIRE_PEERS).
test-release: build
	@scripts/install-deps --test
	cd $(BUILD) && VCUT_REQUIRE_PEERS=1 ctest --output-on-failure -j $(JOBS)

test-sanitize: deps
	cmake -S . -B $(BUILD_SAN) -G Ninja -DCMAKE_BUILD_TYPE=Release -DVCUT_SANITIZE=ON -DVCUT_BUILD_BENCHMARKS=OFF > $(BUILD_SAN).configure.log || (cat $(BUILD_SAN).configure.log; exit 1)
	cmake --build $(BUILD_SAN) -j $(JOBS)
	cd $(BUILD_SAN) && ASAN_OPTIONS=detect_leaks=1 LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 ctest --output-on-failure -j $(JOBS)

# libFuzzer (clang) on the G-code, APT and SINUMERIK readers under ASan+UBSan, 60 s each, side by side.
test-fuzz: deps
	@scripts/install-deps --test
	BUILD_FUZZ=build-fuzz scripts/fuzz-readers 60

# Every C++ file as clang-format writes it (.clang-format).
test-format: deps
	@scripts/install-deps --test
	scripts/check-format

test: test-format test-release test-sanitize test-fuzz

bench: build
	@scripts/install-deps --bench
	./$(BUILD)/benchmarks/vcut_benchmarks --benchmark_min_time=0.2
	scripts/bench-demo $(BUILD)/cli/vcut
	scripts/bench-peers $(BUILD)/cli/vcut
	scripts/bench-features $(BUILD)/cli/vcut
	scripts/bench-memory $(BUILD)/cli/vcut
	scripts/bench-five-axis $(BUILD)/cli/vcut
	scripts/bench-threads $(BUILD)/cli/vcut

clean:
	rm -rf $(BUILD) $(BUILD_SAN) build-fuzz .ccache $(BUILD).configure.log $(BUILD_SAN).configure.log
