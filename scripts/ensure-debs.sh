#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Install the Debian packages named on the command line that are not installed yet.
# Idempotent: prints nothing and does nothing when all are present. Runs apt-get
# update once, only when something is missing. Uses sudo when not root.
# Parallel make (-j2) starts several of these at once: they take turns on a lock, and each looks
# again at what is missing once it holds the lock; apt-get itself waits for a dpkg lock held by
# anything else (DPkg::Lock::Timeout).
set -euo pipefail
find_missing() {
  missing=()
  for p in "$@"; do
    s=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
    [ "$s" = "install ok installed" ] || missing+=("$p")
  done
}
find_missing "$@"
[ ${#missing[@]} -eq 0 ] && exit 0
exec 9>"${TMPDIR:-/tmp}/libcyl-ensure-debs.$(id -u).lock"
flock 9
find_missing "$@"
[ ${#missing[@]} -eq 0 ] && exit 0
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
echo "ensure-debs: installing ${missing[*]}" >&2
# A mirror that is mid-sync can fail one index; the install below still works from the others
# and fails loudly itself if a package cannot be had.
$SUDO env DEBIAN_FRONTEND=noninteractive apt-get -o DPkg::Lock::Timeout=600 update -qq || echo "ensure-debs: apt-get update reported errors; trying the install anyway" >&2
$SUDO env DEBIAN_FRONTEND=noninteractive apt-get -o DPkg::Lock::Timeout=600 install -y -qq --no-install-recommends "${missing[@]}" >&2
