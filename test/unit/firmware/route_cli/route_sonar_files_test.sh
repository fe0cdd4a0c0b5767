#!/bin/bash
# qnav route train/repeat --sonar on files: the repeat must localise and see the 8 m offset; bad
# files must give a clear error and a non-zero exit, never a crash. Usage: $0 QNAV WORKDIR
set -u
Q=$1
W=$2
rm -rf "$W" && mkdir -p "$W" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
"$Q" sonar simulate --out "$W/teach.jsf" --length-m 300 --seed 5 >/dev/null || fail "simulate teach"
"$Q" sonar simulate --out "$W/repeat.xtf" --length-m 300 --offset-m 8 --seed 5 --pass-seed 6 >/dev/null || fail "simulate repeat"
"$Q" route train --sonar "$W/teach.jsf" --out "$W/r.qroute" --lines 300 --stride 150 || fail "train"
"$Q" route info "$W/r.qroute" >/dev/null || fail "info"
"$Q" route repeat --route "$W/r.qroute" --sonar "$W/repeat.xtf" --lines 300 --stride 150 --csv "$W/rep.csv" || fail "repeat"
# tile,true_node,estimate,probability,entropy,confident,inliers,status,side,true_side,cross_track_m,...
awk -F, 'NR > 1 { n++; if ($8 == "tracking") { t++; if ($9 == "starboard" && $11 > 6.5 && $11 < 9.5) ok++ }
                   if (NR > 3 && prev != "" && $3 < prev) back++; prev = $3 }
         END { printf "tiles %d, tracking %d, starboard 6.5-9.5 m %d, estimate went back %d times\n", n, t, ok, back;
               exit !(n >= 10 && t >= 0.8 * n && ok == t && back == 0) }' "$W/rep.csv" || fail "repeat results"
# Damaged inputs: a truncated file, a file that is not sonar data, a missing file, a damaged route.
head -c 100000 "$W/repeat.xtf" > "$W/short.xtf"
"$Q" route repeat --route "$W/r.qroute" --sonar "$W/short.xtf" --lines 300 --stride 150 --csv "$W/short.csv"
rc=$?
[ $rc -le 2 ] || fail "truncated file: exit $rc (crash?)"
head -c 5000 /dev/urandom > "$W/noise.xtf"
"$Q" route train --sonar "$W/noise.xtf" --out "$W/noise.qroute" 2> "$W/noise.err"
rc=$?
[ $rc -eq 1 ] || fail "noise file: exit $rc, want 1"
[ -s "$W/noise.err" ] || fail "noise file: no error message"
"$Q" route train --sonar "$W/missing.xtf" --out "$W/m.qroute" 2>/dev/null && fail "missing file accepted"
cp "$W/r.qroute" "$W/bad.qroute"
printf '\x5a' | dd of="$W/bad.qroute" bs=1 seek=200 conv=notrunc status=none
"$Q" route repeat --route "$W/bad.qroute" --sonar "$W/repeat.xtf" --lines 300 --stride 150 --csv "$W/bad.csv" 2> "$W/bad.err"
rc=$?
[ $rc -eq 1 ] || fail "damaged route: exit $rc, want 1"
grep -q -i "crc\|corrupt\|damaged" "$W/bad.err" || fail "damaged route: message does not say so: $(cat "$W/bad.err")"
echo "PASS"
