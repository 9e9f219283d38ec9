#!/usr/bin/env bash
# The README's test command: installs what is missing, builds COLMAP (4.1.1 by
# default, DPSFM_COLMAP_VERSION=3.10 for 3.10) with
# the plugin (cached outside the clone), and runs the whole test suite
# (CTest + gtest). Safe to re-run; a second run does not rebuild COLMAP.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

total_start=$SECONDS
build_dir="$(build_tree)"

start=$SECONDS
log "stage 'test' ..."
status=0
ctest --test-dir "$build_dir" -j "$(jobs_count)" --output-on-failure \
  --timeout 900 "$@" || status=$?
log "stage 'test' took $((SECONDS - start)) s"
log "total $((SECONDS - total_start)) s"
exit $status
