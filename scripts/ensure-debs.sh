#!/usr/bin/env bash
# Install the Debian packages named on the command line that are not installed yet.
# Idempotent: prints nothing and does nothing when all are present. Runs apt-get
# update once, only when something is missing. Uses sudo when not root.
set -euo pipefail
missing=()
for p in "$@"; do
  s=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  [ "$s" = "install ok installed" ] || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
echo "ensure-debs: installing ${missing[*]}" >&2
# A mirror that is mid-sync can fail one index; the install below still works from the others
# and fails loudly itself if a package cannot be had.
$SUDO env DEBIAN_FRONTEND=noninteractive apt-get update -qq || echo "ensure-debs: apt-get update reported errors; trying the install anyway" >&2
$SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
