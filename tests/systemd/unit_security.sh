#!/usr/bin/env bash
# The unit's hardening, as systemd rates it: at most 2.0 ("OK" or better).
# usage: tests/systemd/unit_security.sh   (needs systemd-analyze: apt-get install systemd)
set -euo pipefail
unit=$(cd "$(dirname "$0")/../.." && pwd)/systemd/marionette.service
command -v systemd-analyze >/dev/null || { echo "unit test: systemd-analyze is missing: apt-get install systemd" >&2; exit 69; }
out=$(systemd-analyze security --offline=true --no-pager "$unit" 2>&1)
score=$(printf '%s\n' "$out" | sed -n 's/.*Overall exposure level for [^:]*: \([0-9.]*\).*/\1/p')
[ -n "$score" ] || { printf '%s\n' "$out" >&2; echo "unit test: no rating" >&2; exit 1; }
echo "marionette.service exposure: $score"
awk -v s="$score" 'BEGIN { exit !(s <= 2.0) }' || { echo "unit test: exposure $score is over 2.0" >&2; exit 1; }
