#!/usr/bin/env bash
# Checks noctua as another project sees it: installs an existing build (default build/, made by
# scripts/setup.sh) into a fresh prefix, builds examples/ against it through
# find_package(noctua), runs them on real frames from ../shared/data, and checks the pkg-config
# file, including a program built from its flags alone. Exits non-zero on any failure.
# Usage: scripts/check_package.sh    (NOCTUA_BUILD_DIR selects another build)
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${NOCTUA_BUILD_DIR:-build}
shared=${NOCTUA_SHARED_DIR:-../shared}
sequence=$shared/data/tum_fr1_rpy_200

fail() {
  echo "check_package: FAILED: $*" >&2
  exit 1
}
[ -f "$build_dir/CMakeCache.txt" ] || fail "$build_dir is not a build (run scripts/setup.sh)"
[ -d "$sequence/rgb" ] || fail "$sequence/rgb is missing"
expected=$(sed -n 's/^CMAKE_PROJECT_VERSION:STATIC=//p' "$build_dir/CMakeCache.txt")
[ -n "$expected" ] || fail "no project version in $build_dir/CMakeCache.txt"

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
prefix=$work/prefix

echo "check_package: installing $build_dir into an empty prefix"
cmake --install "$build_dir" --prefix "$prefix" >"$work/install.log" ||
  { cat "$work/install.log"; fail "cmake --install"; }
version=$("$prefix/bin/noctua" --version) || fail "noctua --version"
[ "$version" = "$expected" ] || fail "noctua --version says '$version', expected '$expected'"
for unwanted in include/noctua/testing include/noctua/fuzz include/noctua/slam/reprojection_cost.h; do
  [ ! -e "$prefix/$unwanted" ] || fail "$unwanted is installed"
done
# No pipes into an early-exiting reader here: under pipefail the writer's SIGPIPE fails the script.
test_files=$(find "$prefix" -name '*_test*')
[ -z "$test_files" ] || fail "test files are installed: $test_files"
[ -f "$prefix/share/noctua/vocabulary/default.vocab" ] || fail "the default vocabulary is not installed"

echo "check_package: building examples/ against the installed package"
cmake -S examples -B "$work/examples" -DCMAKE_PREFIX_PATH="$prefix" >"$work/examples.log" 2>&1 ||
  { cat "$work/examples.log"; fail "configuring examples/"; }
cmake --build "$work/examples" --parallel "$(nproc)" >>"$work/examples.log" 2>&1 ||
  { cat "$work/examples.log"; fail "building examples/"; }

frames=("$sequence"/rgb/*.png) # a glob expands sorted
frame=${frames[0]}
[ -f "$frame" ] || fail "no PNG frame in $sequence/rgb"
output=$("$work/examples/extract_keypoints" "$frame") || fail "extract_keypoints $frame"
echo "  extract_keypoints: $output"
keypoints=$(sed -n 's/.*: \([0-9]*\) keypoints.*/\1/p' <<<"$output")
[ "${keypoints:-0}" -ge 500 ] || fail "extract_keypoints found ${keypoints:-no} keypoints (< 500)"

output=$("$work/examples/slam_sequence" "$sequence" "$prefix/share/noctua/config/tum_fr1.yaml" \
  100) || fail "slam_sequence"
echo "  slam_sequence: ${output//$'\n'/; }"
tracked=$(sed -n 's/.*tracked \([0-9]*\),.*/\1/p' <<<"$output")
[ "${tracked:-0}" -ge 50 ] || fail "slam_sequence tracked ${tracked:-no} of 100 frames"
grep -q '^ATE RMSE' <<<"$output" || fail "slam_sequence gave no ATE"

if grep -q '^NOCTUA_PYTHON_INSTALL_DIR:' "$build_dir/CMakeCache.txt"; then
  echo "check_package: the Python module from the installed prefix"
  python_dir=$(sed -n 's/^NOCTUA_PYTHON_INSTALL_DIR:[A-Z]*=//p' "$build_dir/CMakeCache.txt")
  [ -d "$prefix/$python_dir/noctua" ] || fail "$prefix/$python_dir/noctua is not installed"
  # Run from the prefix so that neither the source tree nor the build can be imported instead.
  frame_abs=$(realpath "$frame")
  output=$(cd "$prefix" && PYTHONPATH="$prefix/$python_dir" NOCTUA_CONFIG_DIR= /usr/bin/python3 -c "
import cv2, noctua, sys
assert noctua.__file__.startswith('$prefix'), noctua.__file__
keypoints, descriptors = noctua.extract(cv2.imread(sys.argv[1]), method='paper')
assert len(keypoints) >= 500 and descriptors.shape == (len(keypoints), 32), descriptors.shape
assert noctua.config_dir().startswith('$prefix'), noctua.config_dir()
print(noctua.__version__, len(keypoints), 'keypoints')
" "$frame_abs") || fail "python3 -c 'import noctua' against the installed prefix"
  echo "  python: noctua ${output##*$'\n'}"  # its last line (spdlog may warn before it)
fi

echo "check_package: pkg-config"
pc=$(find "$prefix" -name noctua.pc)
[ -n "$pc" ] || fail "noctua.pc is not installed"
PKG_CONFIG_PATH=$(dirname "$pc")
export PKG_CONFIG_PATH
pc_version=$(pkg-config --modversion noctua) || fail "pkg-config --modversion noctua"
[ "$pc_version" = "$expected" ] || fail "pkg-config says '$pc_version', expected '$expected'"
# shellcheck disable=SC2046  # the flags are meant to split into words
c++ -std=c++20 -O1 examples/extract_keypoints.cc -o "$work/extract_keypoints_pc" \
  $(pkg-config --cflags --libs noctua) >"$work/pc.log" 2>&1 ||
  { cat "$work/pc.log"; fail "building from pkg-config's flags"; }
"$work/extract_keypoints_pc" "$frame" >/dev/null || fail "the pkg-config build does not run"

echo "check_package: OK (noctua $expected)"
