# demo: qnavd, the flight daemon, flies a mission on the simulated vehicle (teach, repeat forwards and in reverse with lateral offsets; modes switched by CAN)
set -eu
out="$OUT/qnavd"
mkdir -p "$out"
rm -rf build/demo/routes build/demo/qnavd.candump
# The daemon is configured by one TOML file; check it, and show the static pipeline it gives.
"$QNAVD" --check-config firmware/qnavd/config/sim.toml
"$QNAVD" --print-deployment --config firmware/qnavd/config/sim.toml
# The real daemon on the sim backend: the simulated autopilot commands teach, then three repeat passes,
# over an in-process CAN bus; the AHRS, the DVL (Water Linked sentences) and the side-scan feed it.
start=$(date +%s.%N)
"$QNAVD" --config firmware/qnavd/config/sim.toml > "$out/qnavd.jsonl"
end=$(date +%s.%N)
echo "qnavd flew the mission in $(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }') s (wall clock): $(grep -c '"event":"tile"' "$out/qnavd.jsonl") tiles logged to $out/qnavd.jsonl"
/usr/bin/python3 scripts/qnavd_report.py "$out/qnavd.jsonl" "$out"
# What the autopilot saw on the bus, decoded with the DBC (the companion ROUTE_STATUS frame carries
# the guidance status, side and cross-track sigma).
"$QNAV" route info build/demo/routes/route_1.qroute
grep ' 203#' build/demo/qnavd.candump | sed -n '6000p' > "$out/route_status.log"
grep ' 200#' build/demo/qnavd.candump | sed -n '6000p' >> "$out/route_status.log"
"$QNAV" can decode "$out/route_status.log"
