#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Run test programs (cmocka, GoogleTest or pytest; "prog:arg:..." passes arguments), print each one's result and
# a closing "N passed, N failed" line; each result line ends with the program's wall time (the CI
# time budget is watched with it). Exit non-zero if anything failed or crashed.
#
# CYL_TEST_RETRY=1 (make ci-hardening's sanitizer run): a program that fails is run once more. Its
# first failure is printed in full either way; if the second run passes, the program counts as
# passed and the closing lines name it as "passed only on retry" with that first failure, so a
# failure that comes and goes is seen and kept, not hidden. A program that fails twice fails.
set -u
passed=0; failed=0; broken=(); flaky=()
flaky_log=$(mktemp)
trap 'rm -f "$flaky_log"' EXIT

# run_one TEST OUT: runs it into OUT; sets rc p f dt
run_one() {
  local t=$1 out=$2 t0
  if [[ "$t" == pytest:* ]]; then
    cmd=(${t#pytest:})
  elif [[ "$t" == *:* ]]; then
    IFS=: read -r -a cmd <<< "$t"   # "program:arg1:arg2" runs program with those arguments
  else
    cmd=("$t")
  fi
  t0=$SECONDS
  "${cmd[@]}" >"$out" 2>&1
  rc=$?
  dt=$((SECONDS - t0))
  # cmocka: "[  PASSED  ] N test(s)."  GoogleTest: "[  PASSED  ] N tests."
  p=$(grep -aoE '^\[  PASSED  \] [0-9]+ test' "$out" | awk '{s+=$4} END{print s+0}')
  f=$(grep -aoE '^\[  FAILED  \] [0-9]+ test' "$out" | awk '{s+=$4} END{print s+0}')
  if [[ "$t" == pytest:* ]]; then
    p=$(grep -aoE '[0-9]+ passed' "$out" | tail -1 | awk '{print $1+0}'); p=${p:-0}
    f=$(grep -aoE '[0-9]+ (failed|error)' "$out" | tail -1 | awk '{print $1+0}'); f=${f:-0}
  fi
}
bad_result() { [ "$rc" -ne 0 ] || [ "$f" -gt 0 ] || [ "$p" -eq 0 ]; }
failure_lines() { grep -aE 'FAILED|ERROR|Assert|error|failure|Failure|check failed|Sanitizer|runtime error' "$1" | head -40 | sed 's/^/      /'; }

for t in "$@"; do
  out=$(mktemp)
  run_one "$t" "$out"
  name=$(basename "${cmd[0]}")
  [ ${#cmd[@]} -gt 1 ] && [[ "$t" != pytest:* ]] && name="$name $(basename "${cmd[${#cmd[@]}-1]}")"
  if bad_result && [ "${CYL_TEST_RETRY:-0}" = 1 ]; then
    first="first run: exit $rc, $p passed, $f failed, ${dt} s"
    echo "RETRY $name ($first); its output's failure lines:"
    lines=$(failure_lines "$out")
    echo "$lines"
    run_one "$t" "$out"
    if ! bad_result; then flaky+=("$name"); { echo "$name ($first)"; echo "$lines"; } >> "$flaky_log"; fi
  fi
  if bad_result; then
    echo "FAIL  $name (exit $rc, $p passed, $f failed, ${dt} s)"
    failure_lines "$out"
    broken+=("$name")
    [ "$f" -eq 0 ] && f=1
  else
    echo "ok    $name ($p passed, ${dt} s)"
  fi
  passed=$((passed + p)); failed=$((failed + f))
  rm -f "$out"
done
if [ ${#flaky[@]} -gt 0 ]; then
  echo "passed only on retry: ${flaky[*]}; their first failures:"
  cat "$flaky_log"
fi
echo "${passed} passed, ${failed} failed (${SECONDS} s)"
[ ${#broken[@]} -eq 0 ]
