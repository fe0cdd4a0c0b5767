#!/usr/bin/python3
"""hil_qnavd_mavlink (guest): the autopilot's serial line. Makes a pseudo-terminal (raw), puts its
slave behind the symlink LINK (qnavd's mavlink.serial_device) and runs COMMAND with the master's
and the slave's descriptors appended as its last two arguments; the slave stays open in COMMAND too,
so the line stays up while qnavd reopens it (COMMAND closes it at its end: a read blocked on the
master then returns). No relay: the autopilot reads and writes the master itself.
  pty_exec.py LINK COMMAND [ARGS...]"""
import os
import sys
import tty

link, cmd = sys.argv[1], sys.argv[2:]
master, slave = os.openpty()
tty.setraw(slave)
try:
    os.unlink(link)
except FileNotFoundError:
    pass
os.symlink(os.ttyname(slave), link)
os.set_inheritable(master, True)
os.set_inheritable(slave, True)
print(f"pty_exec: {link} -> {os.ttyname(slave)}, master fd {master}", flush=True)
os.execvp(cmd[0], cmd + [str(master), str(slave)])
