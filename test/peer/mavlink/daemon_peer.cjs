// node-mavlink reads what qnavd itself sent in a short simulated mission (test_qnavd_mavlink with
// QNAVD_MAVLINK_CAPTURE=PATH: PATH.bin the bytes, PATH.json what qnav's parser found in them):
//  - every frame has a valid CRC in node-mavlink and none is unknown to it; the same message ids in
//    the same order as qnav's parser found;
//  - every ODOMETRY decodes in node-mavlink to the values qnav decoded (frame_id LOCAL_FRD 20,
//    child BODY_FRD 12, position, quaternion, velocity, reset_counter, estimator_type, quality).
// Usage: node daemon_peer.cjs PATH ; exit 0 pass, 1 mismatch, 77 skip (no node-mavlink).
'use strict';
const fs = require('fs');
const path = require('path');
const { Readable } = require('stream');

const [base] = process.argv.slice(2);
const prefix = process.env.QNAV_NPM_PREFIX || path.resolve(__dirname, '../../../build/npm');
const modDir = path.join(prefix, 'node_modules', 'node-mavlink');
if (!fs.existsSync(modDir)) {
  console.log(`SKIP: node-mavlink is not installed in ${prefix} (run scripts/setup with the npm registry reachable, or set QNAV_NPM_PREFIX)`);
  process.exit(77);
}
const mav = require(modDir);
const { MavLinkPacketSplitter, MavLinkPacketParser } = mav;
const REGISTRY = { ...mav.minimal.REGISTRY, ...mav.common.REGISTRY, ...mav.ardupilotmega.REGISTRY };
const MAGIC = {};
for (const id of Object.keys(REGISTRY)) MAGIC[id] = REGISTRY[id].MAGIC_NUMBER;

function sameFloat(exp, got) {
  const e = Number(exp);
  if (Number.isNaN(e)) return Number.isNaN(got);
  return Object.is(Math.fround(e), got);
}

(async () => {
  const t0 = Date.now();
  const bytes = fs.readFileSync(`${base}.bin`);
  const exp = JSON.parse(fs.readFileSync(`${base}.json`, 'utf8'));
  const splitter = new MavLinkPacketSplitter({}, { magicNumbers: MAGIC });
  const parser = new MavLinkPacketParser();
  const packets = [];
  await new Promise((resolve, reject) => {
    Readable.from([bytes]).pipe(splitter).pipe(parser).on('data', (p) => packets.push(p)).on('end', resolve).on('error', reject);
  });
  const mismatches = [];
  if (splitter.invalidPackages !== 0 || splitter.unknownPackagesCount !== 0)
    mismatches.push(`node-mavlink counted ${splitter.invalidPackages} invalid (CRC) and ${splitter.unknownPackagesCount} unknown packets`);
  if (packets.length !== exp.msgids.length) mismatches.push(`qnav's parser found ${exp.msgids.length} frames, node-mavlink ${packets.length}`);
  const counts = {};
  let odo = 0, fields = 0;
  const ODO = REGISTRY[331];
  for (let i = 0; i < Math.min(packets.length, exp.msgids.length); ++i) {
    const p = packets[i];
    const id = p.header.msgid;
    counts[id] = (counts[id] || 0) + 1;
    if (id !== exp.msgids[i]) { mismatches.push(`frame #${i}: qnav ${exp.msgids[i]} node ${id}`); continue; }
    if (id !== 331) continue;
    const d = p.protocol.data(p.payload, ODO);
    const e = exp.odometry[odo++];
    if (!e) { mismatches.push(`ODOMETRY #${odo}: node found more than qnav`); continue; }
    const check = (name, ok) => { ++fields; if (!ok) mismatches.push(`ODOMETRY #${odo - 1}.${name}: qnav ${JSON.stringify(e[name])} node ${JSON.stringify(d[name], (k, v) => typeof v === 'bigint' ? v.toString() : v)}`); };
    check('time_usec', BigInt(e.time_usec) === BigInt(d.timeUsec));
    check('frame_id', e.frame_id === d.frameId && d.frameId === 20);
    check('child_frame_id', e.child_frame_id === d.childFrameId && d.childFrameId === 12);
    for (const k of ['x', 'y', 'z', 'vx', 'vy', 'vz']) check(k, sameFloat(e[k], d[k]));
    check('q', e.q.every((v, j) => sameFloat(v, d.q[j])));
    check('reset_counter', e.reset_counter === d.resetCounter);
    check('estimator_type', e.estimator_type === d.estimatorType);
    check('quality', e.quality === d.quality && d.quality >= -1 && d.quality <= 100);
  }
  if (odo !== exp.odometry.length) mismatches.push(`ODOMETRY: qnav ${exp.odometry.length}, node-mavlink ${odo}`);
  const names = Object.keys(counts).map((id) => `${REGISTRY[id].MSG_NAME} ${counts[id]}`).join(', ');
  console.log(`qnavd -> node-mavlink: ${packets.length} frames from a simulated mission (${names}), ${fields} ODOMETRY fields compared, ${mismatches.length} mismatches`);
  for (const m of mismatches.slice(0, 20)) console.log(`  ${m}`);
  console.log(`daemon_peer: ${mismatches.length === 0 ? 'PASS' : 'FAIL'} (${Date.now() - t0} ms)`);
  process.exit(mismatches.length === 0 ? 0 : 1);
})().catch((e) => { console.log(`FAIL: ${e.stack || e}`); process.exit(1); });
