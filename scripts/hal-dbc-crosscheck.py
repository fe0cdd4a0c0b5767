#!/usr/bin/python3
"""Cross-checks qnav's CAN codec against an independent DBC implementation (Debian's python3-canmatrix).

For every message of docs/qnav.dbc, random raw signal values are packed into frames by canmatrix and
written as a candump log; `qnav can decode --all` decodes the log with qnav's codec, and every
physical value it prints is compared with canmatrix's own decoding of the same frame. Messages come
from the DBC itself (none are listed here). Also checked: canmatrix reads a value table (VAL_) for every
1-bit signal and every enumeration (Mode, State, GuidanceStatus, Side) naming each raw value in the
signal's range, so CAN tools (cantools, SavvyCAN) show names, not integers.

usage: /usr/bin/python3 scripts/hal-dbc-crosscheck.py QNAV [FRAMES_PER_MESSAGE]
"""
import random
import re
import subprocess
import sys
import tempfile
import os
import logging

logging.disable(logging.CRITICAL)  # canmatrix warns about optional formats it cannot load
import canmatrix  # noqa: E402
import canmatrix.formats  # noqa: E402


ENUMERATIONS = ("Mode", "State", "GuidanceStatus", "Side")


def value_table_problems(db):
    """Signals that CAN tools would show as bare integers: a flag or enumeration without a full VAL_ table."""
    problems = []
    for frame in db.frames:
        for s in frame.signals:
            if s.size != 1 and s.name not in ENUMERATIONS:
                continue
            lo, hi = int(s.phys2raw(s.min)), int(s.phys2raw(s.max))
            missing = [v for v in range(lo, hi + 1) if not s.values.get(v)]
            if missing:
                problems.append("%s.%s: no value name for %s" % (frame.name, s.name, missing))
    return problems


def main():
    qnav = sys.argv[1]
    per_message = int(sys.argv[2]) if len(sys.argv) > 2 else 50
    here = os.path.dirname(os.path.abspath(__file__))
    dbs = canmatrix.formats.loadp(os.path.join(here, "..", "docs", "qnav.dbc"))
    db = list(dbs.values())[0]
    problems = value_table_problems(db)
    for p in problems:
        print("value table: " + p)
    rng = random.Random(7)
    lines, expected = [], []
    t = 1700000000.0
    for frame in db.frames:
        for _ in range(per_message):
            raw = {}
            for s in frame.signals:
                lo = -(1 << (s.size - 1)) if s.is_signed else 0
                hi = (1 << (s.size - 1)) - 1 if s.is_signed else (1 << s.size) - 1
                raw[s.name] = rng.randint(lo, hi)
            data = frame.encode(raw)
            decoded = frame.decode(data)
            t += 0.001
            lines.append("(%.6f) can0 %03X#%s" % (t, frame.arbitration_id.id, bytes(data).hex().upper()))
            expected.append((frame.name, {k: float(v.phys_value) for k, v in decoded.items()}))
    with tempfile.NamedTemporaryFile("w", suffix=".log", delete=False) as f:
        f.write("\n".join(lines) + "\n")
        path = f.name
    out = subprocess.run([qnav, "can", "decode", path, "--all"], capture_output=True, text=True, check=True).stdout
    os.unlink(path)
    got = [l for l in out.splitlines() if re.match(r"^\s*[0-9.]+ QNAV_", l)]
    if len(got) != len(expected):
        print("decoded %d frames, expected %d" % (len(got), len(expected)))
        for frame in db.frames:
            n = sum(1 for l in got if re.match(r"^\s*[0-9.]+ %s " % frame.name, l))
            if n != per_message:
                print("  %s (%d signals): qnav printed %d of %d frames" % (frame.name, len(frame.signals), n, per_message))
        return 1
    compared = mismatches = 0
    for line, (name, values) in zip(got, expected):
        fields = dict(re.findall(r" (\w+)=(-?[0-9.e+-]+)", line.split("[rejected")[0]))
        if name not in line:
            mismatches += 1
            continue
        for sig, want in values.items():
            compared += 1
            have = float(fields.get(sig, "nan"))
            if not abs(have - want) <= 1e-9 * max(1.0, abs(want)):  # qnav prints 10 significant digits
                mismatches += 1
                if mismatches < 10:
                    print("mismatch %s.%s: qnav %r canmatrix %r" % (name, sig, have, want))
    print("%d frames, %d signal values compared with canmatrix, %d mismatches; %d value-table problems"
          % (len(got), compared, mismatches, len(problems)))
    return 0 if mismatches == 0 and not problems else 1


if __name__ == "__main__":
    sys.exit(main())
