#!/usr/bin/env bash
# Checks scripts/test.sh's one rerun on hand-made ctest projects: a test that fails once only by
# LeakSanitizer's tracer crash passes on its rerun; a test failure or a sanitizer report fails
# the suite even when a rerun would pass, and so does the crash twice. Registered with ctest (CMakeLists.txt).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

tracer_crash="echo '[  PASSED  ] 1 test.'; echo 'Tracer caught signal 11: addr=0x2518';\
 echo '==1==LeakSanitizer has encountered a fatal error.'; exit 1"
leak_report="echo '[  PASSED  ] 1 test.'; echo '==1==ERROR: LeakSanitizer: detected memory leaks';\
 echo 'Tracer caught signal 11: addr=0x2518';\
 echo '==1==LeakSanitizer has encountered a fatal error.'; exit 1"

# project NAME 'ctest-name shell-command'...: a build folder whose CTestTestfile runs the commands.
project() {
  local dir=$work/$1
  shift
  mkdir -p "$dir"
  : >"$dir/CTestTestfile.cmake"
  for entry in "$@"; do
    printf 'add_test(%s "/bin/bash" "-c" "%s")\n' "${entry%% *}" "${entry#* }" >>"$dir/CTestTestfile.cmake"
  done
  echo "$dir"
}

expect() {
  local want=$1 dir=$2 label=$3 got=0
  NOCTUA_BUILD_DIR=$dir bash "$root/scripts/test.sh" >"$dir.log" 2>&1 || got=$?
  if { [ "$want" = pass ] && [ "$got" -ne 0 ]; } || { [ "$want" = fail ] && [ "$got" -eq 0 ]; }; then
    echo "test_sh_check: $label: expected $want, exit status $got" >&2
    cat "$dir.log" >&2
    exit 1
  fi
  echo "test_sh_check: $label: $want, as expected"
}

marker=$work/crashed_once
expect pass "$(project passing 'Suite.Good true')" "a passing suite"
expect pass "$(project once 'Suite.Good true' \
  "Suite.Flaky if [ -e $marker ]; then exit 0; fi; touch $marker; $tracer_crash")" \
  "a tracer crash once, then a pass"
[ -e "$marker" ] || { echo "test_sh_check: the flaky test never ran" >&2; exit 1; }
expect fail "$(project twice "Suite.Flaky $tracer_crash")" "the tracer crash twice"
# Failures that would pass on a second run must not get one.
expect fail "$(project failure \
  "Suite.Bad if [ -e $marker.1 ]; then exit 0; fi; touch $marker.1; echo '[  FAILED  ] x'; exit 1")" \
  "a test failure once, then a pass"
expect fail "$(project leak \
  "Suite.Leak if [ -e $marker.3 ]; then exit 0; fi; touch $marker.3; $leak_report")" \
  "a leak report before the tracer crash once, then a pass"
expect fail "$(project mixed 'Suite.Bad exit 1' \
  "Suite.Flaky if [ -e $marker.2 ]; then exit 0; fi; touch $marker.2; $tracer_crash")" \
  "a tracer crash beside a real failure"
