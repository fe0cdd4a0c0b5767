#!/bin/bash
# qnavd's command line: help and version on stdout with exit 0, unknown options exit 2, a bad
# configuration exit 1 with FILE:LINE: key: reason, the deployment table. Usage: $0 QNAVD WORKDIR
set -u
D=$1
W=$2
rm -rf "$W" && mkdir -p "$W" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
"$D" --help > "$W/help.txt" 2>&1 || fail "--help exit $?"
grep -q -- "--check-config" "$W/help.txt" || fail "--help does not list --check-config"
"$D" --version | grep -q "^qnavd [0-9]" || fail "--version"
"$D" --no-such-option > "$W/out.txt" 2>&1; rc=$?
[ $rc -eq 2 ] || fail "unknown option: exit $rc (want 2)"
grep -q -- "--no-such-option" "$W/out.txt" || fail "unknown option not named"
printf '[daemon]\nbackend = "sim"\n[sim]\nlenght_m = 300\n[[sim.pass]]\nmode = "teach"\n' > "$W/typo.toml"
"$D" --check-config "$W/typo.toml" > "$W/out.txt" 2>&1; rc=$?
[ $rc -eq 1 ] || fail "misspelt key: exit $rc (want 1)"
grep -q "typo.toml:4: sim.lenght_m" "$W/out.txt" || { cat "$W/out.txt"; fail "misspelt key not located"; }
grep -q "length_m" "$W/out.txt" || fail "no suggestion for the misspelt key"
printf '[route]\nmax_nodes = 1\n' > "$W/range.toml"
"$D" --check-config "$W/range.toml" > "$W/out.txt" 2>&1 && fail "out-of-range value accepted"
grep -q "range.toml:2: route.max_nodes" "$W/out.txt" || { cat "$W/out.txt"; fail "range error not located"; }
"$D" --check-config "$W/missing.toml" > "$W/out.txt" 2>&1 && fail "missing file accepted"
grep -qi "no such file" "$W/out.txt" || { cat "$W/out.txt"; fail "missing file without the OS reason"; }
printf '[daemon]\nbackend = "sim"\nroute_dir = "%s/routes"\n[sonar]\nping_queue = 64\n[[sim.pass]]\nmode = "teach"\n' "$W" > "$W/ok.toml"
"$D" --check-config "$W/ok.toml" || fail "valid config refused"
"$D" --print-deployment --config "$W/ok.toml" > "$W/dep.txt" || fail "--print-deployment"
grep -Eq "pings +io +-> nav +64" "$W/dep.txt" || { cat "$W/dep.txt"; fail "deployment does not show the configured ping queue depth"; }
grep -q "total .* MB" "$W/dep.txt" || fail "deployment without total static memory"
echo "qnavd command line: ok"
