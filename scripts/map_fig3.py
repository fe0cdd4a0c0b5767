#!/usr/bin/python3
"""The underwater paper's Fig. 3 (top) from `qnav map eval --fig3-csv FILE` (Debian's
python3-matplotlib: run with /usr/bin/python3).

  map_fig3.py FIG3.csv OUT.png

Top: keypoints per frame of the synthetic loop, one line per run (no degradation, Table-1 filters 1-5).
Bottom: true matches per frame (ratio-test matches within the CSV's tolerance of the true transfer to
the keyframe), same runs. The reference frame (no matching) is left out. Legend beside the axes, never
over the data (scripts/qnav_plot.py).
"""
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from qnav_plot import axes_labels, legend_outside, plt  # noqa: E402

RUNS = ("none", "filter1", "filter2", "filter3", "filter4", "filter5")


def read(path):
    with open(path, encoding="utf-8") as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def series(rows, col):
    xs, ys = [], []
    for r in rows:
        if r.get(col, "") != "":
            xs.append(int(r["frame"]))
            ys.append(float(r[col]))
    return xs, ys


def main(path, out):
    rows = read(path)
    runs = [r for r in RUNS if f"keypoints_{r}" in rows[0]]
    fig, (ak, am) = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
    for run in runs:
        label = "no filter" if run == "none" else run.replace("filter", "filter ")
        style = dict(lw=1.6, color="k") if run == "none" else dict(lw=1.0)
        ak.plot(*series(rows, f"keypoints_{run}"), label=label, **style)
        am.plot(*series(rows, f"true_matches_{run}"), label=label, **style)
    ak.set_title("synthetic downward loop under the paper's Table-1 filters (qnav map eval)")
    axes_labels(ak, "", "keypoints per frame", integer_x=True)
    axes_labels(am, "frame", "true matches per frame", integer_x=True)
    ak.set_ylim(bottom=0)
    am.set_ylim(bottom=0)
    legend_outside(ak)
    fig.tight_layout()
    fig.savefig(out, dpi=80)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
