#!/bin/bash
# qnavd's map mode runs the mapper `qnav map` runs (firmware/pipeline/topo_mapper) on the same frames:
# the real downward snippet (../shared/data/downward/sparus_snippet, 22 frames) with a black and a
# saturated frame put in. Per frame the daemon's status and pose must equal the tool's to the tool's
# CSV precision (the same code on the same bytes gives the same numbers; a lost, reordered or
# differently configured frame moves the chain by tenths of a pixel or more); the two bad frames are
# flagged (dark / saturated) with the pose and the node count unchanged, the next frame registers;
# the map file the daemon saved through the FileStore is byte-identical to the tool's --map-out.
# CAN (the simulated autopilot's candump, decoded by `qnav can decode --all` against docs/qnav.dbc,
# which `qnav can dbc` checks first): one QNAV_MAP_POSE + QNAV_MAP_STATUS per frame, FrameSeq = the
# log's seq; per frame the pose equals the log's and the tool's within the signals' resolution
# (X / Y 0.01 px: <= 0.005 px + the CSV's 0.0005 rounding; heading 0.0004 rad: <= 0.0002 rad + the
# CSV's 0.00005 deg), NodeId the log's node on every observed frame (and held on the others),
# NodeCount the log's nodes, Registered on every ok frame, the black frame Black and the saturated one
# Saturated, neither Registered.
# Skipped (77) without the data. Usage: $0 QNAVD QNAV WORKDIR SHARED_DIR
set -u
D=$1
Q=$2
W=$3
S=$4/data/downward/sparus_snippet/frames
DBC=$(cd "$(dirname "$0")/../../../.." && pwd)/docs/qnav.dbc
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
[sim]
candump = "$W/bus.log"
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
"$Q" can dbc "$DBC" > "$W/dbc.txt" 2>&1 || fail "qnav can dbc $DBC: $(cat "$W/dbc.txt")"
"$Q" can decode "$W/bus.log" --all > "$W/bus.txt" 2> "$W/bus_err.txt" || fail "qnav can decode: $(cat "$W/bus_err.txt")"
python3 - "$W/tool/map_trajectory.csv" "$W/qnavd.jsonl" "$W/bus.txt" <<'PY' || fail "the map mode's CAN frames disagree with the log or the tool"
import csv, json, math, re, sys
tool = list(csv.DictReader(open(sys.argv[1])))
ev = [json.loads(l) for l in open(sys.argv[2]) if '"event":"map"' in l]
def frames(name):
    out = []
    for line in open(sys.argv[3]):
        f = line.split()
        if len(f) > 2 and f[1] == name:
            out.append({k: float(v) for k, v in re.findall(r'(\w+)=([-+0-9.eE]+)', line)})
    return out
pose, status = frames('QNAV_MAP_POSE'), frames('QNAV_MAP_STATUS')
assert len(pose) == len(ev) and len(status) == len(ev), f"CAN: {len(pose)} MAP_POSE, {len(status)} MAP_STATUS for {len(ev)} frames"
dx = dh = dt = 0.0
node = 65535
for i, (p, s, e, t) in enumerate(zip(pose, status, ev, tool)):
    assert s['FrameSeq'] == e['seq'] and p['Counter'] == s['Counter'], f"frame {i}: FrameSeq {s['FrameSeq']} / log seq {e['seq']}, counters"
    assert s['Metric'] == 0, "the snippet has no camera: mosaic pixels"
    dx = max(dx, abs(p['X'] - e['x_px']), abs(p['Y'] - e['y_px']))
    h = math.remainder(math.radians(e['heading_deg']), 2 * math.pi)
    dh = max(dh, abs(p['Heading'] - h))
    dt = max(dt, abs(p['X'] - float(t['x_px'])), abs(p['Y'] - float(t['y_px'])), abs(p['Heading'] - math.remainder(math.radians(float(t['heading_deg'])), 2 * math.pi)))
    if e['node'] >= 0:
        node = e['node']
        if t['map_node']:
            assert int(t['map_node']) == s['NodeId'], f"frame {i}: NodeId {s['NodeId']}, tool {t['map_node']}"
    assert s['NodeId'] == node and s['NodeCount'] == e['nodes'], f"frame {i}: NodeId {s['NodeId']} / {node}, NodeCount {s['NodeCount']} / {e['nodes']}"
    assert s['NewNode'] == (e['kind'] == 'created') and s['Revisit'] == e['revisit'], f"frame {i}: NewNode / Revisit"
    assert s['Registered'] == (e['status'] == 'ok'), f"frame {i}: Registered {s['Registered']}, status {e['status']}"
    assert s['Black'] == bool(e['bad_input'] & 1) and s['Saturated'] == bool(e['bad_input'] & 2) and s['Textureless'] == bool(e['bad_input'] & 4)
    assert s['Lost'] == (e['status'] not in ('ok', 'bad_input')), f"frame {i}: Lost"
assert dx <= 0.005 + 1e-6 and dh <= 0.0002 + 1e-6, f"CAN vs log: {dx} px, {dh} rad"
assert dt <= 0.0056 and dh <= 0.00021, f"CAN vs qnav map: {dt}"
bad = [i for i, t in enumerate(tool) if t['file'].endswith('b.pgm')]
assert status[bad[0]]['Black'] == 1 and status[bad[1]]['Saturated'] == 1, "bad frames not flagged on CAN"
assert all(status[i]['Registered'] == 0 and status[i + 1]['Registered'] == 1 for i in bad), "bad frames' Registered"
assert all((pose[i]['X'], pose[i]['Y'], pose[i]['Heading']) == (pose[i - 1]['X'], pose[i - 1]['Y'], pose[i - 1]['Heading']) for i in bad), \
    "a bad frame moved the pose on CAN"
print(f"qnavd map CAN: {len(pose)} MAP_POSE + {len(status)} MAP_STATUS; pose vs log max {dx:.4f} px, {dh:.5f} rad; vs qnav map {dt:.4f}; "
      f"Black / Saturated on the 2 bad frames; last NodeId {status[-1]['NodeId']:.0f} of {status[-1]['NodeCount']:.0f}")
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
