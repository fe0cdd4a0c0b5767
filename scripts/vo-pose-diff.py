#!/usr/bin/env python3
"""scripts/vo-pose-diff.py BEFORE AFTER: how far two KITTI-format pose files (3x4 per line, as written by
`qnav vo --kitti K --out F` / `qnav vo --euroc E --out F`) are apart.

Prints the frames, the path length of BEFORE (sum of its frame-to-frame translations), the largest
per-frame distance between the two positions and that distance as % of BEFORE's path (issue 30's rule:
VO poses within 0.1 % of path), and the largest rotation difference in degrees. Exit status 0 always;
the caller reads the figures."""
import math
import sys


def load(path):
    poses = []
    with open(path) as f:
        for line in f:
            v = [float(x) for x in line.split()]
            if len(v) == 12:
                poses.append(v)
    return poses


def main():
    a, b = load(sys.argv[1]), load(sys.argv[2])
    if len(a) != len(b):
        print(f"frames differ: {len(a)} against {len(b)}")
    n = min(len(a), len(b))
    path = 0.0
    for i in range(1, len(a)):
        path += math.dist([a[i][3], a[i][7], a[i][11]], [a[i - 1][3], a[i - 1][7], a[i - 1][11]])
    dmax, rmax = 0.0, 0.0
    for i in range(n):
        dmax = max(dmax, math.dist([a[i][3], a[i][7], a[i][11]], [b[i][3], b[i][7], b[i][11]]))
        ra = [[a[i][4 * r + c] for c in range(3)] for r in range(3)]
        rb = [[b[i][4 * r + c] for c in range(3)] for r in range(3)]
        m = [[sum(ra[k][r] * rb[k][c] for k in range(3)) for c in range(3)] for r in range(3)]  # Ra^T Rb
        s = 0.5 * math.sqrt((m[2][1] - m[1][2]) ** 2 + (m[0][2] - m[2][0]) ** 2 + (m[1][0] - m[0][1]) ** 2)
        rmax = max(rmax, math.degrees(math.asin(min(1.0, s))))  # small angles: the skew part
    pct = 100.0 * dmax / path if path > 0 else float("inf")
    print(f"frames {n} path {path:.6f} m max position difference {dmax:.3e} m = {pct:.2e} % of path, "
          f"max rotation difference {rmax:.5f} deg")


if __name__ == "__main__":
    main()
