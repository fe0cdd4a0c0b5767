#!/usr/bin/env python3
"""Counts the instructions of every pipeline stage on one target and checks them against budgets.

  check-budgets.py --target leon3 --counter toolchain/count-instructions \
      --program build/leon3/test/timing/timing_stages --budgets test/timing/budgets.tsv [--out F.json]

Runs the program (test/timing/timing_stages.cpp) under the qemu-user instruction counter, joins the
program's region table ("stage ID NAME CALLS", "hash NAME HEX") with the counter's per-region counts
("region ID calls C total T min A max B"), subtracts the markers' own cost (the empty region "marker",
its smallest call) and compares each stage's worst call with its budget for the target. Prints one
line per stage; exits 1 when a stage is over budget, has no budget, failed on its input, or the
program or the counter misbehaved (a clear message says which). --out writes the counts as JSON.
"""
import argparse
import json
import os
import subprocess
import sys

QEMU_ARCH = {"aarch64": "aarch64", "armhf": "arm", "leon3": "sparc32plus"}
TARGETS = ("leon3", "aarch64", "armhf")


def read_budgets(path):
    """budgets.tsv: '#' comments; columns stage, leon3, aarch64, armhf (instructions), what."""
    budgets = {}
    with open(path, encoding="utf-8") as f:
        for n, line in enumerate(f, 1):
            line = line.rstrip("\n")
            if not line.strip() or line.lstrip().startswith("#"):
                continue
            cols = line.split("\t")
            if len(cols) != 5:
                raise ValueError(f"{path}:{n}: expected 5 tab-separated columns, got {len(cols)}")
            stage, what = cols[0], cols[4]
            try:
                per = {t: int(c.replace(",", "")) for t, c in zip(TARGETS, cols[1:4])}
            except ValueError as e:
                raise ValueError(f"{path}:{n}: budget is not an integer: {e}") from None
            budgets[stage] = {"what": what, **per}
    return budgets


def count(counter, target, program, args=()):
    """Runs program under the counter; returns {stage: {...}} with per-call counts net of the markers."""
    env = dict(os.environ)
    proc = subprocess.run([counter, QEMU_ARCH[target], program, *args], capture_output=True, text=True, env=env,
                          timeout=1800, check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"{program} exited {proc.returncode} under the counter:\n{proc.stderr.strip()}")
    names, hashes, regions = {}, {}, {}
    errors = 0
    for line in (proc.stdout + "\n" + proc.stderr).splitlines():
        w = line.split()
        if len(w) == 4 and w[0] == "stage":
            names[int(w[1])] = (w[2], int(w[3]))
        elif len(w) == 3 and w[0] == "hash":
            hashes[w[1]] = w[2]
        elif len(w) == 10 and w[0] == "region":
            regions[int(w[1])] = {k: int(v) for k, v in zip(w[2::2], w[3::2])}
        elif len(w) == 2 and w[0] == "region-errors":
            errors = int(w[1])
    if errors:
        raise RuntimeError(f"{errors} unmatched region markers (a begin without an end or the reverse)")
    if not regions:
        raise RuntimeError("the counter reported no regions (is the plugin older than region support?)")
    overhead = regions.get(0, {}).get("min", 0)
    out = {}
    for rid, (name, calls) in sorted(names.items()):
        if rid == 0:
            continue
        r = regions.get(rid)
        if r is None or r["calls"] != calls:
            raise RuntimeError(f"stage {name}: the program ran {calls} calls, the counter saw "
                               f"{r['calls'] if r else 0}")
        out[name] = {"calls": calls, "max": r["max"] - overhead, "min": r["min"] - overhead,
                     "mean": r["total"] // calls - overhead, "hash": hashes.get(name, "")}
    return out, overhead


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--target", required=True, choices=TARGETS)
    ap.add_argument("--counter", required=True)
    ap.add_argument("--program", required=True)
    ap.add_argument("--budgets", required=True)
    ap.add_argument("--out")
    a = ap.parse_args()
    budgets = read_budgets(a.budgets)
    try:
        counts, overhead = count(a.counter, a.target, a.program)
    except (RuntimeError, subprocess.TimeoutExpired) as e:
        print(f"check-budgets: {a.target}: {e}", file=sys.stderr)
        return 1
    bad = []
    print(f"{a.target}: worst call per stage, guest instructions (marker overhead {overhead} subtracted)")
    for stage, c in counts.items():
        b = budgets.get(stage, {}).get(a.target)
        verdict = "no budget" if b is None else ("ok" if c["max"] <= b else "OVER")
        if verdict != "ok":
            bad.append(stage)
        pct = "" if b is None else f"{100.0 * c['max'] / b:5.1f}%"
        print(f"  {stage:14s} {c['max']:>13,d}  budget {b if b is None else format(b, ','):>13s}  {pct}  {verdict}")
    for stage in budgets:
        if stage not in counts:
            print(f"  {stage:14s} has a budget but the program did not run it")
            bad.append(stage)
    if a.out:
        with open(a.out, "w", encoding="utf-8") as f:
            json.dump({"target": a.target, "marker_overhead": overhead, "stages": counts}, f, indent=1)
    if bad:
        print(f"check-budgets: {a.target}: over budget or unchecked: {', '.join(bad)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
