// node-mavlink (an independent MAVLink implementation, with mavlink-mappings generated from the
// official XML) against qnav's drivers/mavlink codec, both directions:
//  1. qnav -> node: mavlink_peer_tool gen writes COUNT frames of random values; node-mavlink's splitter
//     must find every one with a valid CRC (and a valid signature where signed), and its decoded
//     fields must equal the values qnav meant (JSON from the tool), field by field over every field
//     of node's definition (extensions included).
//  2. node -> qnav: node-mavlink serializes COUNT messages of random values (MAVLink 2, some MAVLink 1,
//     some signed, some with zero extensions for truncation, garbage bytes between frames);
//     mavlink_peer_tool decode parses them and must return the same values, with no reject counter
//     other than the injected garbage bytes.
// Usage: node mavlink_peer.cjs TOOL WORKDIR [COUNT] ; exit 0 pass, 1 mismatch, 77 skip (no node-mavlink).
'use strict';
const fs = require('fs');
const path = require('path');
const { execFileSync } = require('child_process');
const { Readable } = require('stream');

const [tool, workdir, countArg] = process.argv.slice(2);
const COUNT = Number(countArg || 5000);
const prefix = process.env.QNAV_NPM_PREFIX || path.resolve(__dirname, '../../../build/npm');
const modDir = path.join(prefix, 'node_modules', 'node-mavlink');
if (!fs.existsSync(modDir)) {
  console.log(`SKIP: node-mavlink is not installed in ${prefix} (run scripts/setup with the npm registry reachable, or set QNAV_NPM_PREFIX)`);
  process.exit(77);
}
const mav = require(modDir);
const { MavLinkPacketSplitter, MavLinkPacketParser, MavLinkProtocolV1, MavLinkProtocolV2, MavLinkPacketSignature } = mav;
const REGISTRY = { ...mav.minimal.REGISTRY, ...mav.common.REGISTRY, ...mav.ardupilotmega.REGISTRY };
const IDS = [0, 2, 30, 32, 48, 49, 76, 77, 84, 102, 103, 132, 193, 251, 253, 331, 11011];
const MAGIC = {};
for (const id of IDS) {
  if (!REGISTRY[id]) { console.log(`FAIL: node-mavlink has no message ${id}`); process.exit(1); }
  MAGIC[id] = REGISTRY[id].MAGIC_NUMBER;
}
const KEY = MavLinkPacketSignature.key('qnav-mavlink-peer-test');  // SHA-256 of the passphrase: 32 bytes
const KEY_HEX = KEY.toString('hex');
fs.mkdirSync(workdir, { recursive: true });

// Deterministic random numbers (xorshift32) so a failure reproduces.
let rs = 0x2545F491;
function rnd() { rs ^= rs << 13; rs >>>= 0; rs ^= rs >>> 17; rs ^= rs << 5; rs >>>= 0; return rs; }
function below(n) { return rnd() % n; }

function sameFloat(exp, got) {
  const e = typeof exp === 'string' ? Number(exp) : exp;
  if (Number.isNaN(e)) return Number.isNaN(got);
  return Object.is(Math.fround(e), got);
}
function sameValue(type, exp, got) {
  if (exp === undefined) return false;
  if (type === 'float') return sameFloat(exp, got);
  if (type === 'float[]') return Array.isArray(exp) && exp.length === got.length && exp.every((v, i) => sameFloat(v, got[i]));
  if (type === 'uint64_t' || type === 'int64_t') return BigInt(exp) === BigInt(got);
  if (type === 'char[]') return exp === got;
  return Number(exp) === Number(got);
}
function show(v) { return typeof v === 'bigint' ? v.toString() : JSON.stringify(v); }

// Every field of node's definition compared with qnav's JSON (and no field qnav has that node lacks).
function compareFields(clazz, qnavFields, data, where, mismatches) {
  let n = 0;
  const names = new Set(Object.keys(qnavFields));
  for (const f of clazz.FIELDS) {
    names.delete(f.source);
    ++n;
    if (!sameValue(f.type, qnavFields[f.source], data[f.name])) {
      mismatches.push(`${where} ${clazz.MSG_NAME}.${f.source}: qnav ${show(qnavFields[f.source])} node ${show(data[f.name])}`);
    }
  }
  for (const extra of names) mismatches.push(`${where} ${clazz.MSG_NAME}: qnav field ${extra} unknown to node-mavlink`);
  return n;
}

