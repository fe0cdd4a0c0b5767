// hil_qnavd_mavlink (host, from check): node-mavlink decodes what the autopilot received.
//   node decode.cjs NPM_PREFIX     (in the work folder: rx_udp.bin, rx_serial.bin, rx_gcs.bin from autopilot.cjs)
// Writes rx.jsonl, one line per frame, in arrival order per link:
//   {"l": link, "m": CLOCK_MONOTONIC us of the read that completed it, "r": wall-clock us, "id", "s",
//    "c", "q" (seq), ...fields}
// with ODOMETRY (t time_usec, x y z vx vy vz, qu quality, rc reset_counter, f frame_id, cf child),
// VISION_POSITION_DELTA (t, dt time_delta_usec, p position_delta, cf confidence), DISTANCE_SENSOR
// (d cm), HEARTBEAT (cm custom_mode, st system_status), COMMAND_ACK (cmd, res, ts, tc), STATUSTEXT
// (txt), NAMED_VALUE_FLOAT (n, v); non-finite numbers as strings. And rx.json: node-mavlink's count
// of frames with a bad CRC and of unknown messages per link (both must be 0: qnavd sent them).
'use strict';
const fs = require('fs');
const path = require('path');
const { Readable } = require('stream');

const mav = require(path.join(process.argv[2], 'node_modules', 'node-mavlink'));
const { MavLinkPacketSplitter, MavLinkPacketParser } = mav;
const REGISTRY = { ...mav.minimal.REGISTRY, ...mav.common.REGISTRY, ...mav.ardupilotmega.REGISTRY };
const MAGIC = {};
for (const id of Object.keys(REGISTRY)) MAGIC[id] = REGISTRY[id].MAGIC_NUMBER;
const num = (v) => (typeof v === 'number' && !Number.isFinite(v) ? String(v) : v);

async function decode(link) {
  const file = `rx_${link}.bin`;
  const raw = fs.existsSync(file) ? fs.readFileSync(file) : Buffer.alloc(0);
  const chunks = [];  // [end offset in the stream, mono, wall]
  const bufs = [];
  let off = 0, end = 0;
  while (off + 20 <= raw.length) {
    const m = raw.readBigUInt64LE(off), w = raw.readBigUInt64LE(off + 8), n = raw.readUInt32LE(off + 16);
    bufs.push(raw.subarray(off + 20, off + 20 + n));
    end += n;
    chunks.push([end, m, w]);
    off += 20 + n;
  }
  const stream = Buffer.concat(bufs);
  const splitter = new MavLinkPacketSplitter({}, { magicNumbers: MAGIC });
  const packets = [];
  await new Promise((resolve, reject) => {
    Readable.from([stream]).pipe(splitter).pipe(new MavLinkPacketParser()).on('data', (p) => packets.push(p)).on('end', resolve).on('error', reject);
  });
  const out = [];
  let pos = 0, ci = 0;
  for (const p of packets) {
    const at = stream.indexOf(p.buffer, pos);
    if (at < 0) throw new Error(`${link}: a frame not found in the stream`);
    pos = at + p.buffer.length;
    while (ci < chunks.length - 1 && chunks[ci][0] < pos) ++ci;
    const h = p.header;
    const rec = { l: link, m: chunks[ci][1], r: chunks[ci][2], id: h.msgid, s: h.sysid, c: h.compid, q: h.seq };
    const clazz = REGISTRY[h.msgid];
    const d = clazz ? p.protocol.data(p.payload, clazz) : null;
    switch (h.msgid) {
      case 0: rec.cm = d.customMode; rec.st = d.systemStatus; break;
      case 331:
        Object.assign(rec, { t: d.timeUsec, x: num(d.x), y: num(d.y), z: num(d.z), vx: num(d.vx), vy: num(d.vy), vz: num(d.vz),
                             qu: d.quality, rc: d.resetCounter, f: d.frameId, cf: d.childFrameId });
        break;
      case 11011: Object.assign(rec, { t: d.timeUsec, dt: d.timeDeltaUsec, p: d.positionDelta.map(num), cf: num(d.confidence) }); break;
      case 132: rec.d = d.currentDistance; break;
      case 77: Object.assign(rec, { cmd: d.command, res: d.result, ts: d.targetSystem, tc: d.targetComponent }); break;
      case 253: rec.txt = d.text; break;
      case 251: rec.n = d.name; rec.v = num(d.value); break;
      default: break;
    }
    out.push(JSON.stringify(rec, (k, v) => (typeof v === 'bigint' ? v.toString() : v)));
  }
  return { lines: out, stats: { frames: packets.length, bytes: stream.length, crc_errors: splitter.invalidPackages, unknown: splitter.unknownPackagesCount } };
}

(async () => {
  const all = [], stats = {};
  for (const link of ['udp', 'serial', 'gcs']) {
    const r = await decode(link);
    all.push(...r.lines);
    stats[link] = r.stats;
  }
  fs.writeFileSync('rx.jsonl', all.join('\n') + '\n');
  fs.writeFileSync('rx.json', JSON.stringify(stats) + '\n');
  console.log(`decode: node-mavlink ${JSON.stringify(stats)}`);
})().catch((e) => { console.log(`decode: FAIL: ${e.stack || e}`); process.exit(1); });
