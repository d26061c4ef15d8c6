# groundslam: the two commands of the README (`make demo`, `make test`), `make build`, and the reliability
# checks `make test-sanitize` (AddressSanitizer + UndefinedBehaviorSanitizer) and `make fuzz` (libFuzzer).
BUILD_DIR ?= build
BUILD_TYPE ?= Release
JOBS ?= $(shell nproc)

SANITIZE_DIR ?= build-sanitize
SANITIZE ?= address,undefined
FUZZ_DIR ?= build-fuzz
FUZZ_WORK ?= fuzz-work
FUZZ_SECONDS ?= 60

# A sanitizer report aborts the process (non-zero exit, so the test fails) with a stack trace. Leaks are
# detected; tests/lsan.supp lists the third-party leaks that are suppressed and why.
SANITIZER_ENV = ASAN_OPTIONS=halt_on_error=1:abort_on_error=1:detect_leaks=1:check_initialization_order=1 \
	UBSAN_OPTIONS=halt_on_error=1:abort_on_error=1:print_stacktrace=1 \
	LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0

.PHONY: deps configure build test demo benchmark clean test-sanitize test-sanitize-all sanitize-build fuzz-deps fuzz

deps:
	@bash scripts/install_deps.sh

configure: deps
	@cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) > $(BUILD_DIR).configure.log 2>&1 || (cat $(BUILD_DIR).configure.log; exit 1)

build: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS)

test: build
	@cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

demo: build
	@bash scripts/demo.sh $(BUILD_DIR)/groundslam

# Every target built with -fsanitize=$(SANITIZE) in $(SANITIZE_DIR); the tests of `make test` run under it (unit
# and end-to-end tests, the CLI error and fault tests) but for those labelled `long` (tests/long_tests.cmake: accuracy
# runs of 5 s or more each, 10-15 times as long sanitized); `make test-sanitize-all` runs those too.
test-sanitize: sanitize-build
	@cd $(SANITIZE_DIR) && $(SANITIZER_ENV) ctest --output-on-failure -j $(JOBS) -LE long

test-sanitize-all: sanitize-build
	@cd $(SANITIZE_DIR) && $(SANITIZER_ENV) ctest --output-on-failure -j $(JOBS)

sanitize-build: deps
	@cmake -S . -B $(SANITIZE_DIR) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) -DGROUNDSLAM_SANITIZE=$(SANITIZE) \
		-DGROUNDSLAM_BUILD_BENCHMARKS=OFF -DGROUNDSLAM_BUILD_PYTHON=OFF > $(SANITIZE_DIR).configure.log 2>&1 || (cat $(SANITIZE_DIR).configure.log; exit 1)
	@cmake --build $(SANITIZE_DIR) -j $(JOBS)

fuzz-deps:
	@bash scripts/install_deps.sh --fuzz

# libFuzzer targets (tests/fuzz/) built with clang in $(FUZZ_DIR), each run for FUZZ_SECONDS from the seed
# corpus tests/data/fuzz/<target>/; new corpus entries and findings go to $(FUZZ_WORK)/<target>/.
fuzz: fuzz-deps
	@cmake -S . -B $(FUZZ_DIR) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) -DCMAKE_CXX_COMPILER=clang++ -DGROUNDSLAM_FUZZ=ON \
		-DGROUNDSLAM_BUILD_TESTS=OFF -DGROUNDSLAM_BUILD_BENCHMARKS=OFF -DGROUNDSLAM_BUILD_PYTHON=OFF > $(FUZZ_DIR).configure.log 2>&1 || (cat $(FUZZ_DIR).configure.log; exit 1)
	@cmake --build $(FUZZ_DIR) -j $(JOBS) --target fuzzers
	@bash scripts/fuzz.sh $(FUZZ_DIR) $(FUZZ_SECONDS) $(FUZZ_WORK)

clean:
	rm -rf $(BUILD_DIR) $(BUILD_DIR).configure.log $(SANITIZE_DIR) $(SANITIZE_DIR).configure.log \
		$(FUZZ_DIR) $(FUZZ_DIR).configure.log $(FUZZ_WORK)
