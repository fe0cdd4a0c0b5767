// node-mavlink checks qnavd's MAVLink 2 signatures (mavlink.key_file): the bytes qnavd sent in a short
// signed mission (test_qnavd_mavlink_signing with QNAVD_MAVLINK_CAPTURE=PATH: PATH.bin the bytes,
// PATH.json the key and what qnav's own parser counted):
//  - every frame has a valid CRC in node-mavlink, carries a signature, and the signature matches the
//    key (MavLinkPacketSignature.matches); none matches another key;
//  - the link id is qnavd's, the timestamps strictly increase, and they are 10 us units since
//    2015-01-01 near the time the capture was written (the signing specification's clock), not
//    node-mavlink's own default (ms since 1970).
// Usage: node daemon_signed_peer.cjs PATH ; exit 0 pass, 1 mismatch, 77 skip (no node-mavlink).
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
const { MavLinkPacketSplitter, MavLinkPacketParser, MavLinkPacketSignature } = mav;
const REGISTRY = { ...mav.minimal.REGISTRY, ...mav.common.REGISTRY, ...mav.ardupilotmega.REGISTRY };
const MAGIC = {};
for (const id of Object.keys(REGISTRY)) MAGIC[id] = REGISTRY[id].MAGIC_NUMBER;

(async () => {
  const t0 = Date.now();
  const bytes = fs.readFileSync(`${base}.bin`);
  const exp = JSON.parse(fs.readFileSync(`${base}.json`, 'utf8'));
  const key = Buffer.from(exp.key_hex, 'hex');
  const wrongKey = MavLinkPacketSignature.key('not the key');
  const written10us = BigInt(Math.floor((fs.statSync(`${base}.bin`).mtimeMs / 1000 - 1420070400) * 1e5));
  const splitter = new MavLinkPacketSplitter({}, { magicNumbers: MAGIC });
  const parser = new MavLinkPacketParser();
  const packets = [];
  await new Promise((resolve, reject) => {
    Readable.from([bytes]).pipe(splitter).pipe(parser).on('data', (p) => packets.push(p)).on('end', resolve).on('error', reject);
  });
  const mismatches = [];
  if (splitter.invalidPackages !== 0 || splitter.unknownPackagesCount !== 0)
    mismatches.push(`node-mavlink counted ${splitter.invalidPackages} invalid (CRC) and ${splitter.unknownPackagesCount} unknown packets`);
  if (packets.length !== exp.frames) mismatches.push(`qnav's parser verified ${exp.frames} frames, node-mavlink found ${packets.length}`);
  let verified = 0, last = -1n, first = null;
  const ids = {};
  for (let i = 0; i < packets.length; ++i) {
    const p = packets[i];
    ids[p.header.msgid] = (ids[p.header.msgid] || 0) + 1;
    if (p.header.sysid !== exp.system_id || p.header.compid !== exp.component_id) mismatches.push(`#${i}: from ${p.header.sysid}/${p.header.compid}`);
    const s = p.signature;
    if (!s) { mismatches.push(`#${i} (${REGISTRY[p.header.msgid].MSG_NAME}): not signed`); continue; }
    if (s.matches(key)) ++verified; else mismatches.push(`#${i} (${REGISTRY[p.header.msgid].MSG_NAME}): signature does not match the key`);
    if (s.matches(wrongKey)) mismatches.push(`#${i}: signature matches another key`);
    if (s.linkId !== exp.link_id) mismatches.push(`#${i}: link id ${s.linkId}, expected ${exp.link_id}`);
    const ts = BigInt(s.timestamp);
    if (ts <= last) mismatches.push(`#${i}: timestamp ${ts} not after ${last}`);
    if (first === null) first = ts;
    last = ts;
  }
  // The capture was written right after the mission: its last timestamp is within minutes of then.
  const skew_s = last < 0n ? NaN : Number(written10us - last) / 1e5;
  if (!(Math.abs(skew_s) < 600)) mismatches.push(`last timestamp ${last} is ${skew_s} s from the capture's time (not 10 us units since 2015?)`);
  const names = Object.keys(ids).map((id) => `${REGISTRY[id].MSG_NAME} ${ids[id]}`).join(', ');
  console.log(`qnavd signed -> node-mavlink: ${packets.length} frames (${names}), ${verified} signatures match the key, ` +
              `timestamps ${first} .. ${last} (${Number(last - first) / 1e5} s), last ${skew_s.toFixed(1)} s before the capture was written, ` +
              `${mismatches.length} mismatches`);
  for (const m of mismatches.slice(0, 20)) console.log(`  ${m}`);
  console.log(`daemon_signed_peer: ${mismatches.length === 0 ? 'PASS' : 'FAIL'} (${Date.now() - t0} ms)`);
  process.exit(mismatches.length === 0 ? 0 : 1);
})().catch((e) => { console.log(`FAIL: ${e.stack || e}`); process.exit(1); });
