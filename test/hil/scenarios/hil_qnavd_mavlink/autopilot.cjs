// hil_qnavd_mavlink (guest): the autopilot's side, with node-mavlink (an independent MAVLink
// implementation) making every frame it sends; what it receives is recorded raw here and decoded by
// node-mavlink on the host (decode.cjs, from check): decoding ~60 frames/s in the emulated CPU would
// delay the very receive times being measured.
//   pty_exec.py /tmp/mav0 node autopilot.cjs NPM_PREFIX   (pty_exec.py appends the pty master's and slave's fds)
// Links: UDP 127.0.0.1:14550 (qnavd's mavlink.udp_remote: qnavd is the client, this replies to the
// address its datagrams come from) and the serial line (qnavd's mavlink.serial_device: the slave of
// a pseudo-terminal whose master this reads and writes).
// And a ground station on the vehicle's network (component 190 of system 1, so that qnavd ignores its
// HEARTBEAT without a count and the flood's counts stay exact): a UDP socket of its own
// that sends a HEARTBEAT 1 Hz to qnavd's server port (mavlink.udp_listen_port 14555), the port the
// flood hits too, and records what qnavd sends back (rx_gcs.bin).
// Writes at the end (SIGTERM), each read as it came, stamped on arrival with CLOCK_MONOTONIC
// (process.hrtime: the clock of qnavd's sample times on the linux backend) and the wall clock:
//   rx_udp.bin, rx_serial.bin, rx_gcs.bin   records: mono_us (u64 LE), wall_us (u64 LE), length (u32 LE), bytes
//   sent.jsonl                  every frame it sent: {"l": link, "m": mono_us, "what", "cmd", "p1", "from"}
// Sends: HEARTBEAT 1 Hz on both links (ArduSub: type SUBMARINE, autopilot ARDUPILOTMEGA, system 1
// component 1, armed, MANUAL). qnavd's own HEARTBEAT (a UDP datagram is one frame: msgid and
// custom_mode read from the bytes) drives the commands (COMMAND_LONG 31010 = qnav's mode, param1
// mode; to system 1 component 197):
//   first qnavd HEARTBEAT +0.5 s  mode Idle from system 77 (an intruder: refused, counted, no answer)
//                        +1.0 s  mode 9 (out of range: DENIED)
//                        +1.5 s  MAV_CMD_COMPONENT_ARM_DISARM 400 (not qnav's: UNSUPPORTED)
//                        +2.0 s  mode Idle (ACCEPTED)
//   first HEARTBEAT with system_status ACTIVE (the DVL and the AHRS are live: the first dive flies):
//     writes flood.go (the guest starts the flood 2 s later) and 6 s later sends mode Idle on UDP
//     (ACCEPTED inside the flood: the autopilot is still heard);
//   qnavd's mode Repeat (2) and then Idle (0) again (the player's repeat pass over): +0.5 s mode Hold
//     (4), +2.0 s mode Idle (0), on the serial link, both ACCEPTED.
'use strict';
const fs = require('fs');
const path = require('path');
const dgram = require('dgram');

const prefix = process.argv[2];
const masterFd = Number(process.argv[3]), slaveFd = Number(process.argv[4]);
const mav = require(path.join(prefix, 'node_modules', 'node-mavlink'));
const { MavLinkProtocolV2 } = mav;

const hr0 = process.hrtime.bigint();
const wall0 = BigInt(Date.now()) * 1000n;
const monoUs = () => process.hrtime.bigint() / 1000n;
const rx = { udp: [], serial: [], gcs: [] };
const sent = [];
function record(link, b) {
  const m = monoUs();
  rx[link].push([m, wall0 + (m - hr0 / 1000n), b]);
}

