# demo: side-scan sonar - real Iver2 XTF (Scotsman wreck) to waterfall and north-up tiles; simulator
# Runs from the repository root with QNAV (tool), OUT (output dir), SHARED (shared dir). Look at the
# PNGs: the wreck of the Scotsman must be visible in the waterfall and in the tile.
set -euo pipefail
D="$OUT/sonar"
mkdir -p "$D/tiles" "$D/sim_tiles"
XTF="$SHARED/data/sidescan/cidco-scotsman-iver2/scotsman-iver2.xtf"
MB="$SHARED/data/sidescan/cidco-r2sonic-multibeam-xtf/0009-150708_R2Testing-0001.xtf"

if [ -f "$XTF" ]; then
  echo "-- qnav xtf info: the real Iver2 / Marine Sonic 600 kHz file"
  "$QNAV" xtf info "$XTF"
  echo
  echo "-- waterfall (raw) and corrected waterfall (first-return detection, slant->ground, TVG + EGN)"
  "$QNAV" sonar waterfall "$XTF" --out "$D/scotsman_waterfall.png"
  "$QNAV" sonar waterfall "$XTF" --out "$D/scotsman_waterfall_corrected.png" --corrected
  echo
  echo "-- north-up tile at 0.1 m from all 460 navigated pings (paper: a tile per 500 scanlines)"
  "$QNAV" sonar tiles "$XTF" --out "$D/tiles"
  cat "$D/tiles/tiles.csv"
else
  echo "(skipped: $XTF not present)"
fi
if [ -f "$MB" ]; then
  echo
  echo "-- a multibeam XTF (no side-scan channels): read to the end, packets skipped and counted"
  "$QNAV" xtf info "$MB" | sed -n '1,2p;8,12p'
fi
echo
echo "-- simulator: 150 m pass over a procedural seabed with a 14 m wreck, written as XTF, tiled back"
"$QNAV" sonar simulate --out "$D/sim.xtf" --length-m 150 --samples 1024 --range-m 40 --truth "$D/sim_truth.png"
"$QNAV" sonar tiles "$D/sim.xtf" --out "$D/sim_tiles" --lines 500 --res 0.1
echo
echo "-- the same pass as an EdgeTech JSF stream (message 80 per side), framed and paired, tiled"
mkdir -p "$D/jsf_tiles"
"$QNAV" sonar simulate --out "$D/sim.jsf" --length-m 150 --samples 1024 --range-m 40
"$QNAV" sonar tiles "$D/sim.jsf" --out "$D/jsf_tiles" --lines 500 --res 0.1
echo
echo "outputs: $D/scotsman_waterfall*.png, $D/tiles/tile_000_plot.png (metres, scale bar, north arrow), $D/sim_tiles/, $D/sim_truth.png"
