# Thin front door over CMake. `make demo` and `make test` work on a fresh Debian 12 as root.
JOBS ?= 2
BUILD ?= build
ASAN_BUILD ?= build-asan
CMAKE_FLAGS ?=
PREFIX ?= /usr/local
IBL = $(BUILD)/ibl
DEMO_DIR = out/demo

.PHONY: all deps build test test-release test-asan demo bench studies fuzz valgrind install clean

all: build

deps:
	@sh scripts/install-deps.sh

build: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DIBL_WERROR=ON $(CMAKE_FLAGS) >/dev/null
	@cmake --build $(BUILD) -j $(JOBS) -- --no-print-directory

test-release: build
	@cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

# The sanitizer build at -O1, as the sanitizers' own documentation advises: at -O0 its suite took
# 461 of make test's 634 s on an Intel Xeon VM of this project's kind, at -O1 301 s.
test-asan: deps
	@cmake -S . -B $(ASAN_BUILD) -DCMAKE_BUILD_TYPE=Debug -DCMAKE_C_FLAGS_DEBUG="-O1 -g" -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g" -DIBL_WERROR=ON -DIBL_SANITIZE=ON -DIBL_BUILD_BENCH=OFF $(CMAKE_FLAGS) >/dev/null
	@cmake --build $(ASAN_BUILD) -j $(JOBS)
	@cd $(ASAN_BUILD) && ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 ctest --output-on-failure -j $(JOBS)

# Both builds; the run ends with CTest's summary line of the sanitizer build.
test: test-release test-asan

demo: build
	@sh scripts/demo.sh $(IBL) $(DEMO_DIR)

bench: build
	@sh scripts/install-deps.sh --bench
	@sh bench/run.sh $(BUILD)

# docs/STUDIES.md's tables and docs/images/studies_*.png, regenerated (~1-2 minutes, one thread)
studies: build
	@sh tools/studies/run.sh $(BUILD)

fuzz:
	@sh scripts/install-deps.sh --fuzz
	@sh fuzz/run.sh

# memcheck over the small test programs and one CLI run (slow; not part of make test)
VALGRIND_TESTS ?= test_cubemap test_io test_containers test_pixel_format test_sh test_irradiance test_edge_fixup
valgrind: build
	@for t in $(VALGRIND_TESTS); do \
	  valgrind --error-exitcode=9 --leak-check=full -q $(BUILD)/tests/$$t >/dev/null || { echo "valgrind: $$t failed"; exit 1; }; \
	  echo "valgrind: $$t clean"; done
	@valgrind --error-exitcode=9 --leak-check=full -q $(IBL) convert -q tests/data/studio.exr -o $(BUILD)/vg.ktx2 --size 64 --mips && echo "valgrind: ibl convert clean"

install: build
	@cmake --install $(BUILD) --prefix $(PREFIX)

clean:
	rm -rf $(BUILD) $(ASAN_BUILD) build-fuzz out
