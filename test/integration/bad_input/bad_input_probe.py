#!/usr/bin/env python3
"""The qnav tool against damaged input, as a vehicle engineer meets it (issue #19's probe, kept).

Every file the tool reads is damaged in the ways a recording or a link damages it (bit flips,
truncation at any point, a field set to an absurd value, garbage, a device that never ends, a
directory, nothing at all) and fed to the commands that read it. Every run must:
  - end by itself (no hang: each run has a time limit),
  - end with an exit status, never a signal (no crash, no abort),
  - print no sanitizer report (ASan/UBSan builds: a report is a failure even when the run goes on),
  - when the input is refused (status != 0), say why on stderr.
Input that cannot be valid (the "must fail" cases) must be refused.

  bad_input_probe.py QNAV SHARED_DIR WORK_DIR [--runs N] [--seed S]
Prints one line per failure and a summary: runs, refused, accepted, failures.
"""
import argparse
import os
import random
import shutil
import struct
import subprocess
import sys

SANITIZER_MARKS = ("ERROR: AddressSanitizer", "ERROR: LeakSanitizer", "runtime error:", "UndefinedBehaviorSanitizer")


class Probe:
    def __init__(self, qnav, work, timeout):
        self.qnav, self.work, self.timeout = qnav, work, timeout
        self.runs = self.refused = self.accepted = 0
        self.failures = []

    def run(self, args, what, must_fail=False):
        self.runs += 1
        try:
            p = subprocess.run([self.qnav] + args, cwd=self.work, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               timeout=self.timeout, env=dict(os.environ, ASAN_OPTIONS="detect_leaks=1:abort_on_error=0"))
        except subprocess.TimeoutExpired:
            self.failures.append(f"HANG ({self.timeout} s): qnav {' '.join(args)}  [{what}]")
            return
        err = p.stderr.decode(errors="replace")
        if p.returncode < 0:
            self.failures.append(f"SIGNAL {-p.returncode}: qnav {' '.join(args)}  [{what}]\n{err[-2000:]}")
            return
        for mark in SANITIZER_MARKS:
            if mark in err:
                self.failures.append(f"SANITIZER: qnav {' '.join(args)}  [{what}]\n{err[-3000:]}")
                return
        if p.returncode != 0:
            self.refused += 1
            if not err.strip():
                self.failures.append(f"SILENT REFUSAL (status {p.returncode}, nothing on stderr): qnav {' '.join(args)}  [{what}]")
        else:
            self.accepted += 1
            if must_fail:
                self.failures.append(f"ACCEPTED invalid input: qnav {' '.join(args)}  [{what}]")


def mutate(data, rng):
    """One damaged copy: bit flips, a truncation, a zeroed or 0xFF run, or a duplicated block."""
    b = bytearray(data)
    kind = rng.randrange(5)
    if kind == 0:
        for _ in range(rng.randint(1, 8)):
            i = rng.randrange(len(b))
            b[i] ^= 1 << rng.randrange(8)
        return bytes(b), "bit flips"
    if kind == 1:
        return bytes(b[: rng.randrange(len(b))]), "truncated"
    if kind == 2:
        i = rng.randrange(len(b))
        n = rng.randint(1, 64)
        b[i:i + n] = bytes([rng.choice((0x00, 0xFF))]) * len(b[i:i + n])
        return bytes(b), "run of 00/FF"
    if kind == 3:
        i = rng.randrange(len(b))
        n = rng.randint(1, 4096)
        return bytes(b[:i] + b[i:i + n] + b[i:]), "duplicated block"
    i = rng.randrange(len(b))
    return bytes(b[:i] + bytes(rng.randrange(256) for _ in range(rng.randint(1, 200))) + b[i:]), "garbage inserted"


def write(path, data):
    with open(path, "wb") as f:
        f.write(data)
    return path


