# The two commands of the README, plus the pieces they are made of.
.PHONY: example test build bench accuracy profiles real large clean-cache

example:
	bash scripts/run_example.sh

test:
	bash scripts/run_tests.sh

build:
	bash scripts/build.sh

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
