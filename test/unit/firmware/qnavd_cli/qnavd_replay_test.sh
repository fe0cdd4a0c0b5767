#!/bin/bash
# qnavd replays recorded side-scan passes (a [[sim.pass]] with a file) through the same pipeline as
# `qnav route train|repeat --sonar`: teach on a simulated JSF pass, repeat on a second XTF pass 8 m to
# starboard; the daemon's per-tile estimates must equal the tool's (same code path) and see the
# offset. Usage: $0 QNAVD QNAV WORKDIR
set -u
D=$1
Q=$2
W=$3
rm -rf "$W" && mkdir -p "$W" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
"$Q" sonar simulate --out "$W/teach.jsf" --length-m 600 --seed 5 >/dev/null || fail "simulate teach"
"$Q" sonar simulate --out "$W/repeat.xtf" --length-m 600 --offset-m 8 --seed 5 --pass-seed 6 >/dev/null || fail "simulate repeat"
"$Q" route train --sonar "$W/teach.jsf" --out "$W/cli.qroute" --lines 300 --stride 150 >/dev/null || fail "tool train"
"$Q" route repeat --route "$W/cli.qroute" --sonar "$W/repeat.xtf" --lines 300 --stride 150 --csv "$W/cli.csv" >/dev/null || fail "tool repeat"
cat > "$W/replay.toml" <<CFG
[daemon]
backend = "sim"
route_dir = "$W/routes"
log = "json"
realtime = false
[sim]
replay_lines = 300
replay_stride = 150
[[sim.pass]]
mode = "teach"
file = "$W/teach.jsf"
[[sim.pass]]
mode = "repeat"
file = "$W/repeat.xtf"
CFG
"$D" --config "$W/replay.toml" > "$W/qnavd.jsonl" 2> "$W/err.txt" || fail "qnavd exit $?: $(cat "$W/err.txt")"
"$Q" route info "$W/routes/route_1.qroute" || fail "the route qnavd taught is not readable"
# estimate status side cross_track per repeat tile, from each
grep '"event":"tile"' "$W/qnavd.jsonl" | grep '"mode":"repeat"' |
  sed 's/.*"estimate":\([0-9]*\).*"status":"\([a-z_]*\)","side":"\([a-z_]*\)","cross_track_m":\([-0-9.]*\).*/\1 \2 \3 \4/' > "$W/daemon.txt"
tail -n +2 "$W/cli.csv" | cut -d, -f3,8,9,11 | tr ',' ' ' > "$W/tool.txt"
paste -d' ' "$W/tool.txt" "$W/daemon.txt" |
  awk '{ n++; if ($1 == $5) same++; d = $1 - $5; if (d < 0) d = -d; if (d > 1) far++
         if ($6 == "tracking") { t++; if ($7 == "starboard" && $8 > 6.5 && $8 < 9.5) ok++ } }
       END { printf "qnavd replay vs qnav tool: %d tiles, same estimate %d, more than one node apart %d; daemon tracking %d, starboard 6.5-9.5 m %d\n", n, same, far, t, ok;
             exit !(n >= 10 && same >= 0.9 * n && far == 0 && t >= 0.8 * n && ok == t) }' || fail "the daemon and the tool disagree"
n_tool=$(wc -l < "$W/tool.txt"); n_daemon=$(wc -l < "$W/daemon.txt")
[ "$n_tool" -eq "$n_daemon" ] || fail "tool $n_tool repeat tiles, daemon $n_daemon"
# A recorded file that is not sonar data: a clear start-up error, exit 1.
sed "s|$W/repeat.xtf|$W/replay.toml|" "$W/replay.toml" > "$W/bad.toml"
"$D" --config "$W/bad.toml" > /dev/null 2> "$W/bad.txt" && fail "a non-sonar file was accepted"
grep -q "cannot be read as XTF or JSF" "$W/bad.txt" || { cat "$W/bad.txt"; fail "no reason given for the bad file"; }
echo "replay: ok"
