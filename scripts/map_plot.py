#!/usr/bin/python3
"""Plot of `qnav map --out DIR` (Debian's python3-matplotlib: run with /usr/bin/python3).

  map_plot.py DIR/map_trajectory.csv OUT.png

Left: the chained trajectory (aligned to the navigation frame by the fit `qnav map` prints) and the
navigation positions, metres, equal axes, keyframes marked. Legends under the panels, never over the
data (scripts/qnav_plot.py). Middle: the image rotation of the chain and
the navigation's yaw change since frame 0, per frame. Right (when `qnav map --map-out` wrote
map_nodes.csv / map_edges.csv beside the trajectory): the topological map in the chain's frame (metres
with an altitude, else mosaic pixels): nodes (revisited ones red) with their ids, edges, the chain.
"""
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from qnav_plot import axes_labels, legend_outside, plt  # noqa: E402


def fnum(s):
    try:
        return float(s)
    except ValueError:
        return None


def main(path, out):
    rows = list(csv.DictReader(open(path)))
    nodes_path = os.path.join(os.path.dirname(path), "map_nodes.csv")
    edges_path = os.path.join(os.path.dirname(path), "map_edges.csv")
    have_map = os.path.isfile(nodes_path) and os.path.isfile(edges_path)
    if have_map:
        fig, (ax, ay, am) = plt.subplots(1, 3, figsize=(18, 6.2))
        plot_map(am, rows, list(csv.DictReader(open(nodes_path))), list(csv.DictReader(open(edges_path))))
    else:
        fig, (ax, ay) = plt.subplots(1, 2, figsize=(12, 6.2))
    cx = [fnum(r["aligned_x_m"]) for r in rows if r["status"] == "ok" and fnum(r["aligned_x_m"]) is not None]
    cy = [fnum(r["aligned_y_m"]) for r in rows if r["status"] == "ok" and fnum(r["aligned_y_m"]) is not None]
    nx = [fnum(r["nav_x_m"]) for r in rows if fnum(r["nav_x_m"]) is not None]
    ny = [fnum(r["nav_y_m"]) for r in rows if fnum(r["nav_y_m"]) is not None]
    if nx:
        ax.plot(nx, ny, "k.--", lw=1, ms=5, label="navigation (frames.csv)")
        ax.plot(nx[:1], ny[:1], "ks", ms=7, label="start")
    if cx:
        ax.plot(cx, cy, "-", color="tab:blue", lw=2, label="homography chain (aligned)")
        kx = [fnum(r["aligned_x_m"]) for r in rows if r["status"] == "ok" and r["new_keyframe"] == "1" and fnum(r["aligned_x_m"]) is not None]
        ky = [fnum(r["aligned_y_m"]) for r in rows if r["status"] == "ok" and r["new_keyframe"] == "1" and fnum(r["aligned_y_m"]) is not None]
        ax.plot(kx, ky, "o", color="tab:orange", ms=6, label="keyframes")
    ax.set_aspect("equal", adjustable="datalim")
    axes_labels(ax, "x m (navigation frame)", "y m (navigation frame)")
    ax.set_title("trajectory (chain scaled and rotated onto the navigation)")
    legend_outside(ax, where="below", ncol=2)

    fr = [int(r["frame"]) for r in rows if r["status"] == "ok"]
    rot = [fnum(r["image_rot_deg"]) for r in rows if r["status"] == "ok"]
    ay.plot(fr, [v - rot[0] for v in rot] if rot else [], "-o", color="tab:blue", ms=3, label="chain: image rotation")
    nav = [(int(r["frame"]), fnum(r["nav_yaw_deg"]), r["nav_interpolated"]) for r in rows if fnum(r["nav_yaw_deg"]) is not None]
    if nav:
        y0 = nav[0][1]
        ay.plot([f for f, _, _ in nav], [y - y0 for _, y, _ in nav], "k.--", label="navigation yaw change")
        held = [(f, y - y0) for f, y, i in nav if i != "1"]
        if held:
            ay.plot([f for f, _ in held], [y for _, y in held], "rx", ms=8, label="navigation held (outside its span)")
    axes_labels(ay, "frame", "rotation since frame 0 deg", integer_x=True)
    ay.set_title("chained rotation vs navigation yaw")
    legend_outside(ay, where="below", ncol=2)
    fig.tight_layout()
    fig.savefig(out, dpi=100)


def plot_map(am, rows, nodes, edges):
    metric = bool(nodes) and nodes[0]["units"] == "m"
    kx, ky = ("x_m", "y_m") if metric else ("x_px", "y_px")
    tx = [fnum(r[kx]) for r in rows if r["status"] == "ok" and fnum(r[kx]) is not None]
    ty = [fnum(r[ky]) for r in rows if r["status"] == "ok" and fnum(r[ky]) is not None]
    am.plot(tx, ty, "-", color="tab:blue", lw=1, alpha=0.6, label="homography chain")
    pos = {n["id"]: (fnum(n["x"]), fnum(n["y"])) for n in nodes}
    for e in edges:
        if e["a"] in pos and e["b"] in pos:
            (x0, y0), (x1, y1) = pos[e["a"]], pos[e["b"]]
            am.plot([x0, x1], [y0, y1], "-", color="k", lw=1.5)
    rev = [n for n in nodes if int(n["revisits"]) > 0]
    once = [n for n in nodes if int(n["revisits"]) == 0]
    am.plot([fnum(n["x"]) for n in once], [fnum(n["y"]) for n in once], "o", color="tab:green", ms=7, label="node")
    if rev:
        am.plot([fnum(n["x"]) for n in rev], [fnum(n["y"]) for n in rev], "o", color="tab:red", ms=8, label="node revisited")
    for n in nodes:
        am.annotate(n["id"], (fnum(n["x"]), fnum(n["y"])), fontsize=7, xytext=(3, 3), textcoords="offset points")
    am.set_aspect("equal", adjustable="datalim")
    if not metric:
        am.invert_yaxis()
    unit = "m" if metric else "mosaic px"
    axes_labels(am, "x %s" % unit, "y %s" % unit)
    am.set_title("topological map: %d nodes, %d edges" % (len(nodes), len(edges)))
    legend_outside(am, where="below", ncol=3)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
