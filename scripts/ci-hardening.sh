#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# make ci-hardening, run by .ci/run after `make test`: the whole suite under
# AddressSanitizer + UndefinedBehaviorSanitizer, the firmware build and the second architecture,
# 60 s of fuzzing per target, static analysis, and the 10,000-frame soak. The steps run one after
# another (the CI machine has 2 cores). Every step runs even when an earlier one fails, so one CI
# run reports them all; the exit status is non-zero if any failed. Each step's output is also kept
# in build/ci-hardening/STEP.log, and the summary at the end repeats the failure lines of every step
# that failed (CI logs are often read from the end).
set -uo pipefail
cd "$(dirname "$0")/.."
MAKE=${MAKE:-make}
# the sanitizer run retries a failed test program once (scripts/run-tests.sh, CYL_TEST_RETRY)
steps=("test SAN=1 CYL_TEST_RETRY=1" "embedded" "fuzz-smoke" "lint" "soak")
declare -a result
declare -a failed_logs
logdir=build/ci-hardening
mkdir -p "$logdir"
fail=0
i=0
for s in "${steps[@]}"; do
  i=$((i + 1))
  echo "==== [$i/${#steps[@]}] make $s"
  t0=$(date +%s)
  log="$logdir/$(echo "$s" | tr ' =' '__').log"
  # shellcheck disable=SC2086  # the step is "target VAR=value" words
  if $MAKE --no-print-directory $s 2>&1 | tee "$log"; then r=ok; else r=FAIL; fail=1; failed_logs+=("$log"); fi
  result+=("$(printf '%-5s make %-12s %5d s' "$r" "$s" $(( $(date +%s) - t0 )))")
done
echo "==== hardening summary"
printf '%s\n' "${result[@]}"
# tests that failed once and passed on their retry, with their first failure
for log in "$logdir"/*.log; do
  grep -q '^passed only on retry' "$log" 2>/dev/null || continue
  echo "==== $log: $(grep '^passed only on retry' "$log")"
  sed -n '/^passed only on retry/,/^[0-9]* passed, [0-9]* failed/p' "$log" | sed '1d;$d' | head -60
done
for log in "${failed_logs[@]+"${failed_logs[@]}"}"; do
  echo "==== failure lines of $log"
  # the test runner's FAIL lines with the lines it quotes, or else the step's last lines
  if grep -q -E '^FAIL ' "$log"; then
    grep -a -A40 -E '^FAIL ' "$log" | grep -a -E '^(FAIL |      )' | head -80
  else
    tail -40 "$log"
  fi
done
exit $fail
