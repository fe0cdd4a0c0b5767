# demo: qnavd, the flight daemon, flies a mission on the simulated vehicle (teach, repeat forwards and in reverse with lateral offsets, one repeat in closed loop on its own guidance, then visual odometry on a rover; modes switched by CAN)
set -eu
out="$OUT/qnavd"
mkdir -p "$out"
rm -rf build/demo/routes build/demo/qnavd.candump build/demo/qnavd_closed_loop.csv
# The daemon is configured by one TOML file; check it, and show the static pipeline it gives.
"$QNAVD" --check-config firmware/qnavd/config/sim.toml
"$QNAVD" --print-deployment --config firmware/qnavd/config/sim.toml
# The real daemon on the sim backend: the simulated autopilot commands teach, then three repeat passes
# and a visual-odometry pass (a rover with a stereo pair),
# over an in-process CAN bus; the AHRS, the DVL (Water Linked sentences) and the side-scan feed it.
start=$(date +%s.%N)
"$QNAVD" --config firmware/qnavd/config/sim.toml > "$out/qnavd.jsonl"
end=$(date +%s.%N)
echo "qnavd flew the mission in $(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }') s (wall clock): $(grep -c '"event":"tile"' "$out/qnavd.jsonl") tiles logged to $out/qnavd.jsonl"
# The mission from the daemon's log against the simulator's truth: a table per repeat tile and
# qnavd_mission.png (the track in the route's frame, the node estimate coloured by its belief, the
# cross-track), qnavd_vo.png (the rover's VO track over the true one).
/usr/bin/python3 scripts/qnavd_report.py "$out/qnavd.jsonl" "$out"
# Pass 4 flew in closed loop (sim.pass.closed_loop): the vehicle steered on the QNAV_ROUTE_GUIDANCE
# frames it heard, a twin on dead reckoning alone; the truth cross-track of both, and the plan view.
grep '"event":"sim_closed_loop"' "$out/qnavd.jsonl"
/usr/bin/python3 scripts/route_follow_plot.py build/demo/qnavd_closed_loop.csv "$out/qnavd_closed_loop.png"
echo "closed loop: taught, dead-reckoning-only and qnav-guided tracks in $out/qnavd_closed_loop.png"
# What the autopilot saw on the bus, decoded with the DBC (the companion ROUTE_STATUS frame carries
# the guidance status, side and cross-track sigma).
"$QNAV" route info build/demo/routes/route_1.qroute
# (ROUTE_STATUS with Tracking + Starboard starts 203#20; NAV_STATUS in Repeat and localised, 200#12)
grep -m 1 ' 203#20' build/demo/qnavd.candump > "$out/route_status.log"
grep -m 1 ' 200#12' build/demo/qnavd.candump >> "$out/route_status.log"
# (QNAV_VO_STEP, 0x202: the rover's motion since the previous one, from the vo pass)
grep -m 2 ' 202#' build/demo/qnavd.candump >> "$out/route_status.log"
"$QNAV" can decode "$out/route_status.log"
# A recorded dive through the same daemon: the Iver2's XTF replayed as its sonar, AHRS and DVL would
# deliver it (teach on pings 0-300, repeat on 90-460: the tool's own demo below does the same).
X="$SHARED/data/sidescan/cidco-scotsman-iver2/scotsman-iver2.xtf"
if [ -f "$X" ]; then
  rm -rf "$out/iver2_routes"
  cat > "$out/iver2.toml" <<CFG
[daemon]
backend = "sim"
route_dir = "$out/iver2_routes"
log = "json"
realtime = false
[sim]
replay_lines = 100
replay_stride = 50
[[sim.pass]]
mode = "teach"
file = "$X"
first_ping = 0
last_ping = 301
[[sim.pass]]
mode = "repeat"
file = "$X"
first_ping = 90
last_ping = 461
CFG
  "$QNAVD" --config "$out/iver2.toml" > "$out/iver2.jsonl"
  echo "qnavd on the recorded Iver2 dive, repeat tiles (estimate, status, side, cross-track m):"
  grep '"event":"tile"' "$out/iver2.jsonl" | grep '"mode":"repeat"' |
    sed 's/.*"estimate":\([0-9]*\).*"status":"\([a-z_]*\)","side":"\([a-z_]*\)","cross_track_m":\([-0-9.]*\).*/  \1 \2 \3 \4/'
else
  echo "(no $X: the recorded-dive replay is skipped)"
fi
# A recorded stereo sequence through the same daemon: the KITTI city drive (100 pairs, a car's camera
# without an attitude sensor) replayed into the frame pool in Mode = Vo, with the KITTI preset that
# `qnav vo --kitti` uses (firmware/pipeline/vo_defaults).
K="$SHARED/data/stereo/kitti_raw_2011_09_26_0013_city100"
if [ -d "$K/left" ]; then
  rm -rf "$out/kitti_routes"
  cat > "$out/kitti.toml" <<CFG
[daemon]
backend = "sim"
route_dir = "$out/kitti_routes"
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
CFG
  "$QNAVD" --config "$out/kitti.toml" > "$out/kitti.jsonl" 2> "$out/kitti.err"
  grep '"event":"vo"' "$out/kitti.jsonl" |
    awk -F'[:,]' '{ for (i = 1; i < NF; i++) { if ($i == "\"visual\"") v += ($(i + 1) == "true"); if ($i == "\"north_m\"") n = $(i + 1); if ($i == "\"east_m\"") e = $(i + 1) } k++ }
         END { printf "qnavd on the recorded KITTI drive: %d stereo pairs, %d visual steps, end %.1f m north, %.1f m east of the start (libviso2, a peer: 115 m path)\n", k, v, n, e }'
else
  echo "(no $K: the recorded stereo replay is skipped)"
fi
