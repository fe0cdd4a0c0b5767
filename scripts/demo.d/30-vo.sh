# demo: stereo visual odometry (Mars paper) - synthetic Mars yard with the paper's noise, EuRoC hover
# Runs from the repository root with QNAV (tool), OUT (output dir), SHARED (shared dir).
# Short runs (6 m and 10 m instead of 27 m and 100 m); the full evaluation is `qnav vo eval --json`.
set -euo pipefail
D="$OUT/vo"
mkdir -p "$D"
echo "-- synthetic Mars yard, 320x256, paper's small noise (n_t 10 %, attitude 0.1/0.01/0.01 deg), 3D-VME fc fast"
"$QNAV" vo eval --quick --json | tee "$D/vo_eval_quick.json"
EUROC="$SHARED/data/stereo/euroc_v1_01_hover40"
if [ -d "$EUROC" ]; then
  echo
  echo "-- EuRoC V1_01 hover, 40 raw pairs rectified by nav/vision, 6D-VME (truth: 1.9 mm max displacement)"
  "$QNAV" vo --euroc "$EUROC" --out "$D/euroc_poses.txt" | tail -1
fi
