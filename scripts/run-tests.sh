#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Run test programs (cmocka, GoogleTest or pytest; "prog:arg:..." passes arguments), print each one's result and
# a closing "N passed, N failed" line; each result line ends with the program's wall time (the CI
# time budget is watched with it). Exit non-zero if anything failed or crashed.
set -u
passed=0; failed=0; broken=()
for t in "$@"; do
  out=$(mktemp)
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
  name=$(basename "${cmd[0]}")
  [ ${#cmd[@]} -gt 1 ] && [[ "$t" != pytest:* ]] && name="$name $(basename "${cmd[${#cmd[@]}-1]}")"
  if [ $rc -ne 0 ] || [ "$f" -gt 0 ] || [ "$p" -eq 0 ]; then
    echo "FAIL  $name (exit $rc, $p passed, $f failed, ${dt} s)"
    grep -aE 'FAILED|ERROR|Assert|error|failure|Failure' "$out" | head -40 | sed 's/^/      /'
    broken+=("$name")
    [ "$f" -eq 0 ] && f=1
  else
    echo "ok    $name ($p passed, ${dt} s)"
  fi
  passed=$((passed + p)); failed=$((failed + f))
  rm -f "$out"
done
echo "${passed} passed, ${failed} failed (${SECONDS} s)"
[ ${#broken[@]} -eq 0 ]
