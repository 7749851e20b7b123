#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Run each libFuzzer target for N seconds on a copy of its committed corpus (the committed
# seeds are never modified). Exit non-zero on any crash, leak, timeout or sanitizer report.
set -uo pipefail
secs=$1; shift
D=build/fuzz
mkdir -p "$D/findings"
fail=0
for t in "$@"; do
  work="$D/corpus/$t"; mkdir -p "$work"
  [ -d "tests/fuzz/corpus/$t" ] && cp -n tests/fuzz/corpus/$t/* "$work/" 2>/dev/null
  log="$D/$t.log"
  # a Python target (tests/fuzz/NAME.py, atheris in the project venv) or a compiled one
  if [ -f "tests/fuzz/$t.py" ]; then cmd=("${VENV:-.venv}/bin/python" "tests/fuzz/$t.py"); else cmd=("$D/$t"); fi
  dict=(); [ -f "tests/fuzz/$t.dict" ] && dict=(-dict="tests/fuzz/$t.dict")
  "${cmd[@]}" "$work" "${dict[@]}" -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix="$D/findings/$t-" >"$log" 2>&1
  rc=$?
  runs=$(grep -aoE 'stat::number_of_executed_units: *[0-9]+' "$log" | awk '{print $2}')
  cov=$(grep -aoE 'cov: [0-9]+' "$log" | tail -1 | awk '{print $2}')
  if [ $rc -ne 0 ]; then
    echo "FAIL  $t: exit $rc after ${secs}s (see $log)"; grep -aE 'ERROR|SUMMARY|runtime error' "$log" | head -5
    fail=1
  else
    echo "ok    $t: ${runs:-?} inputs in ${secs}s, coverage ${cov:-?} edges, corpus $(ls "$work" | wc -l) files"
  fi
done
exit $fail
