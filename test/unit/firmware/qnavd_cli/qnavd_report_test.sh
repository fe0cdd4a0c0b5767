#!/bin/bash
# scripts/qnavd_report.py, the demo's view of a mission, on a real qnavd log: a short simulated
# mission (teach, one repeat 10 % of the swath to starboard) -> the per-pass summary scores the node
# estimate against the simulator's truth (>= 90 % within one node) and qnavd_mission.png is a real
# figure (a PNG of the figure's size, not blank: matplotlib reads it back); a log without a repeat
# tile exits 1 with the reason, no arguments exit 2.
# Usage: $0 QNAVD WORKDIR
set -u
D=$1
W=$2
R=$(cd "$(dirname "$0")/../../../.." && pwd)/scripts/qnavd_report.py
rm -rf "$W" && mkdir -p "$W/out" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
/usr/bin/python3 -c "import matplotlib" 2>/dev/null || { echo "SKIP: /usr/bin/python3 has no matplotlib (scripts/setup installs python3-matplotlib)"; exit 77; }
cat > "$W/mission.toml" <<CFG
[daemon]
backend = "sim"
route_dir = "$W/routes"
log = "json"
realtime = false
[sim]
length_m = 1500.0
speed = "fast"
[[sim.pass]]
mode = "teach"
[[sim.pass]]
mode = "repeat"
offset_pct = 10.0
CFG
"$D" --config "$W/mission.toml" > "$W/log.jsonl" 2> "$W/err.txt" || fail "qnavd exit $?: $(cat "$W/err.txt")"
/usr/bin/python3 "$R" "$W/log.jsonl" "$W/out" > "$W/report.txt" 2>&1 || { cat "$W/report.txt"; fail "qnavd_report.py exit $?"; }
grep -E "^taught route: [0-9]+ nodes" "$W/report.txt" || fail "no taught-route line"
line=$(grep -E "^pass 1 \(forward, offset \+[0-9.]+ m\): [0-9]+ tiles scored, node within \+/-1 [0-9.]+ %" "$W/report.txt") ||
  { cat "$W/report.txt"; fail "no summary of pass 1"; }
echo "$line"
pct=$(echo "$line" | sed -E 's/.*node within \+\/-1 ([0-9.]+) %.*/\1/')
tiles=$(echo "$line" | sed -E 's/.*: ([0-9]+) tiles scored.*/\1/')
awk -v p="$pct" -v n="$tiles" 'BEGIN { exit !(p >= 90 && n >= 5) }' || fail "pass 1: $tiles tiles, $pct % within one node (want >= 5 tiles, >= 90 %)"
png="$W/out/qnavd_mission.png"
[ -s "$png" ] || fail "no $png"
/usr/bin/python3 - "$png" <<'PY' || fail "qnavd_mission.png is not the mission figure"
import sys
import matplotlib.image as mpimg
a = mpimg.imread(sys.argv[1])
h, w = a.shape[0], a.shape[1]
std = float(a[..., :3].std())
print(f"qnavd_mission.png: {w} x {h} px, pixel std {std:.3f}")
# Three panels one above the other at 90 dpi (about 990 x 945 px), and ink on it (a blank figure has
# std ~0).
sys.exit(0 if w >= 900 and h >= 800 and std > 0.05 else 1)
PY
# A log with no repeat tile: exit 1 and the reason; no arguments: usage, exit 2.
grep -v '"mode":"repeat"' "$W/log.jsonl" > "$W/teach_only.jsonl"
/usr/bin/python3 "$R" "$W/teach_only.jsonl" "$W/out" > "$W/no_repeat.txt" 2>&1
rc=$?
[ $rc -eq 1 ] && grep -q "no teach and repeat tiles" "$W/no_repeat.txt" || { cat "$W/no_repeat.txt"; fail "a log without repeat tiles: exit $rc"; }
/usr/bin/python3 "$R" > /dev/null 2>&1
[ $? -eq 2 ] || fail "no arguments: want exit 2"
echo "PASS"
