#!/usr/bin/python3
"""The camera side of hil_qnavd_camera_loss (guest): unplugs and replugs the vivid stereo rig while
qnavd runs in Mode = Vo, watching the live bus (candump of NAV_STATUS, 0x200) for FaultCameraLost
(bit 41: byte 5, bit 1). One process, so the watching costs no fork per sample under emulation.

vivid's two instances run free, each on its own jiffies grid from its STREAMON: their stamps are
k x 4 ms apart, and qnavd pairs within 2 ms, so only k = 0 gives pairs. `in_phase` replugs (unbind +
bind of vivid.0) until FaultCameraLost clears within 2 s of the (re)plug and then stays clear for 4 s
(longer than vo.stale_s); at most 20 times; an out-of-phase open costs about 3 s. It does so before
the unplug under test and after the replug under test. Timeline: in phase (4 s of pairs), unplug,
UNPLUG_S, replug, in phase (4 s of pairs), done (the guest sends SIGTERM). Event times
(CLOCK_REALTIME, as candump's) go to events.txt; exit status 1 when the cameras never
came in phase.
"""
import os
import subprocess
import sys
import threading
import time

UNPLUG_S = float(sys.argv[1]) if len(sys.argv) > 1 else 5.0
TRIES = 20  # 30-45 % of the opens come out in phase: 20 in a row fail about once in 10^3-10^5
DRIVER = "/sys/bus/platform/drivers/vivid"
state = {"lost": None, "clear_run": 0, "clear_total": 0}


def event(name):
    with open("events.txt", "a") as f:
        f.write(f"{name} {time.time():.6f}\n")


def watch():
    p = subprocess.Popen(["candump", "-L", "vcan0,200:7FF"], stdout=subprocess.PIPE, text=True)
    for line in p.stdout:
        data = line.strip().rpartition("#")[2]
        if len(data) >= 12:
            lost = (int(data[10:12], 16) >> 1) & 1
            state["lost"] = lost
            state["clear_run"] = 0 if lost else state["clear_run"] + 1
            state["clear_total"] += 0 if lost else 1


def write(path, text):
    with open(path, "w") as f:
        f.write(text)


def unplug(name):
    event(name)  # before the write: the daemon may see the device fail while unbind is still running
    write(f"{DRIVER}/unbind", "vivid.0")


def plug(name):
    event(name)
    write(f"{DRIVER}/bind", "vivid.0")


def wait_clear(first_s, run_n):
    """True when FaultCameraLost clears within first_s (the cameras reopen within 1 s and pair at once
    when in phase) and then stays clear for run_n NAV_STATUS frames in a row (longer than vo.stale_s:
    pairs keep coming). False at once when no clear frame came in first_s, or when it is set again
    after it cleared (pairs only now and then: the phase is at the tolerance's edge)."""
    t0, seen0 = time.time(), state["clear_total"]
    while True:
        if state["clear_run"] >= run_n:
            return True
        cleared = state["clear_total"] > seen0
        if (not cleared and time.time() - t0 > first_s) or (cleared and state["clear_run"] == 0):
            return False
        time.sleep(0.02)


def in_phase(stage):
    for k in range(TRIES):
        if wait_clear(2.0, 40):
            print(f"camera_player: {stage}: cameras in phase after {k} replugs", flush=True)
            return True
        print(f"camera_player: {stage}: no stereo pairs (cameras out of phase): replug", flush=True)
        unplug("rephase_unplugged")
        time.sleep(0.5)
        plug("rephase_replugged")
    print(f"camera_player: {stage}: the cameras never came in phase in {TRIES} replugs", flush=True)
    return False


# Started before the daemon (python's start-up costs seconds of the one emulated CPU): wait for the
# guest's Vo command.
event("player_started")
while "vo_cmd" not in (open("events.txt").read() if os.path.exists("events.txt") else ""):
    time.sleep(0.05)
threading.Thread(target=watch, daemon=True).start()
if not in_phase("before the unplug"):
    sys.exit(1)
unplug("camera_unplugged")
time.sleep(UNPLUG_S)
plug("camera_replugged")
if not in_phase("after the replug"):
    sys.exit(1)
event("player_done")
