// hil_qnavd_mavlink (host, setup): the flood of foreign and malformed MAVLink, made with node-mavlink.
//   node flood_gen.cjs NPM_PREFIX COUNT OUT      -> OUT.bin (datagrams: 2-byte big-endian length +
//                                                   bytes) and OUT.json (what qnavd must count)
// Each datagram is one of (drawn at random, deterministic seed):
//  foreign   a valid frame from systems 200-209 (HEARTBEAT, ATTITUDE, LOCAL_POSITION_NED, ODOMETRY):
//            qnavd counts foreign_system, uses nothing (an ATTITUDE of another vehicle is not ours);
//  unused    a valid LOCAL_POSITION_NED or EKF_STATUS_REPORT from the autopilot's own ids (1, 1):
//            known, not read, counted unused_message;
//  spoof     qnav's mode command (COMMAND_LONG 31010, Teach) from system 200 addressed to qnavd
//            (1, 197): refused, counted cmd_wrong_sender, never acted on, no answer;
//  other     a mode command from (1, 1) addressed to system 2: counted cmd_not_for_us;
//  unknown   a valid frame of a message qnav's codec does not know (SYS_STATUS, GPS_RAW_INT,
//            RC_CHANNELS): parser unknown_message, skipped by its length;
//  badcrc    a valid ATTITUDE / HEARTBEAT / COMMAND_LONG (mode Teach) from (1, 1) with one CRC byte
//            flipped: parser bad_crc, never used;
//  garbage   8-64 random bytes with no magic byte (0xFD, 0xFE): parser garbage_bytes, one per byte.
// No frame that must fail holds a magic byte after its first, so the expected parser_rejects total is
// exact: garbage bytes + unknown frames + for each bad-CRC frame one bad_crc and its other bytes
// rescanned as garbage (its length in all).
'use strict';
const fs = require('fs');
const path = require('path');

const [prefix, countArg, outBase] = process.argv.slice(2);
const mav = require(path.join(prefix, 'node_modules', 'node-mavlink'));
const { MavLinkProtocolV2 } = mav;
const C = mav.common, M = mav.minimal, A = mav.ardupilotmega;
const COUNT = Number(countArg);

let rs = 0x1badf00d;
function rnd() { rs ^= rs << 13; rs >>>= 0; rs ^= rs >>> 17; rs ^= rs << 5; rs >>>= 0; return rs; }
const below = (n) => rnd() % n;
const seqs = {};
function frame(data, sysid, compid) {
  const k = `${sysid}/${compid}`;
  let s = ((seqs[k] || 0) + 1) & 255;
  if (s === 0xfd || s === 0xfe) s = 0;
  seqs[k] = s;
  return new MavLinkProtocolV2(sysid, compid).serialize(data, s);
}
const noMagic = (b, from) => { for (let i = from; i < b.length; ++i) if (b[i] === 0xfd || b[i] === 0xfe) return false; return true; };

