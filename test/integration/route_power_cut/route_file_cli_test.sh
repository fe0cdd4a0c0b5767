#!/bin/bash
# What `qnav route info` and `qnav route repeat` say about route files that were cut off, torn,
# damaged in the middle, hold a CRC-valid NaN keypoint, or are version 1; and `route train --force`
# killed with SIGKILL: the old route is untouched until the new one is complete (issue 19).
# Usage: $0 QNAV WORKDIR
set -u
Q=$1
W=$2
rm -rf "$W" && mkdir -p "$W" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
LEN=700
"$Q" route train --sim --length-m $LEN --seed 3 --out "$W/a.qroute" > "$W/train.txt" || fail "train"
"$Q" route info "$W/a.qroute" > "$W/info.txt" || { cat "$W/info.txt"; fail "info on a fresh route"; }
grep -q "format version 2, closed cleanly (end mark: [0-9]* nodes)" "$W/info.txt" || fail "fresh route not reported closed cleanly: $(cat "$W/info.txt")"
grep -qi "torn\|cut off\|damaged" "$W/info.txt" && fail "fresh route reported damaged: $(cat "$W/info.txt")"
N=$(sed -n 's/.* \([0-9][0-9]*\) nodes,.*/\1/p' "$W/info.txt" | head -1)
[ "$N" -ge 8 ] || fail "only $N nodes"
KP=$(od -An -tu2 -j14 -N2 "$W/a.qroute" | tr -d ' ')
REC=$((48 + KP * 76 + 4))
cp "$W/a.qroute" "$W/orig.qroute"

# 1. No implicit replacement; --force killed mid-teach leaves the old route whole.
"$Q" route train --sim --length-m $LEN --seed 4 --out "$W/a.qroute" 2> "$W/exists.err" && fail "an existing route was replaced without --force"
grep -q -- "--force" "$W/exists.err" || fail "refusal does not mention --force: $(cat "$W/exists.err")"
cmp -s "$W/a.qroute" "$W/orig.qroute" || fail "refused train changed the route"
"$Q" route train --sim --length-m 2000 --seed 4 --out "$W/a.qroute" --force > /dev/null 2>&1 &
pid=$!
for i in $(seq 1 600); do  # until the new route holds a few nodes
  [ -f "$W/a.qroute.new" ] && [ "$(stat -c %s "$W/a.qroute.new")" -gt $((64 + 3 * REC)) ] && break
  sleep 0.05
done
kill -9 $pid; wait $pid 2>/dev/null
cmp -s "$W/a.qroute" "$W/orig.qroute" || fail "--force killed mid-teach changed the old route"
"$Q" route info "$W/a.qroute.new" > "$W/new.txt" || fail "info on the killed run's .new"
grep -q "CUT OFF: no end mark" "$W/new.txt" || fail "killed run not reported cut off: $(cat "$W/new.txt")"
"$Q" route train --sim --length-m $LEN --seed 5 --out "$W/a.qroute" --force > /dev/null 2> "$W/force.err" || fail "--force train: $(cat "$W/force.err")"
grep -q "kept as $W/a.qroute.new.kept.1" "$W/force.err" || fail "the killed run's nodes were not kept: $(cat "$W/force.err")"
cmp -s "$W/a.qroute" "$W/orig.qroute" && fail "--force did not replace the route"
"$Q" route info "$W/a.qroute" | grep -q "closed cleanly" || fail "replaced route not closed cleanly"

# 2. Cut off with a torn tail: the end mark and half of the last node lost.
cp "$W/orig.qroute" "$W/t.qroute"
truncate -s -$((16 + REC / 2)) "$W/t.qroute"
"$Q" route info "$W/t.qroute" > "$W/t.txt" || fail "info on a torn route: $(cat "$W/t.txt")"
grep -q "CUT OFF: no end mark" "$W/t.txt" || fail "torn route not reported cut off: $(cat "$W/t.txt")"
grep -q "torn tail: $((REC - REC / 2)) bytes after node $((N - 2)), the last complete one: the partial node $((N - 1)) was dropped" "$W/t.txt" || fail "torn tail not reported: $(cat "$W/t.txt")"
"$Q" route repeat --route "$W/t.qroute" --sim --length-m $LEN --seed 3 --csv "$W/t.csv" 2> "$W/t.err" || fail "repeat on a torn route: $(cat "$W/t.err")"
grep -q "WARNING.*CUT OFF" "$W/t.err" && grep -q "WARNING.*torn tail" "$W/t.err" || fail "repeat did not warn: $(cat "$W/t.err")"

