#!/bin/bash
# qnavd replays a recorded dive's sensor logs (firmware/qnavd/sim_replay.hpp) through the real daemon:
#  1. the side-scan files of a teach pass and a repeat pass 8 m to starboard, each with the AHRS as a
#     `candump -l` log and the DVL as a capture of its sentences (`qnav sonar simulate --candump
#     --dvl-log`): the repeat's estimates must equal those of the same files replayed with their own
#     navigation (the logs carry that navigation): the same node and the same cross-track (to the
#     log's 0.01 m) on every tile, on a loaded machine too (the nav worker places a ping with the inputs
#     that had arrived before it, whatever its lag, and the sim's mode handshakes run in lockstep with
#     the worker: a replay is reproducible), and be on the 8 m offset;
#  2. a mode command and a frame of qnavd's own in the log are skipped and counted; a DVL capture
#     whose checksums are all wrong is refused sentence by sentence by the real driver (dvl_rejected,
#     the eq. 5 fallback), so the capture is what the daemon reads;
#  3. a stereo sequence (KITTI, ../shared/data; skipped without it) in a vo pass: the daemon's VO
#     positions equal `qnav vo --kitti` frame by frame (the same VoOdometry and preset), within 1 mm.
# Usage: $0 QNAVD QNAV WORKDIR SHARED_DIR
set -u
D=$1
Q=$2
W=$3
S=$4
rm -rf "$W" && mkdir -p "$W" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
"$Q" sonar simulate --out "$W/teach.xtf" --length-m 400 --seed 5 --candump "$W/teach.can" --dvl-log "$W/teach.dvl" >/dev/null ||
  fail "simulate teach"
"$Q" sonar simulate --out "$W/repeat.xtf" --length-m 400 --offset-m 8 --seed 5 --pass-seed 6 --start-s 1700001000 \
  --candump "$W/repeat.can" --dvl-log "$W/repeat.dvl" >/dev/null || fail "simulate repeat"
# An autopilot's mode command and one of qnavd's own frames, as a bus log of a real dive has them.
{ echo "(1700000000.050000) can0 110#04000001"; echo "(1700000000.060000) can0 200#0000000000000000"; cat "$W/teach.can"; } > "$W/teach_bus.can"
# config NAME TEACH_EXTRA REPEAT_EXTRA
config() {
  cat > "$W/$1.toml" <<CFG
[daemon]
backend = "sim"
route_dir = "$W/routes_$1"
log = "json"
realtime = false
[sim]
replay_lines = 300
replay_stride = 150
[[sim.pass]]
mode = "teach"
file = "$W/teach.xtf"
$2
[[sim.pass]]
mode = "repeat"
file = "$W/repeat.xtf"
$3
CFG
}
tiles() { grep '"event":"tile"' "$1" | grep '"mode":"repeat"' |
  sed 's/.*"estimate":\([0-9]*\).*"status":"\([a-z_]*\)","side":"\([a-z_]*\)","cross_track_m":\([-0-9.]*\).*/\1 \2 \3 \4/'; }
config own "" ""
config logs "candump = \"$W/teach_bus.can\"
dvl_log = \"$W/teach.dvl\"" "candump = \"$W/repeat.can\"
dvl_log = \"$W/repeat.dvl\""
for c in own logs; do
  "$D" --config "$W/$c.toml" > "$W/$c.jsonl" 2> "$W/$c.err" || fail "qnavd ($c) exit $?: $(cat "$W/$c.err")"
  tiles "$W/$c.jsonl" > "$W/$c.txt"
done
n=$(wc -l < "$W/teach.can")
grep -q "pass 0 replays candump .*: $n frames over .* (2 skipped" "$W/logs.err" || { cat "$W/logs.err"; fail "the log's mode command and qnavd frame were not skipped"; }
grep -q "DVL .*teach.dvl: $n reports over" "$W/logs.err" || { cat "$W/logs.err"; fail "the DVL capture was not loaded whole"; }
paste -d' ' "$W/own.txt" "$W/logs.txt" |
  awk '{ n++; if ($1 == $5) same++; e = $1 - $5; if (e < 0) e = -e; if (e > 1) far++
         d = $4 - $8; if (d < 0) d = -d; if (d > dmax) dmax = d; if (d <= 0.1) near++
         if ($6 == "tracking") { t++; if ($7 == "starboard" && $8 > 6.5 && $8 < 9.5) ok++ } }
       END { printf "replay with logs vs own navigation: %d repeat tiles, same estimate %d, more than one node apart %d, cross-track within 0.1 m on %d, at most %.2f m apart; tracking %d, starboard 6.5-9.5 m %d\n", n, same, far, near, dmax, t, ok;
             exit !(n >= 10 && same == n && dmax <= 0.005 && t >= 0.8 * n && ok == t) }' || fail "the logs' navigation does not reproduce the file's"
