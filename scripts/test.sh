#!/usr/bin/env bash
# Runs the whole test suite of an existing build (scripts/setup.sh makes build/).
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${NOCTUA_BUILD_DIR:-build}
log=$(mktemp)
trap 'rm -f "$log"' EXIT

if ctest --test-dir "$build_dir" --output-on-failure --parallel "$(nproc)" "$@" 2>&1 |
  tee "$log"; then
  exit 0
fi

# LeakSanitizer's stop-the-world tracer now and then crashes at process exit ("Tracer caught
# signal 11", google/sanitizers#1353) after the test itself has passed: a fault of the sanitizer
# runtime, with no leak report. A test that failed only that way runs once more. Any other
# failure (a test failure, any sanitizer report), or the same crash twice, fails the suite.
# Prints each failed test's name, prefixed by "!" unless it failed only by the tracer crash.
classify() {
  awk '
    function flush() {
      if (name != "") print ((tracer && fatal && passed && !report) ? "" : "!") name
      name = ""; tracer = 0; fatal = 0; passed = 0; report = 0
    }
    /Test +#[0-9]+: / {
      flush()
      if ($0 ~ /\*\*\*/) { rest = $0; sub(/.*Test +#[0-9]+: /, "", rest); split(rest, f, " "); name = f[1] }
      next
    }
    /^ *Start +[0-9]+: / { flush(); next }
    name != "" {
      if ($0 ~ /Tracer caught signal/) tracer = 1
      if ($0 ~ /LeakSanitizer has encountered a fatal error/) fatal = 1
      if ($0 ~ /\[  PASSED  \] /) passed = 1
      if ($0 ~ /ERROR: [A-Za-z]+Sanitizer|SUMMARY: [A-Za-z]+Sanitizer|runtime error:|\[  FAILED  \]/) report = 1
    }
    END { flush() }
  ' "$1"
}
mapfile -t failed < <(classify "$log")
if [ "${#failed[@]}" -eq 0 ]; then exit 1; fi
for name in "${failed[@]}"; do
  case $name in '!'*) exit 1 ;; esac
done
echo "test.sh: LeakSanitizer's tracer crashed at exit after ${#failed[@]} passing test(s):" \
  "${failed[*]}; running them once more" >&2
pattern="^($(
  IFS='|'
  echo "${failed[*]}"
))( |\$)"
ctest --test-dir "$build_dir" --output-on-failure -R "$pattern"
