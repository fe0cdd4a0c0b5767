#!/usr/bin/env bash
# qnav_cli_strict_test.sh QNAV QNAVD REPO WORKDIR
# Every qnav command and qnavd against the mistakes a person makes on a command line (docs/cli.md):
# an unknown option, a bad value, a missing file, a directory, an empty file, a file of the wrong
# format -> the exit code (2 usage, 1 the work failed / nothing valid) and a message naming the
# problem; --help on stdout with exit 0; `qnav help route` prints route's help. Tiny inputs: < 5 s.
set -u
Q=$1 D=$2 R=$3 W=$4
rm -rf "$W" && mkdir -p "$W/dir" && cd "$W" || exit 1
: > empty.txt
WRONG="$R/README.md"   # text that is no sensor format, no route, no image
fails=0 checks=0

# err CODE REGEX CMD...: exits CODE, stderr matches REGEX (extended, case-sensitive).
err() {
  local code=$1 re=$2 rc
  shift 2
  checks=$((checks + 1))
  "$@" > out.txt 2> err.txt
  rc=$?
  if [ "$rc" -ne "$code" ] || ! grep -Eq -- "$re" err.txt; then
    echo "FAIL: $* -> exit $rc (want $code), stderr must match /$re/:"
    sed 's/^/    /' err.txt | head -5
    fails=$((fails + 1))
  fi
}
# ok REGEX CMD...: exits 0, stdout matches REGEX.
ok() {
  local re=$1 rc
  shift
  checks=$((checks + 1))
  "$@" > out.txt 2> err.txt
  rc=$?
  if [ "$rc" -ne 0 ] || ! grep -Eq -- "$re" out.txt; then
    echo "FAIL: $* -> exit $rc (want 0), stdout must match /$re/:"
    sed 's/^/    /' out.txt err.txt | head -5
    fails=$((fails + 1))
  fi
}
# help CMD...: exit 0, the help on stdout, nothing on stderr.
help() {
  ok '^Usage: ' "$@"
  if [ -s err.txt ]; then
    echo "FAIL: $* printed on stderr"
    fails=$((fails + 1))
  fi
}

# Tiny valid inputs.
"$Q" sonar simulate --out s.xtf --length-m 10 --samples 64 > /dev/null || { echo "FAIL: sonar simulate"; exit 1; }
"$Q" can simulate c.log --seconds 0.2 > /dev/null || { echo "FAIL: can simulate"; exit 1; }
"$Q" dvl simulate d.txt --seconds 0.5 > /dev/null || { echo "FAIL: dvl simulate"; exit 1; }
printf '  can0  123   [2]  11 22\n  can0  1F334455   [8]  01 02 03 04 05 06 07 08\n' > screen.log

# ---- qnav itself: the command list, help, unknown commands ----
help "$Q" --help
ok 'route' "$Q" --help
ok 'Usage: qnav route' "$Q" help route
ok 'train' "$Q" help route
ok 'length-m NUM +length of the simulated route \(m; default 2000; 200\.\.50000\)' "$Q" help route train
help "$Q" route --help
ok '==== qnav route train ====' "$Q" --help-all   # every (sub)command's help: the man page's text
help "$Q" route train --help
err 2 "unknown command 'rout'.*'route'" "$Q" rout
err 2 "unknown command 'nosuch'" "$Q" help nosuch
err 2 "give a command" "$Q"
err 2 "give a subcommand: train info repeat eval framing xtf camera" "$Q" route
err 2 "unexpected argument 'trian'.*'train'" "$Q" route trian
for c in can dvl map route sonar stereo version vo xtf; do ok "$c" "$Q" --help; done
for c in can dvl map route sonar stereo version vo xtf; do help "$Q" help "$c"; help "$Q" "$c" --help; done

