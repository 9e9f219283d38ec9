# The two commands of the README (make example, make test), plus the pieces
# they are made of. Each target runs at most one script on its way to CMake:
#   make build -> scripts/build.sh -> CMake, which fetches, verifies and
#   patches COLMAP (cmake/ColmapRelease.cmake) and builds it with dp-sfm.
# Variables (environment or command line):
#   DPSFM_COLMAP_VERSION  the COLMAP release built into: 4.1.1 (default) or
#                         3.10; each has its own cached build tree
#   DPSFM_CACHE_DIR       what survives between runs, outside the clone
#   DPSFM_BUILD_TYPE      Release (default)
#   DPSFM_JOBS            parallel jobs (default: the number of cores)
#   CTEST_ARGS            more arguments for ctest (make test), e.g. -R Rescale
#   DPSFM_CMAKE_ARGS      more CMake options for the build, e.g.
#                         -DDPSFM_WITH_FFTW=ON (README, "Licence")
.PHONY: example test build deps bench cost accuracy profiles real stability large \
        clean-cache test-3.10 test-installed check-colmap-main

DPSFM_COLMAP_VERSION ?= 4.1.1
DPSFM_BUILD_TYPE ?= Release
DPSFM_JOBS ?= $(shell nproc 2>/dev/null || echo 2)
DPSFM_CACHE_DIR ?= $(if $(XDG_CACHE_HOME),$(XDG_CACHE_HOME),$(HOME)/.cache)/dp-sfm
DPSFM_BUILD_DIR ?= $(DPSFM_CACHE_DIR)/build/colmap-$(DPSFM_COLMAP_VERSION)
export DPSFM_COLMAP_VERSION DPSFM_BUILD_TYPE DPSFM_JOBS DPSFM_CACHE_DIR \
       DPSFM_BUILD_DIR

# ccache for every compile (CMake sets it as the compiler launcher). A fresh
# clone gives every file a new mtime/ctime; the contents decide.
export CCACHE_DIR ?= $(DPSFM_CACHE_DIR)/ccache
export CCACHE_MAXSIZE ?= 5G
export CCACHE_SLOPPINESS ?= include_file_mtime,include_file_ctime,time_macros

example: build
	bash scripts/run_example.sh

test: build
	ctest --test-dir "$(DPSFM_BUILD_DIR)" -j $(DPSFM_JOBS) \
	  --output-on-failure --timeout 900 $(CTEST_ARGS)

# The Debian packages and the tests' pycolmap (a no-op when all are there).
deps:
	bash scripts/install_deps.sh

build: deps
	bash scripts/build.sh "$(DPSFM_BUILD_DIR)" \
	  -DDPSFM_COLMAP_RELEASE=$(DPSFM_COLMAP_VERSION) \
	  -DCMAKE_BUILD_TYPE=$(DPSFM_BUILD_TYPE) $(DPSFM_CMAKE_ARGS)

# The whole suite on the COLMAP 3.10 build (the default build is COLMAP 4.1.1;
# DPSFM_COLMAP_VERSION=3.10 works with every target), with FFTW's transforms,
# so that CI runs both backends.
test-3.10:
	$(MAKE) test DPSFM_COLMAP_VERSION=3.10 \
	  DPSFM_BUILD_DIR="$(DPSFM_CACHE_DIR)/build/colmap-3.10" \
	  DPSFM_CMAKE_ARGS="-DDPSFM_WITH_FFTW=ON $(DPSFM_CMAKE_ARGS)"

# dp-sfm built against an installed COLMAP 4.1.1 (find_package, the `dpsfm`
# executable; the prefix is installed from the default build) with Clang and
# neither GPL library, its unit tests run and its end-to-end tests run
# through `dpsfm`.
test-installed: build
	bash scripts/run_installed_tests.sh

# dp-sfm's sources compiled against COLMAP's main branch (4.2.0.dev0) from
# ../shared/sources: a compile check, nothing is linked or run.
check-colmap-main: deps
	bash scripts/check_colmap_main.sh

bench: build
	bash scripts/run_bench.sh

# The command's cost per stage and PSF path against decoding the frames
# (also the last part of make bench; a table, gates nothing).
cost: build
	bash scripts/run_cost_bench.sh

# Accuracy on generated scenes with known scale (tables; gates nothing).
accuracy: build
	bash scripts/run_accuracy_bench.sh

# DP PSF profiles x estimation modes on generated scenes (a table).
profiles: build
	bash scripts/run_profile_bench.sh

# Real DP captures (../shared/realdp): calibration from their flat planes,
# then r_s per scene and profile mode (a table; gates nothing).
# How far answers move for an explicit bound 1 px either side of the
# automatic one and for one thread against all (a table; gates nothing).
stability: build
	bash scripts/run_stability_bench.sh

real: build
	bash scripts/run_real_bench.sh

# A 300-view workspace of 3000x2000 DP frames: the view budget against the
# distinct views (a table; gates nothing).
large: build
	bash scripts/run_large_bench.sh

clean-cache:
	rm -rf "$(DPSFM_CACHE_DIR)"
