#!/usr/bin/python3
"""hil_qnavd_mavlink (guest): sends flood.bin's datagrams (flood_gen.cjs) to qnavd's UDP server port
at RATE datagrams per second, from its own socket (another machine on the vehicle's network), and
writes flood.done: the wall-clock start and end (s) and the datagrams sent.
  flood.py FLOOD.bin PORT RATE"""
import socket
import struct
import sys
import time

path, port, rate = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
data = open(path, "rb").read()
grams = []
off = 0
while off < len(data):
    (n,) = struct.unpack_from(">H", data, off)
    grams.append(data[off + 2:off + 2 + n])
    off += 2 + n
sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
t0 = time.time()
m0 = time.monotonic()
sent = 0
for i, g in enumerate(grams):
    due = m0 + i / rate
    d = due - time.monotonic()
    if d > 0:
        time.sleep(d)
    sock.sendto(g, ("127.0.0.1", port))
    sent += 1
t1 = time.time()
open("flood.done", "w").write(f"{t0:.6f} {t1:.6f} {sent}\n")
print(f"flood: {sent} datagrams in {t1 - t0:.2f} s to 127.0.0.1:{port}")
