#!/usr/bin/env bash
# Formats every C++ file with the repository's .clang-format (Google style).
# Needs clang-format on PATH (Debian: apt-get install clang-format, or
# pip install clang-format).
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
command -v clang-format >/dev/null || die "clang-format is not installed"
cd "$DPSFM_ROOT"
git ls-files '*.cc' '*.h' | xargs clang-format -i
