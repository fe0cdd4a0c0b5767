#!/usr/bin/python3
"""Ratios qnav / OpenCV from bench_vision's JSON output (CPU time, median of repetitions).

    build/<dir>/test/bench/vision/bench_vision --benchmark_repetitions=5 \
        --benchmark_report_aggregates_only=true --benchmark_out=bench_vision.json --benchmark_out_format=json
    /usr/bin/python3 scripts/vision-bench-ratios.py bench_vision.json
"""
import json
import sys

PAIRS = [  # (stage, qnav benchmark, OpenCV benchmark)
    ("Harris + NMS + top 500", "BM_Harris_qnav", "BM_Harris_opencv"),
    ("remap (undistort LUT)", "BM_Remap_qnav", "BM_Remap_opencv"),
    ("stereo at 500 corners", "BM_StereoAtCorners_qnav", "BM_StereoAtCorners_opencv"),
    ("downsample", "BM_Downsample_qnav", "BM_Downsample_opencv"),
    ("oriented descriptor x500 vs SIFT compute", "BM_OrientedDescriptor_qnav", "BM_SiftDescriptor_opencv"),
]


def main(path):
    with open(path) as f:
        data = json.load(f)
    med = {}
    labels = {}
    for b in data["benchmarks"]:
        if b.get("aggregate_name", "median") != "median":
            continue
        name = b["run_name"] if "run_name" in b else b["name"]
        unit = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}[b.get("time_unit", "ns")]
        med[name] = b["cpu_time"] * unit
        labels[name] = b.get("label", "")
    print("| stage | size | qnav ms | OpenCV ms | qnav / OpenCV |")
    print("|---|---|---|---|---|")
    for stage, q, o in PAIRS:
        for arg in ("0", "1"):
            qn, on = q + "/" + arg, o + "/" + arg
            if qn in med and on in med:
                print("| %s | %s | %.3f | %.3f | %.2f |" % (stage, labels[qn], med[qn], med[on], med[qn] / med[on]))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "bench_vision.json")
