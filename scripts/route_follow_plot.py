#!/usr/bin/python3
"""route_follow_plot.py CSV PNG [SEED]: the closed loop of `qnav route follow --sim --csv CSV`.

Top: plan view (north up, metres) of the taught track, the qnav-guided track and the track flown on
dead reckoning alone, for one seed (the first in the CSV unless SEED is given), with a scale bar and
a north arrow. Bottom: truth cross-track against the distance flown for every run in the CSV (qnav
guided and dead reckoning alone). Style: scripts/qnav_plot.py (legends outside the axes).
"""
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from qnav_plot import axes_labels, legend_outside, north_arrow, plt  # noqa: E402


def main():
    if len(sys.argv) < 3:
        sys.stderr.write("usage: route_follow_plot.py CSV PNG [SEED]\n")
        return 2
    rows = list(csv.DictReader(open(sys.argv[1])))
    if not rows:
        sys.stderr.write("route_follow_plot.py: %s has no rows\n" % sys.argv[1])
        return 1
    seeds = sorted({r["seed"] for r in rows}, key=int)
    seed = sys.argv[3] if len(sys.argv) > 3 else seeds[0]
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(10, 10), gridspec_kw={"height_ratios": [3, 2]})
    style = {"taught": ("k", "-", 2.5, "taught track"), "dead_reckoning": ("tab:red", "--", 1.2, "dead reckoning alone"),
             "qnav": ("tab:blue", "-", 1.2, "qnav-guided")}
    for track in ("taught", "dead_reckoning", "qnav"):
        pts = [r for r in rows if r["seed"] == seed and r["track"] == track]
        if not pts:
            continue
        c, ls, lw, label = style[track]
        ax.plot([float(r["east_m"]) for r in pts], [float(r["north_m"]) for r in pts], color=c, ls=ls, lw=lw, label=label)
    ax.set_aspect("equal", adjustable="datalim")
    axes_labels(ax, "east m", "north m")
    ax.set_title("seed %s: plan view (truth)" % seed)
    # Scale bar: a round length about a fifth of the width, lower left (limits after the equal aspect).
    ax.apply_aspect()
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    span = (x1 - x0) / 5.0
    bar = max(b for b in (10, 20, 50, 100, 200, 500, 1000, 2000, 5000) if b <= max(span, 10))
    bx0, by0 = x0 + 0.05 * (x1 - x0), y0 + 0.05 * (y1 - y0)
    ax.plot([bx0, bx0 + bar], [by0, by0], color="k", lw=3)
    ax.text(bx0 + bar / 2, by0 + 0.015 * (y1 - y0), "%d m" % bar, ha="center", va="bottom", fontsize=9)
    north_arrow(ax)
    legend_outside(ax)
    first = {"qnav": True, "dead_reckoning": True}
    for s in seeds:
        for track in ("dead_reckoning", "qnav"):
            pts = [r for r in rows if r["seed"] == s and r["track"] == track]
            if not pts:
                continue
            c, ls, lw, label = style[track]
            bx.plot([float(r["travelled_m"]) for r in pts], [float(r["cross_track_m"]) for r in pts], color=c, ls=ls, lw=0.8,
                    alpha=0.7, label=label if first[track] else None)
            first[track] = False
    axes_labels(bx, "distance flown m", "truth cross-track m (+ right)")
    bx.set_title("cross-track from the taught track, %d seed(s)" % len(seeds))
    legend_outside(bx)
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110, bbox_inches="tight")
    return 0


if __name__ == "__main__":
    sys.exit(main())
