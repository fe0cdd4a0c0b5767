# demo: vision front end - stereo at Harris corners vs Middlebury GT, EuRoC rectification, underwater degradation
# Runs the real sample images through nav/vision (via `qnav stereo`); each line printed is measured now.
set -euo pipefail
D="$SHARED/data/stereo"
if [ ! -d "$D" ]; then
  echo "skipped: no sample data in $D"
  exit 0
fi
"$QNAV" stereo aloe --dir "$D/middlebury_aloe_opencv"
"$QNAV" stereo euroc-rectify "$D/euroc_v1_01_hover40" --out "$OUT/vision_euroc_rectified.png"
K="$D/kitti_raw_2011_09_26_0013_city100"
"$QNAV" stereo disparity "$K/left/0000000000.png" "$K/right/0000000000.png" --max-disparity 128 \
  --out "$OUT/vision_kitti_disparity.png"
"$QNAV" stereo degrade "$K/left/0000000000.png" --filter 5 --out "$OUT/vision_kitti_degraded_filter5.png"
