#!/usr/bin/python3
"""Plots for docs/vo.md (Debian's python3-matplotlib: run with /usr/bin/python3).

  vo_plot.py eval TRAJ_DIR OUT.png     error vs distance per configuration (from `qnav vo eval --traj-dir`)
  vo_plot.py kitti OURS PEER OUT.png   top view (x, z) of two KITTI pose files
Legends under the axes, never over the data (scripts/qnav_plot.py).
"""
import csv
import glob
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from qnav_plot import axes_labels, legend_outside, plt  # noqa: E402


def plot_eval(traj_dir, out):
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.5))
    for ax, scen, title in ((axes[0], "27m", "%.0f m, attitude drifting (no recalibration)"),
                            (axes[1], "100m", "%.0f m, attitude recalibrated every 2 m")):
        files = sorted(glob.glob(os.path.join(traj_dir, "vo_%s_*.csv" % scen)))
        longest = 0.0
        for f in files:
            name = os.path.basename(f)[len("vo_%s_" % scen):-4]
            path, err = [], []
            with open(f) as fh:
                for row in csv.DictReader(fh):
                    path.append(float(row["path_m"]))
                    err.append(100.0 * float(row["err_m"]) / max(float(row["path_m"]), 1e-9) if float(row["path_m"]) > 1.0 else float("nan"))
            style = "-" if name.startswith("3D") else "--"
            ax.plot(path, err, style, label=name)
            longest = max([longest] + path)
        ax.set_title(title % longest)
        axes_labels(ax, "distance travelled m", "position error / distance %")
        legend_outside(ax, where="below", ncol=3)
    fig.suptitle("Stereo VO on the synthetic Mars yard (paper's noise model, small), qnav vo eval")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def read_poses(p):
    xs, zs = [], []
    with open(p) as fh:
        for line in fh:
            v = [float(x) for x in line.split()]
            if len(v) == 12:
                xs.append(v[3])
                zs.append(v[11])
    return xs, zs


def plot_kitti(ours, peer, out):
    fig, ax = plt.subplots(figsize=(6, 7.6))
    x, z = read_poses(ours)
    px, pz = read_poses(peer)
    n = len(x)
    ax.plot(px[:n], pz[:n], "k--", label="libviso2 (peer, not ground truth)")
    ax.plot(x, z, "r-", label="qnav vo (6D-VME, fc fast)")
    axes_labels(ax, "x m (right of the first camera pose; stretched 4x)", "z m (forward of the first camera pose)")
    ax.set_xlim(-12, 12)
    legend_outside(ax, where="below", ncol=1)
    ax.set_title("KITTI 2011_09_26 city, %d frames" % n)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "eval":
        plot_eval(sys.argv[2], sys.argv[3])
    elif len(sys.argv) == 5 and sys.argv[1] == "kitti":
        plot_kitti(sys.argv[2], sys.argv[3], sys.argv[4])
    else:
        sys.exit(__doc__)
