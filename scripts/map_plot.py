#!/usr/bin/python3
"""Plot of `qnav map --out DIR` (Debian's python3-matplotlib: run with /usr/bin/python3).

  map_plot.py DIR/map_trajectory.csv OUT.png

Left: the chained trajectory (aligned to the navigation frame by the fit `qnav map` prints) and the
navigation positions, metres, equal axes, keyframes marked. Right: the image rotation of the chain and
the navigation's yaw change since frame 0, per frame.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def fnum(s):
    try:
        return float(s)
    except ValueError:
        return None


def main(path, out):
    rows = list(csv.DictReader(open(path)))
    fig, (ax, ay) = plt.subplots(1, 2, figsize=(12, 5.2))
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
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("trajectory (chain scaled and rotated onto the navigation)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="best", framealpha=0.8)

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
    ay.set_xlabel("frame")
    ay.set_ylabel("rotation since frame 0 [deg]")
    ay.set_title("chained rotation vs navigation yaw")
    ay.grid(True, alpha=0.3)
    ay.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(out, dpi=100)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
