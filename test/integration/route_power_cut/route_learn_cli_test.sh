#!/bin/bash
# Routes that learn (issue 29), the tool's side: `qnav route repeat --learn` appends experiences to
# ROUTE.exp and never touches the route file; `route info` lists them; a pass over another seabed
# (the wrong route) learns nothing; a learning repeat killed with SIGKILL, and a torn last record
# (a power cut mid-append), leave every fully written experience readable, the tail reported and
# cut by the next learning repeat; contradictory options are refused.
# Usage: $0 QNAV WORKDIR
set -u
Q=$1
W=$2
rm -rf "$W" && mkdir -p "$W" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
LEN=1000
"$Q" route train --sim --length-m $LEN --seed 3 --out "$W/a.qroute" > /dev/null || fail "train"
cp "$W/a.qroute" "$W/orig.qroute"
KP=$(od -An -tu2 -j14 -N2 "$W/a.qroute" | tr -d ' ')
REC=$((48 + KP * 76 + 4))
records() { echo $(( ($(stat -c %s "$W/a.qroute.exp") - 64) / REC )); }

# 1. Learning: a reverse pass at 30 % of the swath.
"$Q" route repeat --route "$W/a.qroute" --sim --length-m $LEN --seed 3 --reverse --offset-pct 30 --learn --csv "$W/l1.csv" > "$W/l1.txt" 2>&1 \
  || { cat "$W/l1.txt"; fail "repeat --learn"; }
N=$(sed -n 's/^learned \([0-9]*\) experiences.*/\1/p' "$W/l1.txt")
[ -n "$N" ] && [ "$N" -ge 1 ] || fail "nothing learned: $(cat "$W/l1.txt")"
[ "$(records)" -eq "$N" ] || fail "ROUTE.exp holds $(records) records, $N learned"
cmp -s "$W/a.qroute" "$W/orig.qroute" || fail "learning changed the route file"
"$Q" route info "$W/a.qroute" > "$W/info1.txt" || { cat "$W/info1.txt"; fail "info after learning"; }
grep -q "experiences: .*a.qroute.exp: format 1, <= 4 per node, $N records, $N live" "$W/info1.txt" || fail "info: $(cat "$W/info1.txt")"
[ "$(grep -c '^  node [0-9]*: [0-9] \[pass 1 reverse offset' "$W/info1.txt")" -ge 1 ] || fail "info lists no node's experiences"

# 2. The wrong route: a pass over another seabed learns nothing (backfill on: it never has a confirmed fix).
"$Q" route repeat --route "$W/a.qroute" --sim --length-m $LEN --seed 9 --reverse --offset-pct 30 --learn --backfill --csv "$W/w.csv" > "$W/w.txt" 2>&1 \
  || { cat "$W/w.txt"; fail "repeat --learn (wrong route)"; }
grep -q "^learned 0 experiences" "$W/w.txt" || fail "the wrong route learned: $(cat "$W/w.txt")"
[ "$(records)" -eq "$N" ] || fail "the wrong route added records"

# 3. Killed while learning (SIGKILL at a moment after the first new record), then a torn last record.
"$Q" route repeat --route "$W/a.qroute" --sim --length-m $LEN --seed 3 --reverse --offset-pct 40 --learn --csv "$W/k.csv" > /dev/null 2>&1 &
pid=$!
for i in $(seq 1 400); do
  [ "$(records)" -gt "$N" ] && break
  kill -0 $pid 2> /dev/null || break
  sleep 0.02
done
kill -9 $pid 2> /dev/null
wait $pid 2> /dev/null
K=$(records)
[ $(( ($(stat -c %s "$W/a.qroute.exp") - 64) % REC )) -eq 0 ] || fail "kill -9 left a partial record (page cache survives a kill)"
head -c $((REC / 2)) /dev/urandom >> "$W/a.qroute.exp"
"$Q" route info "$W/a.qroute" > "$W/info2.txt" || { cat "$W/info2.txt"; fail "info after a power cut while learning"; }
grep -q "$K records, $K live, torn tail $((REC / 2)) bytes after record $K (ignored)" "$W/info2.txt" || fail "torn tail not reported: $(grep experiences "$W/info2.txt")"
"$Q" route repeat --route "$W/a.qroute" --sim --length-m $LEN --seed 3 --reverse --offset-pct 50 --learn --csv "$W/l3.csv" > "$W/l3.txt" 2>&1 \
  || { cat "$W/l3.txt"; fail "repeat --learn after the torn tail"; }
grep -q "torn tail: $((REC / 2)) bytes after record $K (a partial experience, cut)" "$W/l3.txt" || fail "repeat did not report the torn tail: $(cat "$W/l3.txt")"
[ $(( ($(stat -c %s "$W/a.qroute.exp") - 64) % REC )) -eq 0 ] || fail "the torn tail was not cut"
"$Q" route info "$W/a.qroute" > "$W/info3.txt" || fail "info after resuming"
cmp -s "$W/a.qroute" "$W/orig.qroute" || fail "learning changed the route file"

# 4. Without experiences, and contradictory options.
"$Q" route repeat --route "$W/a.qroute" --sim --length-m $LEN --seed 3 --no-experiences --csv "$W/n.csv" > "$W/n.txt" 2>&1 || fail "--no-experiences"
grep -q "experiences of" "$W/n.txt" && fail "--no-experiences read the experiences"
"$Q" route repeat --route "$W/a.qroute" --sim --learn --no-experiences > /dev/null 2>&1
[ $? -eq 2 ] || fail "--learn --no-experiences not refused with exit 2"
echo "route learn CLI: $N learned at 30 %, 0 on the wrong route, $K records after the kill, torn tail reported and cut"
