#!/bin/bash
# SIGTERM while teaching: qnavd exits 0 within its shutdown bound, the route is committed with every
# completed node readable (CRC), nothing torn. Usage: $0 QNAVD QNAV WORKDIR
set -u
D=$1
Q=$2
W=$3
rm -rf "$W" && mkdir -p "$W" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
cat > "$W/teach.toml" <<CFG
[daemon]
backend = "sim"
route_dir = "$W/routes"
log = "json"
realtime = false
[sim]
length_m = 20000.0
speed = "fast"
[[sim.pass]]
mode = "teach"
CFG
"$D" --config "$W/teach.toml" > "$W/log.jsonl" 2> "$W/err.txt" &
pid=$!
# Wait until at least 4 nodes are on disk (the .new file grows by one record per node).
for i in $(seq 1 600); do
  n=$(grep -c '"event":"tile"' "$W/log.jsonl" 2>/dev/null || true)
  [ "${n:-0}" -ge 4 ] && break
  kill -0 $pid 2>/dev/null || fail "qnavd exited before it was signalled: $(cat "$W/err.txt")"
  sleep 0.1
done
kill -TERM $pid
t0=$(date +%s%N)
wait $pid; rc=$?
ms=$(( ($(date +%s%N) - t0) / 1000000 ))
[ $rc -eq 0 ] || fail "exit $rc after SIGTERM: $(cat "$W/err.txt")"
[ $ms -lt 5000 ] || fail "took $ms ms to stop"
grep -q '"event":"stopped","signal":15' "$W/log.jsonl" || fail "no stopped event with signal 15"
written=$(grep -c '"event":"tile"' "$W/log.jsonl")
"$Q" route info "$W/routes/route_1.qroute" > "$W/info.txt" || { cat "$W/info.txt"; fail "route not readable after SIGTERM"; }
cat "$W/info.txt"
nodes=$(sed -n 's/.* \([0-9][0-9]*\) nodes,.*/\1/p' "$W/info.txt")
[ "$nodes" -ge 4 ] || fail "only $nodes nodes kept"
[ "$nodes" -eq "$written" ] || fail "$written tiles logged as taught but $nodes nodes in the file"
grep -q "torn" "$W/info.txt" && fail "torn tail after a clean stop"
echo "SIGTERM while teaching: exit 0 in $ms ms, $nodes nodes kept, all readable"