async function nodeSplit(buf) {
  const splitter = new MavLinkPacketSplitter({}, { magicNumbers: MAGIC });
  const parser = new MavLinkPacketParser();
  const chunks = [];
  for (let at = 0; at < buf.length;) { const n = 1 + below(300); chunks.push(buf.subarray(at, at + n)); at += n; }
  const packets = [];
  await new Promise((resolve, reject) => {
    Readable.from(chunks).pipe(splitter).pipe(parser)
      .on('data', (p) => packets.push(p)).on('end', resolve).on('error', reject);
  });
  return { packets, valid: splitter.validPackages, invalid: splitter.invalidPackages, unknown: splitter.unknownPackagesCount };
}

function randomValue(f) {
  switch (f.type) {
    case 'uint8_t': case 'uint8_t_mavlink_version': return below(256);
    case 'int8_t': return below(256) - 128;
    case 'uint16_t': return below(65536);
    case 'int16_t': return below(65536) - 32768;
    case 'uint32_t': return rnd();
    case 'int32_t': return rnd() | 0;
    case 'uint64_t': return (BigInt(rnd()) << 32n) | BigInt(rnd());
    case 'int64_t': return BigInt.asIntN(64, (BigInt(rnd()) << 32n) | BigInt(rnd()));
    case 'float': { const dv = new DataView(new ArrayBuffer(4)); dv.setUint32(0, rnd(), true); return dv.getFloat32(0, true); }
    case 'float[]': { const a = []; for (let i = 0; i < f.length; ++i) a.push(randomValue({ type: 'float' })); return a; }
    case 'char[]': { let s = ''; const n = below(f.length + 1); for (let i = 0; i < n; ++i) s += String.fromCharCode(0x20 + below(95)); return s; }
    default: throw new Error(`no generator for ${f.type}`);
  }
}
function zeroValue(f) {
  if (f.type === 'uint64_t' || f.type === 'int64_t') return 0n;
  if (f.type === 'float[]') return new Array(f.length).fill(0);
  if (f.type === 'char[]') return '';
  return 0;
}

async function qnavToNode() {
  const frames = path.join(workdir, 'qnav_frames.bin');
  const expected = path.join(workdir, 'qnav_expected.jsonl');
  execFileSync(tool, ['gen', String(COUNT), '20261127', frames, expected, KEY_HEX], { stdio: 'inherit' });
  const exp = fs.readFileSync(expected, 'utf8').trim().split('\n').map((l) => JSON.parse(l));
  const { packets, valid, invalid, unknown } = await nodeSplit(fs.readFileSync(frames));
  const mismatches = [];
  let fields = 0, signed = 0;
  if (packets.length !== exp.length) mismatches.push(`qnav->node: ${exp.length} frames sent, node-mavlink found ${packets.length}`);
  for (let i = 0; i < Math.min(packets.length, exp.length); ++i) {
    const p = packets[i], e = exp[i];
    const h = p.header;
    if (h.msgid !== e.msgid || h.sysid !== e.sysid || h.compid !== e.compid || h.seq !== e.seq)
      mismatches.push(`qnav->node #${i}: header ${h.msgid}/${h.sysid}/${h.compid}/${h.seq} expected ${e.msgid}/${e.sysid}/${e.compid}/${e.seq}`);
    if (e.signed) {
      ++signed;
      if (!p.signature || !p.signature.matches(KEY)) mismatches.push(`qnav->node #${i}: signature does not verify in node-mavlink`);
    }
    const clazz = REGISTRY[h.msgid];
    fields += compareFields(clazz, e.fields, p.protocol.data(p.payload, clazz), `qnav->node #${i}`, mismatches);
  }
  if (invalid !== 0 || unknown !== 0) mismatches.push(`qnav->node: node-mavlink counted ${invalid} invalid (CRC) and ${unknown} unknown packets`);
  console.log(`qnav -> node-mavlink: ${exp.length} frames (${signed} signed), ${valid} with a valid CRC in node-mavlink, ` +
              `${fields} fields compared, ${mismatches.length} mismatches`);
  return mismatches;
}

