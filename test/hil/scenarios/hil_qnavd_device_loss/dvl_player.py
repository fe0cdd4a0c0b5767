#!/usr/bin/python3
"""The DVL on a pseudo-terminal, as a USB serial adapter the daemon opens by its name (/tmp/dvl0, a
symlink to the pty's slave): plays dvl.txt's sentences at 8 Hz; after UNPLUG_S it closes the master
(the daemon reads EOF / an I/O error, as when the adapter is pulled) and removes the name; after
REPLUG_S it makes a new pty under the same name and goes on; it stops after END_S. Event times
(CLOCK_REALTIME, as candump's) go to events.txt."""
import os
import pty
import sys
import time

UNPLUG_S, REPLUG_S, END_S = float(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3])
LINK = "/tmp/dvl0"
lines = open("dvl.txt").read().splitlines(keepends=True)
groups, cur = [], []
for ln in lines:  # one velocity report with the dead-reckoning lines after it
    if ln.startswith("wrz") and cur:
        groups.append(cur)
        cur = []
    cur.append(ln)
if cur:
    groups.append(cur)


def event(name):
    with open("events.txt", "a") as f:
        f.write(f"{name} {time.time():.6f}\n")


def plug():
    master, slave = pty.openpty()
    name = os.ttyname(slave)
    try:
        os.unlink(LINK)
    except FileNotFoundError:
        pass
    os.symlink(name, LINK)
    return master, slave


t0 = time.time()
master, slave = plug()
event("dvl_plugged")
k = 0
unplugged = replugged = False
while time.time() - t0 < END_S and k < len(groups):
    now = time.time() - t0
    if not unplugged and now >= UNPLUG_S:
        os.unlink(LINK)
        os.close(master)
        os.close(slave)
        event("dvl_unplugged")
        unplugged = True
    if unplugged and not replugged and now >= REPLUG_S:
        master, slave = plug()
        event("dvl_replugged")
        replugged = True
    if not unplugged or replugged:
        try:
            os.write(master, "".join(groups[k]).encode())
        except OSError:
            pass
    k += 1
    time.sleep(0.125)
event("dvl_end")
