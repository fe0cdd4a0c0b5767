#!/bin/bash
# qnav route camera: teach a 3 m route with a downward camera over the synthetic Mars yard and repeat
# it forwards and in reverse at 0-40 % of the footprint width. The route must localise (node within
# +/-1 on >= 85 % of scored tiles; 97.5 % when written) with the side right on >= 95 % of the tiles
# where guidance decides one. Usage: $0 QNAV
set -u
Q=$1
out=$("$Q" route camera --length-m 3 --json) || { echo "FAIL: qnav route camera exit $?"; exit 1; }
echo "$out"
field() { echo "$out" | sed -n "s/.*\"$1\":\([-0-9.]*\).*/\1/p"; }
w1=$(field node_within_1_pct)
side=$(field side_correct_pct)
decided=$(field side_decided)
[ -n "$w1" ] && [ -n "$side" ] && [ -n "$decided" ] || { echo "FAIL: JSON fields missing"; exit 1; }
awk -v w="$w1" -v s="$side" -v d="$decided" 'BEGIN { exit !(w >= 85 && s >= 95 && d >= 40) }' ||
  { echo "FAIL: node within +/-1 $w1 %, side correct $side % of $decided decided"; exit 1; }
# Bad input: a route length out of range is a usage error, not a crash.
"$Q" route camera --length-m 0.5 >/dev/null 2>&1
rc=$?
[ $rc -eq 2 ] || { echo "FAIL: --length-m 0.5: exit $rc, want 2"; exit 1; }
echo "ok"
