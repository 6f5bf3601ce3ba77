#!/usr/bin/env bash
# Runs the whole test suite of an existing build (scripts/setup.sh makes build/).
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${NOCTUA_BUILD_DIR:-build}
ctest --test-dir "$build_dir" --output-on-failure --parallel "$(nproc)" "$@"