# ---- route ----
err 2 "unknown option '--lenght-m'.*did you mean '--length-m'" "$Q" route train --sim --out r.qroute --lenght-m 300
err 2 "--length-m: 5 is outside the allowed range 200\.\.50000 m" "$Q" route train --sim --out r.qroute --length-m 5
err 2 "--offset-pct: 'x' is not a number" "$Q" route repeat --route r.qroute --sim --offset-pct x
err 2 "--out.*required" "$Q" route train --sim
err 2 "--pings: give A:B" "$Q" route train --sonar s.xtf --out r.qroute --pings 9
err 1 "nosuch.qroute: No such file or directory" "$Q" route info nosuch.qroute
err 1 "dir: is a directory" "$Q" route info dir
err 1 "empty.txt: empty file" "$Q" route info empty.txt
err 1 "not a qnav route file" "$Q" route info "$WRONG"
err 1 "dir: is a directory" "$Q" route train --sonar dir --out r.qroute
err 1 "not an XTF file" "$Q" route train --sonar "$WRONG" --out r.qroute
[ -e r.qroute ] && { echo "FAIL: a refused route train wrote r.qroute"; fails=$((fails + 1)); }

# ---- sonar ----
err 2 "unknown option '--corected'.*'--corrected'" "$Q" sonar waterfall s.xtf --out w.png --corected
err 2 "--samples: 8 is outside the allowed range 16\.\.16384" "$Q" sonar simulate --out x.xtf --samples 8
err 2 "--nav: 'gps' is not one of fix, dr" "$Q" sonar tiles s.xtf --out t --nav gps
err 1 "nosuch.xtf: No such file or directory" "$Q" sonar waterfall nosuch.xtf --out w.png
err 1 "dir: is a directory" "$Q" sonar tiles dir --out t
err 1 "empty.txt: empty file" "$Q" sonar waterfall empty.txt --out w.png
err 1 "not an XTF file" "$Q" sonar waterfall "$WRONG" --out w.png
ok "waterfall new/sub/w.png" "$Q" sonar waterfall s.xtf --out new/sub/w.png   # --out's folders are created
# The pictures a person reads: the waterfall drawn with axes around it (wider than its 2 x 64 samples),
# --raster the bare image one pixel per sample; each tile's bare rasters and its plot.
png_w() { od -An -tu1 -j16 -N4 "$1" | awk '{ print $1 * 16777216 + $2 * 65536 + $3 * 256 + $4 }'; }
ok "waterfall w.png" "$Q" sonar waterfall s.xtf --out w.png --raster raw/w.png
checks=$((checks + 1))
if [ "$(png_w raw/w.png)" != 128 ] || [ "$(png_w w.png)" -le 128 ]; then
  echo "FAIL: waterfall --raster $(png_w raw/w.png) px wide (want 128), the plot $(png_w w.png) (want more)"
  fails=$((fails + 1))
fi
ok "tile 0" "$Q" sonar tiles s.xtf --out t --size 256
checks=$((checks + 1))
for f in tile_000.png tile_000_coverage.png tile_000_plot.png tiles.csv; do
  [ -s "t/$f" ] || { echo "FAIL: sonar tiles wrote no t/$f"; fails=$((fails + 1)); }
done
[ "$(png_w t/tile_000.png)" = 256 ] || { echo "FAIL: tile_000.png $(png_w t/tile_000.png) px wide (want 256)"; fails=$((fails + 1)); }

# ---- vo ----
err 2 "unknown option '--quik'.*'--quick'" "$Q" vo eval --quik
err 2 "--noise: 'loud' is not one of small, moderate, none" "$Q" vo eval --noise loud
err 2 "--frames: 1 is outside the allowed range 2\.\." "$Q" vo --kitti dir --out p.txt --frames 1
err 2 "needs --out" "$Q" vo --kitti dir
err 2 "give .eval., --kitti DIR or --euroc DIR" "$Q" vo
err 1 "nosuch: No such file or directory" "$Q" vo --kitti nosuch --out p.txt
err 1 "README.md: not a directory" "$Q" vo --euroc "$WRONG" --out p.txt
err 1 "dir: cannot read the KITTI sequence" "$Q" vo --kitti dir --out p.txt
ok 'att-rate-scale' "$Q" help vo eval
ok 'track-radius' "$Q" help vo eval

