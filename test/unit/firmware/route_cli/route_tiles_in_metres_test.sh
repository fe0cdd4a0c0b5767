#!/bin/bash
# Tiles framed in metres (issue 27): a route taught from one recorded pass is repeated from passes
# flown at twice and half the speed (so 0.3 and 0.075 m between pings instead of 0.15), forwards and
# in reverse, with no framing flag: the tiles follow the swath, not the ping count. Each repeat must
# localise (at least 4 tiles with a side) and every side given must be the right one at 3.5-6.5 m
# (the 5 m offset), and the CSV names the pings of each tile, in order.
# Usage: $0 QNAV WORKDIR
set -u
Q=$1
W=$2
rm -rf "$W" && mkdir -p "$W" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
sim() { "$Q" sonar simulate --length-m 400 --range-m 30 --samples 512 --seed 5 "$@" >/dev/null || fail "simulate $*"; }
sim --out "$W/teach.jsf"
sim --out "$W/fast.xtf" --speed-mps 3.0 --offset-m 5 --pass-seed 6
sim --out "$W/slow_rev.xtf" --speed-mps 0.75 --offset-m 5 --pass-seed 7 --reverse
"$Q" route train --sonar "$W/teach.jsf" --out "$W/r.qroute" 2> "$W/train.err" || fail "train: $(cat "$W/train.err")"
grep -q "tiles of 54.0 m every 36.0 m" "$W/train.err" || fail "train: tiles not sized by the swath: $(cat "$W/train.err")"
for pass in fast slow_rev; do
  rev=""
  [ "$pass" = slow_rev ] && rev="--reverse"
  "$Q" route repeat --route "$W/r.qroute" --sonar "$W/$pass.xtf" $rev --csv "$W/$pass.csv" 2>/dev/null || fail "repeat $pass"
  # tile,true_node,estimate,...,status(8),side(9),...,cross_track_m(11),...,ping_first(17),ping_last(18)
  head -1 "$W/$pass.csv" | grep -q ",ping_first,ping_last$" || fail "$pass: CSV has no ping_first,ping_last"
  # forwards the offset is to starboard; in reverse the same offset lies to port of the direction of travel
  want=starboard
  [ "$pass" = slow_rev ] && want=port
  awk -F, -v pass="$pass" -v want="$want" 'NR > 1 { n++; x = $11 < 0 ? -$11 : $11
                     if ($9 != "unknown") { d++; if ($9 == want && x > 3.5 && x < 6.5) ok++ }
                     if ($18 <= $17 || (NR > 2 && $17 <= first)) bad++; first = $17 }
           END { printf "%s: tiles %d, side decided %d, %s at 3.5-6.5 m %d, ping ranges out of order %d\n", pass, n, d, want, ok, bad;
                 exit !(n >= 8 && d >= 4 && ok == d && bad == 0) }' "$W/$pass.csv" || fail "$pass results"
done
# route framing: a configuration it does not fly is refused by name (it once ran the reference alone).
"$Q" route framing --only 3:1.5 > /dev/null 2> "$W/only.err"
rc=$?
[ $rc -eq 2 ] && grep -q "must be one of the configurations" "$W/only.err" || fail "framing --only 3:1.5: rc $rc, $(cat "$W/only.err")"
echo "PASS"
