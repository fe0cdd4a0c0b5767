#!/usr/bin/python3
"""The vehicle around qnavd while it teaches (hil_qnavd_kill, guest), on one timeline at the dive's
own ping rate: for each ping of dive.jsf, its JSF messages to the daemon's sonar TCP connection (the
topside's data port, 127.0.0.1:1709), the DVL sentence of the same time (dvl.txt, Water Linked) to a
pseudo-terminal named /tmp/dvl0, and the AHRS frame of the same time (ahrs.log, QNAV_ATTITUDE_IN) on
vcan0. The daemon is stopped and restarted while this plays: a closed connection is dropped and the
next one accepted, and the pseudo-terminal stays (an adapter that is not pulled). At the end of the
dive it starts again from the first ping. Runs until killed; prints `ready` once the names exist.
The DVL's name is $QNAV_HIL_DVL_LINK when set (hil_qnavd_unprivileged: /dev/ttyUSB0, since the
daemon's private /tmp hides /tmp/dvl0).
"""
import os
import pty
import select
import socket
import struct
import sys
import time
import tty

RATE_HZ = 10.0
data = open("dive.jsf", "rb").read()
pings, cur, off = [], b"", 0
while off + 16 <= len(data):
    (size,) = struct.unpack_from("<I", data, off + 12)
    (mtype,) = struct.unpack_from("<H", data, off + 4)
    cur += data[off:off + 16 + size]
    off += 16 + size
    if mtype == 80 and data[off - 16 - size + 8] == 1:  # the starboard channel closes a ping
        pings.append(cur)
        cur = b""
dvl = open("dvl.txt").read().splitlines(keepends=True)
ahrs = []
for line in open("ahrs.log"):
    cid, payload = line.split()[2].split("#")
    ahrs.append((int(cid, 16), bytes.fromhex(payload)))
n = min(len(pings), len(dvl), len(ahrs))

DVL_LINK = os.environ.get("QNAV_HIL_DVL_LINK", "/tmp/dvl0")
master, slave = pty.openpty()
tty.setraw(slave)
try:
    os.unlink(DVL_LINK)
except FileNotFoundError:
    pass
os.symlink(os.ttyname(slave), DVL_LINK)
can = socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
can.bind(("vcan0",))
srv = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
srv.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
srv.bind(("127.0.0.1", 1709))
srv.listen(1)
srv.setblocking(False)
client = None
print(f"ready: {n} pings, {len(data)} bytes of JSF", flush=True)
sent = dropped = connections = 0
t0 = time.monotonic()
k = 0
while True:
    due = t0 + k / RATE_HZ
    now = time.monotonic()
    if due > now:
        time.sleep(due - now)
    i = k % n
    if client is None:
        try:
            client, _ = srv.accept()
            client.setblocking(True)
            connections += 1
            print(f"sonar: connection {connections} at ping {k}", flush=True)
        except BlockingIOError:
            pass
    if client is not None:
        try:
            client.sendall(pings[i])
            sent += 1
        except OSError:
            client.close()
            client = None
            dropped += 1
    else:
        dropped += 1
    os.write(master, dvl[i].encode())
    # drain what the daemon may write to the DVL (nothing is expected)
    while select.select([master], [], [], 0)[0]:
        os.read(master, 4096)
    cid, payload = ahrs[i]
    payload = payload[:6] + bytes([k & 0xFF]) + payload[7:]  # a rolling counter across restarts
    can.send(struct.pack("=IB3x8s", cid, len(payload), payload.ljust(8, b"\0")))
    k += 1
    if k % 100 == 0:
        print(f"vehicle: {k} pings, {sent} sent, {dropped} with no daemon connected", flush=True)
