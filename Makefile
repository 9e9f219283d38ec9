# The two commands of the README, plus the pieces they are made of.
.PHONY: example test build bench accuracy profiles real large clean-cache \
        test-3.10 test-installed check-colmap-main

example:
	bash scripts/run_example.sh

test:
	bash scripts/run_tests.sh

build:
	bash scripts/build.sh

# The whole suite on the COLMAP 3.10 build (the default build is COLMAP 4.1.1;
# DPSFM_COLMAP_VERSION=3.10 works with every target).
test-3.10:
	DPSFM_COLMAP_VERSION=3.10 bash scripts/run_tests.sh

# dp-sfm built against an installed COLMAP 4.1.1 (find_package, the `dpsfm`
# executable; the prefix is installed from make test's cached build) and its
# end-to-end tests run through `dpsfm`.
test-installed:
	bash scripts/run_installed_tests.sh

# dp-sfm's sources compiled against COLMAP's main branch (4.2.0.dev0) from
# ../shared/sources: a compile check, nothing is linked or run.
check-colmap-main:
	bash scripts/check_colmap_main.sh

bench:
	bash scripts/run_bench.sh

# Accuracy on generated scenes with known scale (tables; gates nothing).
accuracy:
	bash scripts/run_accuracy_bench.sh

# DP PSF profiles x estimation modes on generated scenes (a table).
profiles:
	bash scripts/run_profile_bench.sh

# Real DP captures (../shared/realdp): calibration from their flat planes,
# then r_s per scene and profile mode (a table; gates nothing).
real:
	bash scripts/run_real_bench.sh

# A 300-view workspace of 3000x2000 DP frames: the view budget against the
# distinct views (a table; gates nothing).
large:
	bash scripts/run_large_bench.sh

clean-cache:
	rm -rf "$${DPSFM_CACHE_DIR:-$${XDG_CACHE_HOME:-$$HOME/.cache}/dp-sfm}"
