"""`qnav map eval --fig3-csv` (the underwater paper's Fig. 3) and the eval's mosaic, on a short loop:
  - the CSV has, for every run (none, filter1 .. filter5), keypoints, matches, true_matches and
    inliers per frame; the reference frame has no matches; every other frame of every run has
    0 < true matches <= matches <= keypoints <= 400 (the chain's max_keypoints) and at least the
    chain's 15-inlier registration floor of true matches (every frame registers on this loop);
  - the filters cost true matches: each filter's median is below the clean run's, and the clean run's
    matches are mostly true (>= 80 %; measured 90 %);
  - `--out` writes map_mosaic.png (a PNG) beside the map CSVs; the JSON stays valid with no revisit
    frames (revisits_recognised_pct null on a loop shorter than a lap + 3 frames).

  map_fig3_test.py QNAV WORK_DIR
"""
import csv
import json
import os
import shutil
import statistics
import subprocess
import sys

RUNS = ("none", "filter1", "filter2", "filter3", "filter4", "filter5")


def main():
    qnav, work = sys.argv[1:3]
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    fig3 = os.path.join(work, "fig3.csv")
    cmd = [qnav, "map", "eval", "--json", "--frames-per-lap", "40", "--laps", "1.05", "--fig3-csv", fig3, "--out", work]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    print(" ".join(cmd))
    print(p.stdout.strip(), p.stderr.strip())
    failures = []

    def check(cond, what):
        if not cond:
            failures.append(what)

    check(p.returncode == 0, "eval exit %d" % p.returncode)
    r = json.loads(p.stdout)
    check(r["runs"]["none"]["revisits_recognised_pct"] is None, "revisits on a loop without a second pass should be null")
    with open(fig3, encoding="utf-8") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    check(len(rows) == 42, "%d frames in the CSV, expected 42" % len(rows))
    medians = {}
    for run in RUNS:
        cols = ["%s_%s" % (c, run) for c in ("keypoints", "matches", "true_matches", "inliers")]
        missing = [c for c in cols if c not in rows[0]]
        check(not missing, "columns missing: %s" % missing)
        if missing:
            continue
        check(all(rows[0][c] == "" for c in cols[1:]), "%s: the reference frame has matches" % run)
        true = []
        for row in rows[1:]:
            kp, m, t, inl = (int(row[c]) for c in cols)
            check(15 <= t <= m <= kp <= 400, "%s frame %s: true %d, matches %d, keypoints %d" % (run, row["frame"], t, m, kp))
            check(0 < inl <= m, "%s frame %s: inliers %d of %d matches" % (run, row["frame"], inl, m))
            true.append(t)
        medians[run] = statistics.median(true)
        if run == "none":
            ratio = sum(true) / sum(int(row[cols[1]]) for row in rows[1:])
            check(ratio >= 0.8, "clean run: %.2f of the matches true, expected >= 0.8" % ratio)
    for run in RUNS[1:]:
        if run in medians and "none" in medians:
            check(medians[run] < medians["none"], "%s: median true matches %s not below the clean run's %s" % (run, medians[run], medians["none"]))
    png = os.path.join(work, "map_mosaic.png")
    check(os.path.isfile(png) and open(png, "rb").read(8) == b"\x89PNG\r\n\x1a\n", "map_mosaic.png missing or not a PNG")
    print("median true matches per frame:", medians)
    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
