#!/bin/bash
# qnavd's map mode runs the mapper `qnav map` runs (firmware/pipeline/topo_mapper) on the same frames:
# the real downward snippet (../shared/data/downward/sparus_snippet, 22 frames) with a black and a
# saturated frame put in. Per frame the daemon's status and pose must equal the tool's to the tool's
# CSV precision (the same code on the same bytes gives the same numbers; a lost, reordered or
# differently configured frame moves the chain by tenths of a pixel or more); the two bad frames are
# flagged (dark / saturated) with the pose and the node count unchanged, the next frame registers;
# the map file the daemon saved through the FileStore is byte-identical to the tool's --map-out.
# Skipped (77) without the data. Usage: $0 QNAVD QNAV WORKDIR SHARED_DIR
set -u
D=$1
Q=$2
W=$3
S=$4/data/downward/sparus_snippet/frames
[ -d "$S" ] || { echo "SKIP: no $S"; exit 77; }
rm -rf "$W" && mkdir -p "$W/frames" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
cp "$S"/frame_*.png "$W/frames/" || fail "copy frames"
python3 - "$W/frames" <<'PY' || fail "bad frames"
import sys
d = sys.argv[1]
open(d + '/frame_0010b.pgm', 'wb').write(b'P5\n384 288\n255\n' + bytes(384 * 288))          # black
open(d + '/frame_0015b.pgm', 'wb').write(b'P5\n384 288\n255\n' + bytes([255]) * (384 * 288))  # saturated
PY
"$Q" map --images "$W/frames" --out "$W/tool" --map-out "$W/tool/map.qmap" --node-spacing 30 --no-plot > "$W/tool.txt" 2>&1
[ -f "$W/tool/map_trajectory.csv" ] || fail "qnav map wrote no trajectory: $(cat "$W/tool.txt")"
cat > "$W/map.toml" <<CFG
[daemon]
backend = "sim"
route_dir = "$W/routes"
log = "json"
realtime = false
[map]
enabled = true
width = 384
height = 288
node_spacing = 30.0
[[sim.pass]]
mode = "map"
images = "$W/frames"
CFG
"$D" --print-deployment --config "$W/map.toml" > "$W/deployment.txt" || fail "print-deployment"
grep -q "^  map .*per downward frame" "$W/deployment.txt" || fail "no map stage in the deployment table"
"$D" --config "$W/map.toml" > "$W/qnavd.jsonl" 2> "$W/err.txt" || fail "qnavd exit $?: $(cat "$W/err.txt")"
grep -q '"event":"mode","t_s":[0-9.]*,"cmd":"map","reverse":false,"route_id":1,"state":"map","refused":false' "$W/qnavd.jsonl" ||
  fail "the daemon did not enter map mode"
python3 - "$W/tool/map_trajectory.csv" "$W/qnavd.jsonl" <<'PY' || fail "the daemon and the tool disagree"
import csv, json, sys
tool = list(csv.DictReader(open(sys.argv[1])))
ev = [json.loads(l) for l in open(sys.argv[2]) if '"event":"map"' in l]
assert len(tool) == 24 and len(ev) == 24, f"frames: tool {len(tool)}, daemon {len(ev)}"
dx = dh = 0.0
for t, e in zip(tool, ev):
    status = t['status']
    assert status == e['status'], f"frame {t['frame']} ({t['file']}): tool {status}, daemon {e['status']}"
    dx = max(dx, abs(float(t['x_px']) - e['x_px']), abs(float(t['y_px']) - e['y_px']))
    dh = max(dh, abs(float(t['heading_deg']) - e['heading_deg']))
    if t['map_node']:
        assert int(t['map_node']) == e['node'] and t['map_kind'] == e['kind'], f"frame {t['frame']}: map node/kind differ"
# The CSV prints 3 decimals of pixels and 4 of degrees: rounding alone is < 0.0006 px / 0.00006 deg.
assert dx <= 0.002 and dh <= 0.0002, f"pose differs: {dx} px, {dh} deg"
bad = [i for i, t in enumerate(tool) if t['file'].endswith('b.pgm')]
assert [ev[i]['status'] for i in bad] == ['bad_input', 'bad_input'], "bad frames not flagged"
assert ev[bad[0]]['bad_input'] & 1 and ev[bad[1]]['bad_input'] & 2, "flag reasons (dark 1, saturated 2) wrong"
for i in bad:
    p, b, n = ev[i - 1], ev[i], ev[i + 1]
    assert (b['x_px'], b['y_px'], b['heading_deg'], b['nodes'], b['edges']) == (p['x_px'], p['y_px'], p['heading_deg'], p['nodes'], p['edges']), \
        f"bad frame {i} moved the pose or the map"
    assert b['node'] == -1 and b['kind'] == 'none', f"bad frame {i} observed"
    assert n['status'] == 'ok', f"frame {i + 1} after the bad one did not register"
ok = sum(e['status'] == 'ok' for e in ev)
print(f"qnavd map vs qnav map: {len(ev)} frames, {ok} ok, 2 bad flagged; pose max difference {dx:.4f} px, {dh:.5f} deg; "
      f"map {ev[-1]['nodes']} nodes, {ev[-1]['edges']} edges")
PY
cmp "$W/tool/map.qmap" "$W/routes/map_1.qmap" || fail "the daemon's map file differs from the tool's"
"$Q" map route --map "$W/routes/map_1.qmap" --from 0 --to 1 > /dev/null || fail "the daemon's map is not readable by qnav map route"
grep -q '"event":"map_closed","route_id":1,"nodes":[1-9][0-9]*,.*"frames":24,"bad_frames":2,.*"save_errors":0' "$W/qnavd.jsonl" ||
  fail "no map_closed event with 24 frames, 2 bad"
# A map pass without map.enabled: refused at start-up with the key named.
sed 's/^enabled = true/enabled = false/' "$W/map.toml" > "$W/off.toml"
"$D" --config "$W/off.toml" > /dev/null 2> "$W/off.txt" && fail "a map pass without map.enabled was accepted"
grep -q "map.enabled" "$W/off.txt" || { cat "$W/off.txt"; fail "the refusal does not name map.enabled"; }
echo "map: ok"
