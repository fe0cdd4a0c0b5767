#!/usr/bin/python3
# Plots for docs/route.md from the CSVs written by `qnav route eval --out DIR`.
# usage: /usr/bin/python3 scripts/route_plots.py DIR OUTDIR
#   route_offsets.png  node-within-1 and side-correct vs lateral offset, forward and reverse
#   route_fig5.png     measurement model p(z|w) per sensed tile (paper Fig. 5)
#   route_fig7.png     belief per sensed tile (paper Fig. 7)
#   route_fig9.png     true positions, estimated nodes and cross-track side arrows (paper Fig. 9/10)
#   (scripts/qnav_plot.py's style: legends outside the axes, colour bars labelled, north arrow on Fig. 9)
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from qnav_plot import axes_labels, colour_bar, legend_outside, north_arrow, plt  # noqa: E402


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def matrix(path):
    with open(path) as f:
        return [[float(v) for v in line.strip().split(",")] for line in f if line.strip()]


def main():
    src, out = sys.argv[1], sys.argv[2]
    offs = rows(src + "/route_eval_offsets.csv")
    fig, ax = plt.subplots(1, 2, figsize=(11, 5.4))
    for d, m in (("forward", "o-"), ("reverse", "s--")):
        r = [x for x in offs if x["direction"] == d]
        pct = [int(x["offset_pct"]) for x in r]
        ax[0].plot(pct, [float(x["within1_pct"]) for x in r], m, label=d + ": filter, node +/-1")
        if "registered_on_true_node_pct" in r[0]:
            ax[0].plot(pct, [float(x["registered_on_true_node_pct"]) for x in r], m, alpha=0.35,
                       label=d + ": registration alone on the true node")
        side = [100.0 * int(x["side_correct"]) / int(x["side_n"]) if int(x["side_n"]) else float("nan") for x in r]
        ax[1].plot(pct, side, m, label=d + " (side correct, of decided)")
        decided = [100.0 * int(x["side_n"]) / int(x["scored"]) if int(x["scored"]) and int(x["offset_pct"]) > 0 else float("nan") for x in r]
        ax[1].plot(pct, decided, m, alpha=0.4, label=d + " (side decided, of tiles)")
    axes_labels(ax[0], "lateral offset, % of swath", "% of tiles", grid=False)
    ax[0].set_ylim(0, 105)
    ax[0].axhline(95, color="gray", lw=0.5)
    legend_outside(ax[0], where="below", ncol=1, fontsize=7)
    ax[0].set_title("localisation vs offset")
    axes_labels(ax[1], "lateral offset, % of swath", "%", grid=False)
    ax[1].set_ylim(0, 105)
    ax[1].axhline(95, color="gray", lw=0.5)
    legend_outside(ax[1], where="below", ncol=1, fontsize=7)
    ax[1].set_title("route side (decided: a side reported, not unknown)")
    fig.tight_layout()
    fig.savefig(out + "/route_offsets.png", dpi=90)

    for name, title, value in (("fig5", "measurement model p(z|w) (paper Fig. 5)", "p(z|w)"), ("fig7", "belief bel(w) (paper Fig. 7)", "bel(w)")):
        m = matrix(src + "/route_%s.csv" % name)
        fig, ax = plt.subplots(figsize=(8.2, 4))
        im = ax.imshow(m, aspect="auto", cmap="viridis", origin="upper",
                       extent=(0.5, len(m[0]) + 0.5, len(m) + 0.5, 0.5))
        t1 = rows(src + "/route_table1.csv")
        ax.plot([int(x["truth"]) for x in t1], [int(x["sensed"]) for x in t1], "r+", ms=10, label="true node")
        axes_labels(ax, "training node", "sensed tile", grid=False)
        ax.set_title(title)
        colour_bar(fig, im, ax, value)
        legend_outside(ax, where="below", ncol=1, fontsize=7)
        fig.tight_layout()
        fig.savefig(out + "/route_%s.png" % name, dpi=90)

    f9 = rows(src + "/route_fig9.csv")
    fig, ax = plt.subplots(figsize=(6.4, 8.4))
    for x in f9:
        tn, te = float(x["true_north"]), float(x["true_east"])
        nn, ne = float(x["node_north"]), float(x["node_east"])
        ax.plot([te, ne], [tn, nn], ":", color="gray", lw=0.8)
        ax.plot(ne, nn, "ks", ms=5)
        ax.plot(te, tn, "bo", ms=6)
        ax.annotate(x["sensed"], (te, tn), fontsize=8, xytext=(4, 4), textcoords="offset points")
        if x["side"] != "unknown":
            # Arrow from the vehicle towards the route, |cross-track| long, on the reported side
            # (dashed: the filter was not yet confident, the side came from a strong registration).
            dn, de = nn - tn, ne - te
            d = max((dn * dn + de * de) ** 0.5, 1e-6)
            L = abs(float(x["cross_track_m"]))
            ok = x["side"] == x["true_side"]
            ax.annotate("", xy=(te + L * de / d, tn + L * dn / d), xytext=(te, tn),
                        arrowprops=dict(arrowstyle="->", color="g" if ok else "r", lw=1.5,
                                        ls="-" if x["status"] != "hold_course" else "--"))
    ax.plot([], [], "ks", label="estimated node (true position of its tile)")
    ax.plot([], [], "bo", label="true vehicle position at the sensed tile")
    ax.plot([], [], "g-", label="side reported and correct, steering (tracking)")
    ax.plot([], [], "g--", label="side reported and correct, holding course")
    axes_labels(ax, "east m", "north m", grid=False)
    legend_outside(ax, where="below", ncol=1, fontsize=7)
    north_arrow(ax)
    ax.set_title("paper Fig. 9/10: estimate, route side (15 nodes, 8 tiles)")
    fig.tight_layout()
    fig.savefig(out + "/route_fig9.png", dpi=90)


if __name__ == "__main__":
    main()