const udp = dgram.createSocket('udp4');
const gcs = dgram.createSocket('udp4');
let qnavdUdp = null;  // qnavd's client endpoint, learnt from its first datagram
const links = {
  udp: (b) => { if (qnavdUdp) udp.send(b, qnavdUdp.port, qnavdUdp.address); },
  serial: (b) => fs.write(masterFd, b, () => {}),
  gcs: (b) => gcs.send(b, 14555, '127.0.0.1'),
};
const seq = { 1: 0, 77: 0 };
const gcsSeq = { n: 0 };
function sendMsg(link, data, sysid, what, extra = {}) {
  const q = link === 'gcs' ? (gcsSeq.n = (gcsSeq.n + 1) & 255) : (seq[sysid] = (seq[sysid] + 1) & 255);
  links[link](new MavLinkProtocolV2(sysid, link === 'gcs' ? 190 : 1).serialize(data, q));
  if (what) sent.push({ l: link, m: monoUs().toString(), what, ...extra });
}
function command(link, cmd, p1, sysid, what) {
  const c = new mav.common.CommandLong();
  c.targetSystem = 1; c.targetComponent = 197; c.command = cmd; c.confirmation = 0;
  c._param1 = p1; c._param2 = 0; c._param3 = 0; c._param4 = 0; c._param5 = 0; c._param6 = 0; c._param7 = 0;
  sendMsg(link, c, sysid, what, { cmd, p1, from: sysid });
}

let first = false, active = false, sawRepeat = false, ended = false;
function onQnavdHeartbeat(customMode, systemStatus) {
  if (!first) {
    first = true;
    setTimeout(() => command('udp', 31010, 0, 77, 'intruder'), 500);
    setTimeout(() => command('udp', 31010, 9, 1, 'bad_mode'), 1000);
    setTimeout(() => command('udp', 400, 1, 1, 'unsupported'), 1500);
    setTimeout(() => command('udp', 31010, 0, 1, 'idle'), 2000);
  }
  if (!active && systemStatus === 4) {
    active = true;
    fs.writeFileSync('flood.go', `${monoUs()}\n`);
    setTimeout(() => command('udp', 31010, 0, 1, 'idle_flood'), 6000);
  }
  if (customMode === 2) sawRepeat = true;
  if (sawRepeat && customMode === 0 && !ended) {
    ended = true;
    setTimeout(() => command('serial', 31010, 4, 1, 'hold'), 500);
    setTimeout(() => command('serial', 31010, 0, 1, 'idle_end'), 2000);
  }
}

udp.on('message', (b, rinfo) => {
  record('udp', b);
  if (!qnavdUdp) qnavdUdp = rinfo;
  // HEARTBEAT (msgid 0) from qnavd (1, 197): custom_mode u32 at payload 0, system_status at payload 7.
  if (b.length >= 18 && b[0] === 0xfd && b[7] === 0 && b[8] === 0 && b[9] === 0 && b[5] === 1 && b[6] === 197)
    onQnavdHeartbeat(b.readUInt32LE(10), b[17]);
});
// The pty master: blocking reads in libuv's thread pool, each chunk as it comes.
fs.createReadStream(null, { fd: masterFd, autoClose: false, highWaterMark: 4096 }).on('data', (b) => record('serial', b));
gcs.on('message', (b) => record('gcs', b));
gcs.bind(0, '127.0.0.1');
udp.bind(14550, '127.0.0.1', () => fs.writeFileSync('/tmp/autopilot.ready', `${monoUs()}\n`));

// HEARTBEAT 1 Hz on both links: ArduSub, armed, MANUAL (custom_mode 19).
setInterval(() => {
  const h = new mav.minimal.Heartbeat();
  h.type = 12; h.autopilot = 3; h.baseMode = 128 | 1; h.customMode = 19; h.systemStatus = 4; h.mavlinkVersion = 3;
  sendMsg('udp', h, 1);
  sendMsg('serial', h, 1);
  const g = new mav.minimal.Heartbeat();
  g.type = 6; g.autopilot = 8; g.baseMode = 0; g.customMode = 0; g.systemStatus = 4; g.mavlinkVersion = 3;
  sendMsg('gcs', g, 1);
}, 1000);

process.on('SIGTERM', () => {
  for (const link of Object.keys(rx)) {
    const parts = [];
    for (const [m, w, b] of rx[link]) {
      const h = Buffer.alloc(20);
      h.writeBigUInt64LE(m, 0);
      h.writeBigUInt64LE(w, 8);
      h.writeUInt32LE(b.length, 16);
      parts.push(h, b);
    }
    fs.writeFileSync(`rx_${link}.bin`, Buffer.concat(parts));
  }
  fs.writeFileSync('sent.jsonl', sent.map((s) => JSON.stringify(s)).join('\n') + '\n');
  // The read blocked on the master (a thread-pool thread) ends once no slave is open (qnavd has
  // exited): without that, node's exit waits for it for ever.
  fs.closeSync(slaveFd);
  process.exit(0);
});
