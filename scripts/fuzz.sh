#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/) with clang, AddressSanitizer and UBSan into build-fuzz/ and
# runs each for a bounded time on a copy of its corpus (fuzz/corpus/<target>/). Crash inputs are
# written to fuzz/crashes/<target>/ (the corpus replay test of the normal build feeds them to the
# same entry functions); with --update-corpus the new inputs are merged, minimised, into
# fuzz/corpus/. Not part of CI.
# Usage: scripts/fuzz.sh [--update-corpus] [seconds per target (default 150)] [target...]
set -euo pipefail
cd "$(dirname "$0")/.."

update=0
if [ "${1:-}" = "--update-corpus" ]; then
  update=1
  shift
fi
seconds=${1:-150}
shift || true
targets=("$@")
((${#targets[@]})) || targets=(trajectory association settings extractor)

packages=(clang libclang-rt-14-dev)
missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" ||
    missing+=("$package")
done
if ((${#missing[@]})); then
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -q
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends \
    "${missing[@]}"
fi

build_dir=${NOCTUA_FUZZ_BUILD_DIR:-build-fuzz}
flags="-g -O1 -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined"
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DNOCTUA_FUZZ=ON -DNOCTUA_BUILD_TESTS=OFF -DNOCTUA_BUILD_BENCHMARKS=OFF -DNOCTUA_BUILD_PYTHON=OFF \
  -DNOCTUA_WERROR=OFF
cmake --build "$build_dir" --parallel "${NOCTUA_FUZZ_JOBS:-2}" \
  --target "${targets[@]/#/fuzz_}"

export ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
status=0
for target in "${targets[@]}"; do
  work="$build_dir/corpus/$target"
  mkdir -p "$work" "fuzz/crashes/$target"
  cp -n fuzz/corpus/"$target"/* "$work"/ 2>/dev/null || true
  log="$build_dir/fuzz_$target.log"
  echo "fuzz: $target for ${seconds}s (log $log)"
  if ! "$build_dir/fuzz/fuzz_$target" "$work" -max_total_time="$seconds" -max_len=4096 -timeout=20 \
      -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="fuzz/crashes/$target/" \
      >"$log" 2>&1; then
    echo "fuzz: $target FOUND A CRASH (see $log and fuzz/crashes/$target/)"
    status=1
  fi
  grep -E "^stat::number_of_executed_units|^stat::peak_rss_mb|^#[0-9]+ +DONE" "$log" || true
  if ((update)); then
    "$build_dir/fuzz/fuzz_$target" -merge=1 -max_len=4096 "fuzz/corpus/$target" "$work" \
      >>"$log" 2>&1
  fi
done
exit $status
