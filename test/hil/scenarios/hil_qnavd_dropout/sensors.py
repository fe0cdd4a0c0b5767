#!/usr/bin/python3
"""The vehicle's sensors for hil_qnavd_dropout (guest), on one timeline from the player's start: the
AHRS (attitude.log's QNAV_ATTITUDE_IN frames, 20 Hz, their own spacing) on vcan0 and the DVL
(dvl.txt, one velocity report with its dead-reckoning lines every 0.125 s) on a pseudo-terminal
named /tmp/dvl0 (as a USB serial adapter). Both devices stay present throughout:
  DVL_OFF_S .. DVL_ON_S   the DVL sends nothing (its pseudo-terminal stays open: silence, not an unplug);
  ATT_OFF_S .. ATT_ON_S   no AHRS frame (vcan0 stays up: the attitude goes stale);
it stops at END_S. The time of the last sentence / frame before each silence and of the first after
it (CLOCK_REALTIME, as candump's) go to events.txt: dvl_last, dvl_resumed, att_last, att_resumed."""
import os
import pty
import socket
import struct
import sys
import time
import tty

DVL_OFF_S, DVL_ON_S, ATT_OFF_S, ATT_ON_S, END_S = (float(a) for a in sys.argv[1:6])
LINK = "/tmp/dvl0"
DVL_PERIOD_S = 0.125

groups, cur = [], []
for ln in open("dvl.txt").read().splitlines(keepends=True):  # a velocity report and the lines after it
    if ln.startswith("wrz") and cur:
        groups.append("".join(cur).encode())
        cur = []
    cur.append(ln)
if cur:
    groups.append("".join(cur).encode())
ahrs, t_first = [], None
for line in open("attitude.log"):  # (1700000000.000000) can0 100#...
    t = float(line[1:line.index(")")])
    t_first = t if t_first is None else t_first
    cid, payload = line.split()[2].split("#")
    ahrs.append((t - t_first, struct.pack("=IB3x8s", int(cid, 16), len(payload) // 2, bytes.fromhex(payload).ljust(8, b"\0"))))

plan = [(k * DVL_PERIOD_S, "dvl", g) for k, g in enumerate(groups)] + [(t, "att", f) for t, f in ahrs]
plan = sorted((p for p in plan if p[0] < END_S), key=lambda p: p[0])

master, slave = pty.openpty()
tty.setraw(slave)
try:
    os.unlink(LINK)
except FileNotFoundError:
    pass
os.symlink(os.ttyname(slave), LINK)
can = socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
can.bind(("vcan0",))

events = {}


def event(name, t):
    if name not in events:
        events[name] = t
        with open("events.txt", "a") as f:
            f.write(f"{name} {t:.6f}\n")


print(f"ready: {len(plan)} writes", flush=True)
t0 = time.monotonic()
last = {"dvl": None, "att": None}
sent = {"dvl": 0, "att": 0}
for t, kind, data in plan:
    off, on = (DVL_OFF_S, DVL_ON_S) if kind == "dvl" else (ATT_OFF_S, ATT_ON_S)
    if off <= t < on:
        if last[kind] is not None:
            event(f"{kind}_last", last[kind])
        continue
    due = t0 + t
    now = time.monotonic()
    if due > now:
        time.sleep(due - now)
    if kind == "dvl":
        os.write(master, data)
    else:
        can.send(data)
    stamp = time.time()
    sent[kind] += 1
    last[kind] = stamp
    if t >= on:
        event(f"{kind}_resumed", stamp)
event("player_end", time.time())
print(f"done: {sent['dvl']} DVL reports, {sent['att']} AHRS frames sent", flush=True)
# The pseudo-terminal stays open until the daemon has stopped (the guest kills this process then).
while True:
    time.sleep(1.0)
