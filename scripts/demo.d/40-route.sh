# demo: route teach and repeat on the side-scan simulator (train, file check, forward + reverse repeat)
set -eu
out="$OUT/route"
mkdir -p "$out"
rm -f "$out/demo.qroute"
# Teach a 900 m route (durable: one fdatasync per node), then check every record's CRC.
"$QNAV" route train --sim --length-m 900 --seed 3 --out "$out/demo.qroute" --force
"$QNAV" route info "$out/demo.qroute"
# Repeat 20% of the swath to starboard, forwards (survey) and in reverse (emergency return).
"$QNAV" route repeat --route "$out/demo.qroute" --sim --length-m 900 --seed 3 --offset-pct 20 --csv "$out/repeat_fwd.csv"
"$QNAV" route repeat --route "$out/demo.qroute" --sim --length-m 900 --seed 3 --offset-pct 20 --reverse --csv "$out/repeat_rev.csv"
echo "last tiles of the forward repeat (tile,true_node,estimate,probability,entropy,confident,inliers,status,side,true_side,cross_track_m):"
tail -n 4 "$out/repeat_fwd.csv" | cut -d, -f1-11
# A damaged file is detected, never half-read: flip one byte inside node 5 (record = 48 + 128 x 76 + 4
# bytes after the 64-byte header) and check again.
cp "$out/demo.qroute" "$out/damaged.qroute"
printf '\x5a' | dd of="$out/damaged.qroute" bs=1 seek=$((64 + 5 * (48 + 128 * 76 + 4) + 100)) conv=notrunc status=none
if "$QNAV" route info "$out/damaged.qroute"; then echo "ERROR: damage not detected"; exit 1; fi
# Real data: teach on the Iver2 pass (pings 0-300, 33 m) and repeat on a shifted window of the same
# pass, with the 12 m tiles every 6 m `qnav route xtf` uses for this short pass (the default tiles,
# sized from the swath and the file's length, would give one tile in 33 m).
X="$SHARED/data/sidescan/cidco-scotsman-iver2/scotsman-iver2.xtf"
if [ -f "$X" ]; then
  "$QNAV" route train --sonar "$X" --pings 0:301 --tile-length-m 12 --tile-stride-m 6 --out "$out/iver2.qroute" --force
  "$QNAV" route repeat --route "$out/iver2.qroute" --sonar "$X" --pings 90:461 --tile-length-m 12 --tile-stride-m 6 --csv "$out/iver2_repeat.csv"
  cut -d, -f1,3-9,11 "$out/iver2_repeat.csv"
else
  echo "(no $X: real-data step skipped)"
fi
# The same route teach and repeat on a downward camera over the synthetic Mars yard (3 m route).
"$QNAV" route camera --length-m 3