# ---- can ----
err 2 "unknown option '--nod'.*'--node'" "$Q" can decode c.log --nod 3
err 2 "--node: 300 is outside the allowed range 0\.\.127" "$Q" can decode c.log --node 300
err 2 "--seconds: 'nan' is not a number" "$Q" can simulate x.log --seconds nan
err 1 "nosuch.log: No such file or directory" "$Q" can decode nosuch.log
err 1 "dir: is a directory" "$Q" can decode dir
err 1 "empty.txt: empty file" "$Q" can dbc empty.txt
err 1 "no CAN frame in the log.*screen format" "$Q" can decode "$WRONG"
err 1 "no message \(BO_\) in the DBC file" "$Q" can dbc "$WRONG"
ok "frames 2, bad log lines 0" "$Q" can decode screen.log     # candump's screen format
ok "frames [1-9]" "$Q" can decode c.log                        # and candump -l

# ---- dvl ----
err 2 "unknown option '--pd7'.*'--pd6'" "$Q" dvl parse d.txt --pd7
err 2 "--seconds: 0 is outside the allowed range" "$Q" dvl simulate x.txt --seconds 0
err 2 "--baud: 'fast' is not a number" "$Q" dvl listen /dev/null --baud fast
err 1 "nosuch.txt: No such file or directory" "$Q" dvl parse nosuch.txt
err 1 "dir: is a directory" "$Q" dvl parse dir
err 1 "empty.txt: empty file" "$Q" dvl parse empty.txt
err 1 "no Water Linked velocity sentence.*binary" "$Q" dvl parse s.xtf
err 1 "no Water Linked velocity sentence" "$Q" dvl parse "$WRONG"
ok "velocity samples" "$Q" dvl parse d.txt

# ---- xtf ----
err 2 "unknown option '--verbose'" "$Q" xtf info s.xtf --verbose
err 2 "unexpected argument 'extra'" "$Q" xtf info s.xtf extra
err 2 "unexpected argument 'show'" "$Q" xtf show s.xtf
err 1 "nosuch.xtf: No such file or directory" "$Q" xtf info nosuch.xtf
err 1 "dir: is a directory" "$Q" xtf info dir
err 1 "empty.txt: empty file" "$Q" xtf info empty.txt
err 1 "not an XTF file" "$Q" xtf info "$WRONG"

# ---- stereo ----
err 2 "unknown option '--filtr'.*'--filter'" "$Q" stereo degrade x.png --filtr 2
err 2 "--filter: 9 is outside the allowed range 1\.\.5" "$Q" stereo degrade x.png --filter 9
err 2 "--max-disparity: 1 is outside the allowed range 3\.\.500" "$Q" stereo disparity a.png b.png --max-disparity 1
err 1 "nosuch.png: No such file or directory" "$Q" stereo degrade nosuch.png
err 1 "dir: is a directory" "$Q" stereo degrade dir
err 1 "empty.txt: empty file" "$Q" stereo degrade empty.txt
err 1 "unknown format" "$Q" stereo degrade "$WRONG"

# ---- map ----
err 2 "unknown option '--imagse'.*'--images'" "$Q" map --imagse dir
err 2 "--laps: 9 is outside the allowed range 1\.05\.\.5" "$Q" map eval --laps 9
err 2 "--from is required" "$Q" map route --map m.qmap
err 1 "nosuch: No such file or directory" "$Q" map --images nosuch --no-plot
err 1 "README.md: not a directory" "$Q" map --images "$WRONG" --no-plot
err 1 "nosuch.qmap: No such file or directory" "$Q" map route --map nosuch.qmap --from 0 --to 1
err 1 "dir: is a directory" "$Q" map route --map dir --from 0 --to 1
err 1 "empty.txt: empty file" "$Q" map route --map empty.txt --from 0 --to 1
err 1 "README.md" "$Q" map route --map "$WRONG" --from 0 --to 1

# ---- version ----
err 2 "unknown option '--verbose'" "$Q" version --verbose
ok "^qnav [0-9]" "$Q" version

# ---- qnavd ----
help "$D" --help
err 2 "unknown option '--confg'.*'--config'" "$D" --confg x.toml
err 2 "--check-config.*(required|missing)" "$D" --check-config
err 1 "nosuch.toml: cannot open: No such file or directory" "$D" --check-config nosuch.toml
err 1 "dir: cannot read: Is a directory" "$D" --check-config dir
err 1 "empty.txt" "$D" --check-config empty.txt
err 1 "README.md:[0-9]+: " "$D" --check-config "$WRONG"
ok "^qnavd [0-9]" "$D" --version

echo "qnav_cli_strict: $checks checks, $fails failed"
[ "$fails" -eq 0 ]