function nodeToQnav() {
  const out = [];
  const expected = [];
  let garbage = 0, v1 = 0, signed = 0, ts = Date.UTC(2026, 0, 1);  // node-mavlink signs with ms since 1970
  const seqs = {};
  const SENDERS = [];
  for (let k = 0; k < 8; ++k) SENDERS.push([1 + below(254), below(256)]);
  for (let i = 0; i < COUNT; ++i) {
    const id = IDS[below(IDS.length)];
    const clazz = REGISTRY[id];
    const data = new clazz();
    const zeroExt = below(4) === 0;
    const fieldsJson = {};
    for (const f of clazz.FIELDS) {
      const v = zeroExt && f.extension ? zeroValue(f) : randomValue(f);
      data[f.name] = v;
      fieldsJson[f.source] = v;
    }
    // A handful of senders, as on a vehicle (the signing replay table holds 16 streams).
    const sender = SENDERS[below(SENDERS.length)];
    const sysid = sender[0], compid = sender[1];
    const key = `${sysid}/${compid}`;
    const seq = seqs[key] = ((seqs[key] ?? below(256)) + 1) & 255;
    const useV1 = id < 256 && below(5) === 0;
    let buf;
    let isSigned = false;
    if (useV1) {
      buf = new MavLinkProtocolV1(sysid, compid).serialize(data, seq);
      ++v1;
    } else {
      isSigned = below(5) === 0;  // node-mavlink signs a frame serialized with the signed flag set
      const proto = new MavLinkProtocolV2(sysid, compid, isSigned ? MavLinkProtocolV2.IFLAG_SIGNED : 0);
      buf = proto.serialize(data, seq);
      if (isSigned) { buf = proto.sign(buf, 3, KEY, ts++); ++signed; }
    }
    if (below(3) === 0) {  // garbage without magic bytes between frames
      const g = Buffer.alloc(1 + below(40));
      for (let k = 0; k < g.length; ++k) { let b = below(256); if (b === 0xFD || b === 0xFE) b = 0x55; g[k] = b; }
      out.push(g);
      garbage += g.length;
    }
    out.push(buf);
    expected.push({ msgid: id, sysid, compid, seq, version: useV1 ? 1 : 2, signed: isSigned, fields: fieldsJson, data });
  }
  const frames = path.join(workdir, 'node_frames.bin');
  const decoded = path.join(workdir, 'qnav_decoded.jsonl');
  fs.writeFileSync(frames, Buffer.concat(out));
  execFileSync(tool, ['decode', frames, decoded, KEY_HEX], { stdio: 'inherit' });
  const lines = fs.readFileSync(decoded, 'utf8').trim().split('\n').map((l) => JSON.parse(l));
  const counters = lines.pop();
  const mismatches = [];
  let fields = 0;
  if (lines.length !== expected.length) mismatches.push(`node->qnav: ${expected.length} frames sent, qnav decoded ${lines.length}`);
  for (let i = 0; i < Math.min(lines.length, expected.length); ++i) {
    const q = lines[i], e = expected[i];
    if (q.msgid !== e.msgid || q.sysid !== e.sysid || q.compid !== e.compid || q.seq !== e.seq || q.version !== e.version)
      mismatches.push(`node->qnav #${i}: header ${JSON.stringify([q.msgid, q.sysid, q.compid, q.seq, q.version])} expected ${JSON.stringify([e.msgid, e.sysid, e.compid, e.seq, e.version])}`);
    if (q.signed !== e.signed || (e.signed && !q.verified)) mismatches.push(`node->qnav #${i}: signed ${q.signed} verified ${q.verified}, sent signed ${e.signed}`);
    const clazz = REGISTRY[e.msgid];
    // The same comparison with the roles swapped: qnav's decoded JSON against node's own values.
    fields += compareFields(clazz, q.fields, e.data, `node->qnav #${i}`, mismatches);
  }
  for (const [name, n] of Object.entries(counters.counters)) {
    const want = name === 'garbage_bytes' ? garbage : 0;
    if (n !== want) mismatches.push(`node->qnav: qnav counter ${name} = ${n}, expected ${want}`);
  }
  console.log(`node-mavlink -> qnav: ${COUNT} frames (${v1} MAVLink 1, ${signed} signed, ${garbage} garbage bytes between), ` +
              `${lines.length} decoded, ${fields} fields compared, ${mismatches.length} mismatches`);
  return mismatches;
}

(async () => {
  const t0 = Date.now();
  const bad = [...(await qnavToNode()), ...nodeToQnav()];
  for (const m of bad.slice(0, 20)) console.log(`  ${m}`);
  console.log(`mavlink_peer: ${bad.length === 0 ? 'PASS' : 'FAIL'} (${Date.now() - t0} ms)`);
  process.exit(bad.length === 0 ? 0 : 1);
})().catch((e) => { console.log(`FAIL: ${e.stack || e}`); process.exit(1); });
