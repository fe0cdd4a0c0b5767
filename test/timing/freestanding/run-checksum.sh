#!/bin/sh
# Boots the freestanding LEON3 image in qemu-system-sparc (leon3_generic, UART on stdio), runs the
# host reference, and passes only when both print status ok and identical checksum lines.
# usage: run-checksum.sh QEMU ELF RAM_MIB HOST_REFERENCE [TIMEOUT_S]
set -u
qemu=$1 elf=$2 ram=$3 host=$4 limit=${5:-280}
out=$(mktemp) ref=$(mktemp)
trap 'rm -f "$out" "$ref"' EXIT
start=$(date +%s)
timeout "$limit" "$qemu" -M leon3_generic -m "${ram}M" -nographic -no-reboot -monitor none -serial stdio \
  -kernel "$elf" </dev/null >"$out" 2>&1
rc=$?
end=$(date +%s)
tr -d '\r' <"$out" >"$out.clean" && mv "$out.clean" "$out"
echo "--- leon3 (qemu-system-sparc, $((end - start)) s, qemu exit $rc)"
cat "$out"
if [ "$rc" -ne 0 ]; then echo "FAIL: qemu exited $rc (124 = timeout after ${limit} s)"; exit 1; fi
"$host" >"$ref" 2>&1 || { echo "FAIL: host reference failed"; cat "$ref"; exit 1; }
echo "--- host reference"
cat "$ref"
grep -qx 'status ok' "$out" || { echo "FAIL: the image did not report status ok"; exit 1; }
grep -qx 'EXIT 0' "$out" || { echo "FAIL: the image did not exit 0"; exit 1; }
a=$(grep '^checksum ' "$out") b=$(grep '^checksum ' "$ref")
[ -n "$a" ] || { echo "FAIL: no checksum from the image"; exit 1; }
if [ "$a" != "$b" ]; then echo "FAIL: checksums differ between LEON3 and host"; exit 1; fi
echo "PASS: LEON3 checksums equal the host's"
