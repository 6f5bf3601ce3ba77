#!/usr/bin/env bash
# Installs the Debian 12 packages noctua needs (as root, when any is missing) and builds it in
# Release into build/. Usage: scripts/setup.sh [extra cmake arguments]
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  cmake g++ ninja-build pkg-config
  libopencv-dev libeigen3-dev libceres-dev
  libyaml-cpp-dev nlohmann-json3-dev libcli11-dev libspdlog-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  gnuplot-nox
  libfftw3-dev
  libx11-dev xvfb
  pybind11-dev python3-dev python3-numpy python3-opencv python3-pytest
  librosbag-storage-dev libsensor-msgs-dev libopenni2-dev
  python3-rosbag python3-sensor-msgs
)
missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" ||
    missing+=("$package")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -q
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends \
    "${missing[@]}"
fi

build_dir=${NOCTUA_BUILD_DIR:-build}
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@"
cmake --build "$build_dir" --parallel "$(nproc)"
echo "setup: built $build_dir/noctua"