# 3. Damaged nodes in the middle: every one named; repeat uses the good prefix, with a warning.
cp "$W/orig.qroute" "$W/d.qroute"
for k in 5 7; do printf '\x5a' | dd of="$W/d.qroute" bs=1 seek=$((64 + k * REC + 100)) conv=notrunc status=none; done
"$Q" route info "$W/d.qroute" > "$W/d.txt" && fail "info exit 0 on a damaged route"
grep -q "DAMAGED: node 5: route record CRC mismatch" "$W/d.txt" && grep -q "DAMAGED: node 7: route record CRC mismatch" "$W/d.txt" ||
  fail "damaged nodes not all named: $(cat "$W/d.txt")"
grep -q "2 of $N nodes damaged (counters: bad_record_crc=2); route repeat uses the good prefix, nodes 0..4" "$W/d.txt" || fail "summary: $(cat "$W/d.txt")"
"$Q" route repeat --route "$W/d.qroute" --sim --length-m $LEN --seed 3 --csv "$W/d.csv" 2> "$W/d.err" || fail "repeat on the good prefix: $(cat "$W/d.err")"
grep -q "WARNING.*node 5 is damaged: route record CRC mismatch; repeating on the good prefix, nodes 0..4 ($((N - 5)) later nodes not used; counters: bad_record_crc=1 nodes_unused=$((N - 5)))" "$W/d.err" ||
  fail "repeat warning: $(cat "$W/d.err")"
awk -F, 'NR > 1 && $3 > 4 { bad++ } END { exit bad > 0 }' "$W/d.csv" || fail "repeat estimated a node beyond the good prefix"
cp "$W/orig.qroute" "$W/d0.qroute"
printf '\x5a' | dd of="$W/d0.qroute" bs=1 seek=$((64 + REC + 100)) conv=notrunc status=none
"$Q" route repeat --route "$W/d0.qroute" --sim --length-m $LEN --seed 3 --csv "$W/d0.csv" 2> "$W/d0.err" && fail "repeat on a route damaged at node 1"
grep -q "node 1 is damaged: route record CRC mismatch; fewer than 2 good nodes before it: refused" "$W/d0.err" || fail "refusal: $(cat "$W/d0.err")"
grep -q "WARNING\|closed cleanly" "$W/d0.err" && fail "a clean route's end reported as a warning: $(cat "$W/d0.err")"

# 4. A CRC-valid node holding a NaN keypoint (a foreign writer): named, with the field counter.
cp "$W/orig.qroute" "$W/nan.qroute"
python3 - "$W/nan.qroute" $REC 3 <<'PY' || fail "python patch"
import struct, sys, zlib
path, rec, node = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
b = bytearray(open(path, "rb").read())
at = 64 + node * rec
b[at + 48 + 4: at + 48 + 8] = struct.pack("<f", float("nan"))  # keypoint 0, y_m
b[at + rec - 4: at + rec] = struct.pack("<I", zlib.crc32(bytes(b[at: at + rec - 4])) & 0xFFFFFFFF)
open(path, "wb").write(b)
PY
"$Q" route info "$W/nan.qroute" > "$W/nan.txt" && fail "info exit 0 on a NaN node"
grep -q "DAMAGED: node 3: route keypoint not finite" "$W/nan.txt" || fail "NaN node not named: $(cat "$W/nan.txt")"
grep -q "bad_record_field=1" "$W/nan.txt" || fail "NaN node not counted: $(cat "$W/nan.txt")"

# 5. Version 1 (no end mark): read, and said so.
cp "$W/orig.qroute" "$W/v1.qroute"
truncate -s -16 "$W/v1.qroute"
python3 - "$W/v1.qroute" <<'PY' || fail "python patch"
import struct, sys, zlib
b = bytearray(open(sys.argv[1], "rb").read())
b[8:10] = struct.pack("<H", 1)
b[60:64] = struct.pack("<I", zlib.crc32(bytes(b[0:60])) & 0xFFFFFFFF)
open(sys.argv[1], "wb").write(b)
PY
"$Q" route info "$W/v1.qroute" > "$W/v1.txt" || fail "info on a version 1 route: $(cat "$W/v1.txt")"
grep -q "no end marker: version 1" "$W/v1.txt" || fail "version 1 not reported: $(cat "$W/v1.txt")"
echo "PASS: route file reports (closed, cut off, torn, damaged, NaN, version 1) and --force killed mid-teach"
