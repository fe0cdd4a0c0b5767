# demo: drivers - qnav's CAN interface (DBC), DroneCAN AHRS reassembly, DVL serial protocols
# Runs from the repository root with QNAV (tool), OUT (output dir). Every input is either a vendor-
# published sentence or traffic the tool simulates with injected faults; every fault must show up in
# a named counter.
set -euo pipefail
D="$OUT/drivers"
mkdir -p "$D"

echo "-- docs/qnav.dbc checked signal by signal against the codec"
"$QNAV" can dbc docs/qnav.dbc

echo
echo "-- 2 s of a simulated AHRS at 20 Hz: qnav ATTITUDE_IN + DroneCAN ahrs.Solution (node 42),"
echo "   with a corrupted frame, a lost frame and a repeated message every 10 steps"
"$QNAV" can simulate "$D/ahrs_candump.log" --seconds 2 --faults
"$QNAV" can decode "$D/ahrs_candump.log" | tail -n 8

echo
echo "-- Water Linked DVL-A50: the sentences published in the vendor's protocol document"
cat > "$D/wl_vendor.txt" <<'WL'
wru,0,0.070,1.10,-40,-95*9c
wru,1,-0.500,1.25,-62,-104*f0
wru,2,2.200,1.40,-56,-98*18
wru,3,1.800,1.35,-58,-96*a3
wrz,0.120,-0.400,2.000,y,1.30,1.855,1e-07;0;1.4;0;1.2;0;0.2;0;1e+09,7,14,123.00,1*50
wrp,49056.809,0.41,0.15,1.23,0.4,53.9,13.0,19.3,0*de
WL
"$QNAV" dvl parse "$D/wl_vendor.txt"

echo
echo "-- 4 s of simulated Water Linked output (8 Hz) with bad checksums, lock losses, repeats"
"$QNAV" dvl simulate "$D/wl_sim.txt" --seconds 4 --faults
"$QNAV" dvl parse "$D/wl_sim.txt" | tail -n 2

echo
echo "-- Teledyne RDI PD6: Water Linked's published PD6 ensemble"
printf '%s\r\n' ':SA, +0.00, +0.00,  0.00' ':TS,22020812061800, 0.0, +0.0,   0.0,1475.0,  0' \
  ':WI,    +0,    +0,    +0,    +0,V' ':WS,    +0,    +0,    +0,V' ':WE,    +0,    +0,    +0,V' \
  ':WD,       +0.00,       +0.00,       +0.00,   0.00,  0.00' ':BI,  +123,  -420, +2000,    +0,A' \
  ':BS,  -420,  +123, +2000,A' ':BE,    +0,    +0,    +0,V' \
  ':BD,       +0.00,       +0.00,       +0.00,   5.32,  0.00' > "$D/pd6_vendor.txt"
"$QNAV" dvl parse "$D/pd6_vendor.txt"