[ "$(wc -l < "$W/own.txt")" -eq "$(wc -l < "$W/logs.txt")" ] || fail "different numbers of repeat tiles"
grep '"event":"health"' "$W/logs.jsonl" | tail -1 | grep -q '"dvl_rejected":0,' || fail "the recorded DVL sentences were rejected"
# The capture is what the daemon reads: with every checksum wrong, the driver refuses every sentence.
sed 's/\*[0-9a-f][0-9a-f]$/*00/' "$W/repeat.dvl" > "$W/bad.dvl"
config bad "" "dvl_log = \"$W/bad.dvl\""
"$D" --config "$W/bad.toml" > "$W/bad.jsonl" 2> "$W/bad.err" || fail "qnavd (bad DVL) exit $?"
rej=$(grep '"event":"health"' "$W/bad.jsonl" | tail -1 | sed 's/.*"dvl_rejected":\([0-9]*\).*/\1/')
[ "$rej" -ge "$n" ] || fail "a DVL capture with bad checksums: $rej sentences rejected, expected every one of $n"
grep '"event":"tile"' "$W/bad.jsonl" | grep '"mode":"repeat"' | grep -q '"eq5":true' || fail "no eq. 5 fallback without usable DVL velocities"
echo "bad DVL capture: $rej sentences rejected, the repeat fell back to eq. 5"
# A log that is not a candump log: a clear start-up error.
config notlog "candump = \"$W/teach.dvl\"" ""
"$D" --config "$W/notlog.toml" > /dev/null 2> "$W/notlog.err" && fail "a DVL capture was accepted as a candump log"
grep -q "no frame to replay" "$W/notlog.err" || { cat "$W/notlog.err"; fail "no reason given for the bad candump log"; }

K="$S/data/stereo/kitti_raw_2011_09_26_0013_city100"
if [ ! -d "$K/left" ]; then
  echo "replay logs: ok (KITTI stereo replay skipped: no $K)"
  exit 0
fi
cat > "$W/kitti.toml" <<CFG
[daemon]
backend = "sim"
route_dir = "$W/routes_kitti"
log = "json"
realtime = false
[dvl]
enabled = false
[vo]
preset = "kitti"
width = 1242
height = 375
focal_px = 721.5377
cu_px = 609.5593
cv_px = 172.854
baseline_m = 0.53715
tilt_down_deg = 0.0
mount_height_m = 0.0
[[sim.pass]]
mode = "vo"
images = "$K"
max_frames = 20
CFG
"$D" --config "$W/kitti.toml" > "$W/kitti.jsonl" 2> "$W/kitti.err" || fail "qnavd (kitti) exit $?: $(cat "$W/kitti.err")"
"$Q" vo --kitti "$K" --frames 20 --out "$W/tool_poses.txt" > /dev/null || fail "qnav vo --kitti"
# KITTI poses: camera x right, y down, z forward; the daemon's body (camera level, no lever arm): north = z, east = x, down = y.
grep '"event":"vo"' "$W/kitti.jsonl" | sed 's/.*"north_m":\([-0-9.]*\),"east_m":\([-0-9.]*\),"down_m":\([-0-9.]*\).*/\1 \2 \3/' > "$W/daemon_vo.txt"
awk '{ print $12, $4, $8 }' "$W/tool_poses.txt" | paste -d' ' - "$W/daemon_vo.txt" |
  awk '{ n++; d = sqrt(($1 - $4)^2 + ($2 - $5)^2 + ($3 - $6)^2); if (d > dmax) dmax = d; end = $1 }
       END { printf "KITTI replay vs qnav vo --kitti: %d pairs, %.1f m forward, positions differ by at most %.2f mm\n", n, end, 1000 * dmax;
             exit !(n == 20 && end > 20 && dmax <= 0.001) }' || fail "the daemon's VO differs from the tool's"
echo "replay logs: ok"