def xtf_ping_offsets(data):
    """Offsets of the sonar packets (type 0) of an XTF file (magic 0xFACE, length at +10)."""
    hdr_channels = data[166] | data[167] << 8
    extra = max(0, (hdr_channels - 6 + 7) // 8) if hdr_channels > 6 else 0
    at, out = 1024 * (1 + extra), []
    while at + 14 <= len(data):
        magic, = struct.unpack_from("<H", data, at)
        if magic != 0xFACE:
            break
        n, = struct.unpack_from("<I", data, at + 10)
        if data[at + 2] == 0:
            out.append(at)
        at += n
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("qnav")
    ap.add_argument("shared")
    ap.add_argument("work")
    ap.add_argument("--runs", type=int, default=12, help="damaged copies per file and command")
    ap.add_argument("--seed", type=int, default=19)
    ap.add_argument("--timeout", type=float, default=60.0)
    a = ap.parse_args()
    rng = random.Random(a.seed)
    shutil.rmtree(a.work, ignore_errors=True)
    os.makedirs(a.work)
    pr = Probe(os.path.abspath(a.qnav), a.work, a.timeout)
    w = lambda name: os.path.join(a.work, name)

    # ---- Good inputs made by the tool itself, and the real side-scan file ----
    subprocess.run([pr.qnav, "sonar", "simulate", "--out", w("good.jsf"), "--length-m", "60", "--samples", "512"], check=True,
                   stdout=subprocess.DEVNULL)
    subprocess.run([pr.qnav, "sonar", "simulate", "--out", w("good.xtf"), "--length-m", "60", "--samples", "512"], check=True,
                   stdout=subprocess.DEVNULL)
    subprocess.run([pr.qnav, "route", "train", "--sonar", w("good.jsf"), "--out", w("good.qroute"), "--force"], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    subprocess.run([pr.qnav, "can", "simulate", w("good.candump"), "--seconds", "2", "--faults"], check=True, stdout=subprocess.DEVNULL)
    subprocess.run([pr.qnav, "dvl", "simulate", w("good.dvl"), "--seconds", "3"], check=True, stdout=subprocess.DEVNULL)
    real_xtf = os.path.join(a.shared, "data", "sidescan", "cidco-scotsman-iver2", "scotsman-iver2.xtf")
    dbc = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "docs", "qnav.dbc")
    jpeg = os.path.join(a.shared, "data", "stereo", "middlebury_aloe_opencv", "aloeL.jpg")

    sonar_files = [w("good.jsf"), w("good.xtf")] + ([real_xtf] if os.path.exists(real_xtf) else [])
    for src in sonar_files:
        data = open(src, "rb").read()
        ext = os.path.splitext(src)[1]
        for k in range(a.runs):
            bad, what = mutate(data, rng)
            f = write(w(f"bad{k}{ext}"), bad)
            what = f"{os.path.basename(src)}: {what}"
            if ext == ".xtf":
                pr.run(["xtf", "info", f], what)
            pr.run(["sonar", "tiles", f, "--out", w("tiles")], what)
            pr.run(["route", "train", "--sonar", f, "--out", w("t.qroute"), "--force"], what)
            pr.run(["route", "repeat", "--route", w("good.qroute"), "--sonar", f], what)

    # The regressions of issue #19, exactly: a slant range of 8.8e-38 m in the real file's pings.
    if os.path.exists(real_xtf):
        data = bytearray(open(real_xtf, "rb").read())
        for at in xtf_ping_offsets(bytes(data))[10:400:7]:
            struct.pack_into("<f", data, at + 256 + 4, 8.8e-38)  # first channel header: SlantRange
        f = write(w("tiny_range.xtf"), bytes(data))
        pr.run(["sonar", "tiles", f, "--out", w("tiles")], "slant range 8.8e-38 m")
        pr.run(["route", "train", "--sonar", f, "--out", w("t.qroute"), "--force"], "slant range 8.8e-38 m")
        pr.run(["route", "xtf", "--xtf", f], "slant range 8.8e-38 m")

    # Route files: damaged copies of a good route.
    data = open(w("good.qroute"), "rb").read()
    for k in range(a.runs * 2):
        bad, what = mutate(data, rng)
        f = write(w(f"bad{k}.qroute"), bad)
        pr.run(["route", "info", f], "route file: " + what)
        pr.run(["route", "repeat", "--route", f, "--sonar", w("good.jsf")], "route file: " + what)

    # CAN logs, the DBC, DVL captures.
    for src, cmd in ((w("good.candump"), ["can", "decode"]), (dbc, ["can", "dbc"]), (w("good.dvl"), ["dvl", "parse"])):
        data = open(src, "rb").read()
        for k in range(a.runs):
            bad, what = mutate(data, rng)
            f = write(w(f"bad{k}_{cmd[0]}_{cmd[1]}.txt"), bad)
            pr.run(cmd + [f], f"{os.path.basename(src)}: {what}")

    # Images (the stereo tools' reader): damaged copies of the real JPEG.
    if os.path.exists(jpeg):
        data = open(jpeg, "rb").read()
        for k in range(max(2, a.runs // 3)):
            f = write(w(f"bad{k}.jpg"), data[: rng.randrange(len(data))])
            pr.run(["stereo", "disparity", "--left", f, "--right", jpeg, "--out", w("d.png")], "JPEG cut short", must_fail=True)

    # The downward-camera mapping (qnav map): the real sparus frames with some of them damaged (cut
    # short, garbage, empty), a damaged navigation CSV and camera calibration.
    sparus = os.path.join(a.shared, "data", "downward", "sparus_snippet")
    if os.path.isdir(os.path.join(sparus, "frames")):
        frames = sorted(f for f in os.listdir(os.path.join(sparus, "frames")) if f.endswith(".png"))[:8]
        for k in range(max(2, a.runs // 3)):
            d = w(f"frames{k}")
            os.makedirs(d, exist_ok=True)
            for i, name in enumerate(frames):
                data = open(os.path.join(sparus, "frames", name), "rb").read()
                if i == 1 + k % 5:
                    data = data[: rng.randrange(len(data))]
                elif i == 2 + k % 5:
                    data = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 4096)))
                elif i == 6:
                    data = b""
                write(os.path.join(d, name), data)
            pr.run(["map", "--images", d, "--out", w("map"), "--no-plot"], "frames cut short / garbage / empty")
            for src, opt in ((os.path.join(sparus, "frames.csv"), "--poses"), (os.path.join(sparus, "camera.yaml"), "--camera")):
                bad, what = mutate(open(src, "rb").read(), rng)
                f = write(w(f"bad{k}_{os.path.basename(src)}"), bad)
                pr.run(["map", "--images", os.path.join(sparus, "frames"), opt, f, "--out", w("map"), "--no-plot", "--frames", "6"],
                       f"{os.path.basename(src)}: {what}")

    # Input that cannot be valid: must be refused, with a reason.
    os.makedirs(w("adir"), exist_ok=True)
    write(w("empty"), b"")
    for path, what in (("/dev/zero", "a device that never ends"), (w("adir"), "a directory"), (w("empty"), "an empty file"),
                       (w("missing"), "no such file")):
        for cmd in (["xtf", "info", path], ["sonar", "tiles", path, "--out", w("tiles")], ["route", "info", path],
                    ["route", "train", "--sonar", path, "--out", w("t.qroute"), "--force"], ["can", "decode", path],
                    ["can", "dbc", path], ["dvl", "parse", path], ["map", "--images", path, "--out", w("map"), "--no-plot"]):
            pr.run(cmd, what, must_fail=True)
    for value in ("nan", "inf", "-inf", "1e400", "-1", "0", "abc", ""):
        pr.run(["dvl", "simulate", w("x.dvl"), "--seconds", value], f"--seconds {value!r}", must_fail=True)
        pr.run(["can", "simulate", w("x.candump"), "--seconds", value], f"--seconds {value!r}", must_fail=True)
        pr.run(["sonar", "simulate", "--out", w("x.jsf"), "--length-m", value], f"--length-m {value!r}", must_fail=True)

    for f in pr.failures:
        print(f)
    print(f"bad_input_probe: {pr.runs} runs, {pr.refused} refused with a reason, {pr.accepted} accepted, {len(pr.failures)} failures")
    return 1 if pr.failures else 0


if __name__ == "__main__":
    sys.exit(main())
