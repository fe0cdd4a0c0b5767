#!/bin/bash
# The systemd unit passes `systemd-analyze verify` (with ExecStart pointed at the built binary).
# Exit 77 (skipped) when the machine has no systemd-analyze. Usage: $0 QNAVD UNIT WORKDIR
set -u
D=$1
U=$2
W=$3
command -v systemd-analyze >/dev/null || { echo "SKIP: no systemd-analyze on this machine"; exit 77; }
rm -rf "$W" && mkdir -p "$W" || exit 1
sed "s|/usr/bin/qnavd|$D|g" "$U" > "$W/qnavd.service"
out=$(systemd-analyze verify "$W/qnavd.service" 2>&1); rc=$?
echo "$out"
[ $rc -eq 0 ] || { echo "FAIL: systemd-analyze verify exit $rc"; exit 1; }
[ -z "$out" ] || { echo "FAIL: systemd-analyze verify printed warnings"; exit 1; }
for key in Type=notify WatchdogSec= User=qnav NoNewPrivileges=yes ProtectSystem=strict ReadWritePaths= RestrictAddressFamilies= \
           "AmbientCapabilities=CAP_SYS_NICE CAP_IPC_LOCK"; do
  grep -q "^$key" "$U" || { echo "FAIL: unit lacks $key"; exit 1; }
done
echo "systemd unit: verified"
