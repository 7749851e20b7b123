#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# make ci-hardening, run by .ci/run after `make test`: the whole suite under
# AddressSanitizer + UndefinedBehaviorSanitizer, the firmware build and the second architecture,
# 60 s of fuzzing per target, static analysis, and the 10,000-frame soak. The steps run one after
# another (the CI machine has 2 cores). Every step runs even when an earlier one fails, so one CI
# run reports them all; the exit status is non-zero if any failed.
set -uo pipefail
cd "$(dirname "$0")/.."
MAKE=${MAKE:-make}
steps=("test SAN=1" "embedded" "fuzz-smoke" "lint" "soak")
declare -a result
fail=0
i=0
for s in "${steps[@]}"; do
  i=$((i + 1))
  echo "==== [$i/${#steps[@]}] make $s"
  t0=$(date +%s)
  # shellcheck disable=SC2086  # the step is "target VAR=value" words
  if $MAKE --no-print-directory $s; then r=ok; else r=FAIL; fail=1; fi
  result+=("$(printf '%-5s make %-12s %5d s' "$r" "$s" $(( $(date +%s) - t0 )))")
done
echo "==== hardening summary"
printf '%s\n' "${result[@]}"
exit $fail