function heartbeat() { const h = new M.Heartbeat(); h.type = below(30); h.autopilot = 3; h.baseMode = 0; h.customMode = below(20); h.systemStatus = 4; h.mavlinkVersion = 3; return h; }
function attitude() { const a = new C.Attitude(); a.timeBootMs = rnd(); a.roll = 0.1; a.pitch = -0.2; a.yaw = (below(628) / 100) - 3.14; a.rollspeed = 0; a.pitchspeed = 0; a.yawspeed = 0; return a; }
function lpos() { const p = new C.LocalPositionNed(); p.timeBootMs = rnd(); p.x = below(1000); p.y = below(1000); p.z = below(50); p.vx = 1; p.vy = 0; p.vz = 0; return p; }
function odometry() {
  const o = new C.Odometry(); o.timeUsec = BigInt(rnd()); o.frameId = 20; o.childFrameId = 12; o.x = 1; o.y = 2; o.z = 3; o.q = [1, 0, 0, 0];
  o.vx = 0; o.vy = 0; o.vz = 0; o.rollspeed = 0; o.pitchspeed = 0; o.yawspeed = 0; o.poseCovariance = new Array(21).fill(0);
  o.velocityCovariance = new Array(21).fill(0); o.resetCounter = 0; o.estimatorType = 0; o.quality = 100; return o;
}
function ekf() { const e = new A.EkfStatusReport(); e.flags = 0x1ff; e.velocityVariance = 0.1; e.posHorizVariance = 0.1; e.posVertVariance = 0.1; e.compassVariance = 0.1; e.terrainAltVariance = 0; e.airspeedVariance = 0; return e; }
function modeCmd(ts, tc, mode) {
  const c = new C.CommandLong(); c.targetSystem = ts; c.targetComponent = tc; c.command = 31010; c.confirmation = 0;
  c._param1 = mode; c._param2 = 0; c._param3 = 0; c._param4 = 0; c._param5 = 0; c._param6 = 0; c._param7 = 0; return c;
}
function unknownMsg() {
  const k = below(3);
  if (k === 0) { const s = new C.SysStatus(); for (const f of C.SysStatus.FIELDS) s[f.name] = 0; s.voltageBattery = 12000; return s; }
  if (k === 1) { const g = new C.GpsRawInt(); for (const f of C.GpsRawInt.FIELDS) g[f.name] = f.type.startsWith('uint64') ? 0n : 0; g.fixType = 3; return g; }
  const r = new C.RcChannels(); for (const f of C.RcChannels.FIELDS) r[f.name] = 1500; r.timeBootMs = 0; r.chancount = 8; r.rssi = 200; return r;
}

const counts = { datagrams: 0, foreign: 0, unused: 0, spoof: 0, other: 0, unknown: 0, badcrc: 0, garbage_datagrams: 0, garbage_bytes: 0, badcrc_bytes: 0 };
const parts = [];
while (counts.datagrams < COUNT) {
  const kind = below(7);
  let b;
  if (kind === 0) {
    const k = below(4);
    b = frame([heartbeat, attitude, lpos, odometry][k](), 200 + below(10), 1);
    counts.foreign++;
  } else if (kind === 1) {
    b = frame(below(2) ? lpos() : ekf(), 1, 1);
    counts.unused++;
  } else if (kind === 2) {
    b = frame(modeCmd(1, 197, 1), 200 + below(10), 1);
    counts.spoof++;
  } else if (kind === 3) {
    b = frame(modeCmd(2, 197, 1), 1, 1);
    counts.other++;
  } else if (kind === 4) {
    b = frame(unknownMsg(), 1, 1);
    if (!noMagic(b, 1)) continue;
    counts.unknown++;
  } else if (kind === 5) {
    const k = below(3);
    b = Buffer.from(frame([attitude, heartbeat, () => modeCmd(1, 197, 1)][k](), 1, 1));
    b[b.length - 1 - below(2)] ^= 1 << below(8);
    if (!noMagic(b, 1)) continue;
    counts.badcrc++;
    counts.badcrc_bytes += b.length;
  } else {
    const n = 8 + below(57);
    b = Buffer.alloc(n);
    for (let i = 0; i < n; ++i) { let v; do { v = below(256); } while (v === 0xfd || v === 0xfe); b[i] = v; }
    counts.garbage_datagrams++;
    counts.garbage_bytes += n;
  }
  const len = Buffer.alloc(2);
  len.writeUInt16BE(b.length);
  parts.push(len, b);
  counts.datagrams++;
}
// A failed candidate counts once (bad_crc) and the parser rescans its bytes after the first: each is a
// garbage byte (no magic among them).
counts.parser_rejects = counts.garbage_bytes + counts.badcrc_bytes + counts.unknown;
fs.writeFileSync(`${outBase}.bin`, Buffer.concat(parts));
fs.writeFileSync(`${outBase}.json`, JSON.stringify(counts) + '\n');
console.log(`flood_gen: ${JSON.stringify(counts)}`);
