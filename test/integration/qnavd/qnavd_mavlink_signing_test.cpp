// MAVLink signing and the EKF origin in qnavd (docs/interfaces.md "MAVLink": key file, signing, origin):
//  - mavlink.key_file: the checks at start (regular file, owner, mode 0600, 64 hex digits, not zero),
//    each a named error, and Daemon::init failing on them; the owner rule with the test's own uid
//    (production requires root: uid 0);
//  - with a key, the endpoint refuses and counts every mode command that is unsigned, signed with
//    another key, replayed, or more than a minute behind its clock, acts on the signed one, and signs
//    everything it sends with strictly increasing timestamps from its clock;
//  - SET_GPS_GLOBAL_ORIGIN to the autopilot once a second until GPS_GLOBAL_ORIGIN answers, again after
//    the autopilot rebooted; the origin keys both or neither;
//  - a short signed mission over UDP (QNAVD_MAVLINK_CAPTURE=PATH writes PATH.bin and PATH.key for
//    test/peer/mavlink's node-mavlink check of qnavd's signatures: ctest -L mavlink_peer).
#include <gtest/gtest.h>

#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "drivers/mavlink/messages.hpp"
#include "drivers/mavlink/parser.hpp"
#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/daemon.hpp"
#include "firmware/qnavd/mavlink_endpoint.hpp"
#include "firmware/qnavd/mavlink_key.hpp"
#include "firmware/qnavd/software_fault.hpp"
#include "hal/linux/secret_file.hpp"
#include "hal/linux/udp_port.hpp"
#include "hal/sim/manual_clock.hpp"

namespace qnav::daemon {
namespace {

namespace mav = drivers::mavlink;
namespace qc = drivers::qnavcan;

constexpr const char* kKeyHex = "00112233445566778899aabbccddeeff0123456789ABCDEFfedcba9876543210";
constexpr std::int64_t kEpoch2015Ns = 1420070400LL * 1000000000LL;
constexpr std::int64_t kNow = kEpoch2015Ns + 377LL * 24 * 3600 * 1000000000LL * 10;  // some day in 2025

std::string temp_dir() {
  char t[] = "/tmp/qnavd_mavsec_XXXXXX";
  const char* d = mkdtemp(t);
  return d ? std::string(d) : std::string("/tmp");
}

std::string write_file(const std::string& dir, const char* name, const std::string& text, mode_t mode) {
  const std::string p = dir + "/" + name;
  FILE* f = std::fopen(p.c_str(), "wb");
  EXPECT_NE(f, nullptr);
  if (f == nullptr) return p;
  std::fwrite(text.data(), 1, text.size(), f);
  std::fclose(f);
  EXPECT_EQ(chmod(p.c_str(), mode), 0);
  return p;
}

mav::SigningKey key_from_hex(const char* hex) {
  Result<mav::SigningKey> k = parse_mavlink_key(reinterpret_cast<const std::uint8_t*>(hex), std::strlen(hex));
  EXPECT_TRUE(k);
  return k ? k.value() : mav::SigningKey{};
}

// ---- the key file --------------------------------------------------------------------------------

TEST(MavlinkKeyFile, AcceptsARootOnlyFileOf64HexDigitsAndRefusesEverythingElseByName) {
  const std::string d = temp_dir();
  const std::uint32_t me = hal::current_uid();
  // Good: 0600 (and 0400), the digits alone, or with one line end.
  for (const char* end : {"", "\n", "\r\n"}) {
    const std::string p = write_file(d, "good.key", std::string(kKeyHex) + end, 0600);
    Result<mav::SigningKey> k = load_mavlink_key(p.c_str(), me);
    ASSERT_TRUE(k) << k.status().message();
    EXPECT_EQ(k.value().secret[0], 0x00);
    EXPECT_EQ(k.value().secret[1], 0x11);
    EXPECT_EQ(k.value().secret[15], 0xFF);
    EXPECT_EQ(k.value().secret[23], 0xEF);  // upper case digits read the same
    EXPECT_EQ(k.value().secret[31], 0x10);
  }
  EXPECT_TRUE(load_mavlink_key(write_file(d, "ro.key", kKeyHex, 0400).c_str(), me));
  const auto refused = [&](const std::string& path, std::uint32_t uid, const char* why) {
    Result<mav::SigningKey> k = load_mavlink_key(path.c_str(), uid);
    ASSERT_FALSE(k) << path;
    EXPECT_NE(std::strstr(k.status().message(), why), nullptr) << k.status().message();
  };
  // The owner rule (production: uid 0; here a uid that is not ours).
  refused(write_file(d, "owner.key", kKeyHex, 0600), me + 1, "mavlink.key_file: not owned by root");
  // Any group or other bit, or setuid/setgid/sticky.
  for (mode_t m : {0640, 0604, 0660, 0644, 0601, 0610, 04600, 01600}) {
    char name[32];
    std::snprintf(name, sizeof name, "mode%o.key", static_cast<unsigned>(m));
    refused(write_file(d, name, kKeyHex, m), me, "group or others have access");
  }
  // Contents: 63 or 65 digits, a non-hex character, two line ends, all zeros, empty.
  refused(write_file(d, "short.key", std::string(kKeyHex).substr(0, 63), 0600), me, "not a 32-byte key");
  refused(write_file(d, "long.key", std::string(kKeyHex) + "0", 0600), me, "not a 32-byte key");
  refused(write_file(d, "longer.key", std::string(kKeyHex) + kKeyHex, 0600), me, "not a 32-byte key");
  refused(write_file(d, "twolines.key", std::string(kKeyHex) + "\n\n", 0600), me, "not a 32-byte key");
  std::string bad = kKeyHex;
  bad[10] = 'g';
  refused(write_file(d, "nonhex.key", bad, 0600), me, "not a hex digit");
  refused(write_file(d, "zero.key", std::string(64, '0'), 0600), me, "all-zero key");
  refused(write_file(d, "empty.key", "", 0600), me, "not a 32-byte key");
  // Not a regular file; a symbolic link (even to a good key); no file.
  const std::string sub = d + "/dir.key";
  ASSERT_EQ(mkdir(sub.c_str(), 0700), 0);
  refused(sub, me, "not a regular file");
  const std::string link = d + "/link.key";
  ASSERT_EQ(symlink((d + "/good.key").c_str(), link.c_str()), 0);
  refused(link, me, "symbolic link");
  Result<mav::SigningKey> none = load_mavlink_key((d + "/absent.key").c_str(), me);
  ASSERT_FALSE(none);
  EXPECT_EQ(none.status().code(), StatusCode::kNotFound);
}

DaemonConfig sim_config(const std::string& dir) {
  SoftwareFaults::reset_for_tests();
  DaemonConfig c;
  c.backend = Backend::kSim;
  c.route_dir = dir;
  c.log = LogFormat::kOff;
  c.realtime = false;
  c.sim_length_m = 200.0;
  c.sim_seed = 1;
  c.sim_speed = SimSpeed::kFast;
  c.tile_budget_us = 10000000;
  c.ping_budget_us = 1000000;
  c.mavlink_enabled = true;
  c.mavlink_udp_listen_port = 0;
  SimPass teach;
  teach.mode = qc::Mode::kTeach;
  EXPECT_TRUE(c.sim_mission.push_back(teach));
  return c;
}

TEST(MavlinkKeyFile, DaemonInitFailsOnABadKeyFileAndStartsWithAGoodOne) {
  const std::string d = temp_dir();
  DaemonConfig c = sim_config(d);
  c.mavlink_udp_remote = "127.0.0.1:9";  // discard: nothing listens, nothing needs to
  c.mavlink_key_owner_uid = hal::current_uid();
  c.mavlink_key_file = write_file(d, "open.key", kKeyHex, 0644);
  {
    Daemon bad(c);
    const Status s = bad.init(nullptr);
    ASSERT_FALSE(s);
    EXPECT_NE(std::strstr(s.message(), "mavlink.key_file: group or others have access"), nullptr) << s.message();
  }
  c.mavlink_key_owner_uid = hal::current_uid() + 1;  // as if qnavd required root and the file were ours
  c.mavlink_key_file = write_file(d, "mine.key", kKeyHex, 0600);
  {
    Daemon bad(c);
    const Status s = bad.init(nullptr);
    ASSERT_FALSE(s);
    EXPECT_NE(std::strstr(s.message(), "not owned by root"), nullptr) << s.message();
  }
  c.mavlink_key_owner_uid = hal::current_uid();
  Daemon good(c);
  ASSERT_TRUE(good.init(nullptr));
  EXPECT_TRUE(good.config().mavlink_key_loaded);
  ASSERT_NE(good.nav().mavlink(), nullptr);
  EXPECT_TRUE(good.nav().mavlink()->signing());
}

TEST(MavlinkConfig, OriginNeedsLatitudeAndLongitudeOrNone) {
  const std::string base = "[daemon]\nbackend = \"linux\"\n[vo]\nenabled = false\n[mavlink]\nenabled = true\nudp_remote = \"127.0.0.1:14550\"\n";
  DaemonConfig c;
  ConfigError e;
  ASSERT_TRUE(parse_config(base, "t", c, e)) << e.message;
  EXPECT_FALSE(c.mavlink_origin);
  c = DaemonConfig{};
  ASSERT_TRUE(parse_config(base + "origin_lat_deg = 47.5\norigin_lon_deg = -122.25\norigin_alt_m = -3.5\n", "t", c, e)) << e.message;
  EXPECT_TRUE(c.mavlink_origin);
  EXPECT_DOUBLE_EQ(c.mavlink_origin_lat_deg, 47.5);
  EXPECT_DOUBLE_EQ(c.mavlink_origin_lon_deg, -122.25);
  EXPECT_DOUBLE_EQ(c.mavlink_origin_alt_m, -3.5);
  for (const char* bad : {"origin_lat_deg = 47.5\n", "origin_lon_deg = 8.0\n", "origin_alt_m = 10.0\n", "origin_lat_deg = 91.0\norigin_lon_deg = 0.0\n",
                          "origin_lat_deg = 0.0\norigin_lon_deg = 180.5\n"}) {
    c = DaemonConfig{};
    EXPECT_FALSE(parse_config(base + bad, "t", c, e)) << bad;
    EXPECT_NE(e.to_string().find("mavlink.origin"), std::string::npos) << e.to_string();
  }
  c = DaemonConfig{};
  EXPECT_FALSE(parse_config(base + "key_file = \"relative.key\"\n", "t", c, e));
  EXPECT_NE(e.to_string().find("mavlink.key_file"), std::string::npos) << e.to_string();
}

// ---- the endpoint with a key ---------------------------------------------------------------------

struct SignedRig {
  DaemonConfig c;
  hal::ManualClock utc{kNow};
  std::vector<MavBytes> rx_items = std::vector<MavBytes>(16), tx_items = std::vector<MavBytes>(64);
  SpscRing<MavBytes> rx, tx;
  std::unique_ptr<MavlinkEndpoint> ep;
  mav::SigningKey key = key_from_hex(kKeyHex);
  mav::FrameEncoder ap{1, 1};
  std::uint64_t ap_ts = static_cast<std::uint64_t>((kNow - kEpoch2015Ns) / 10000);
  explicit SignedRig(bool loaded = true) {
    c.mavlink_enabled = true;
    c.mavlink_key_file = "/etc/qnav/mavlink.key";
    c.mavlink_key_loaded = loaded;
    std::memcpy(c.mavlink_key_secret, key.secret, 32);
    EXPECT_TRUE(rx.init(Span<MavBytes>(rx_items.data(), rx_items.size())));
    EXPECT_TRUE(tx.init(Span<MavBytes>(tx_items.data(), tx_items.size())));
    ep = std::make_unique<MavlinkEndpoint>(c, nullptr, &utc);
  }
  // One frame from the autopilot (1, 1): unsigned, or signed with `k` at timestamp ts and link id.
  MavBytes frame(const mav::CommandLong& m, const mav::SigningKey* k, std::uint64_t ts, std::uint8_t link = 0) {
    MavBytes b;
    Result<std::size_t> n = mav::encode(ap, m, Span<std::uint8_t>(b.data, kMavBytes));
    EXPECT_TRUE(n);
    std::size_t len = n.value();
    if (k != nullptr) {
      mav::SigningKey kk = *k;
      kk.link_id = link;
      Result<std::size_t> s = mav::sign_frame(b.data, len, kMavBytes, kk, ts);
      EXPECT_TRUE(s);
      len = s.value();
    }
    b.len = static_cast<std::uint16_t>(len);
    return b;
  }
  bool push(const MavBytes& b) { return rx.try_push(b).is_ok(); }
  // What the endpoint sent after a publish at t_ns, read by a parser with the key.
  struct Sent {
    std::vector<mav::Frame> frames;
    std::uint32_t unsigned_frames = 0;
  };
  Sent published(std::int64_t t_ns) {
    MavSnapshot s;
    s.now_ns = t_ns;
    ep->publish(s, tx);
    return drain_tx();
  }
  Sent drain_tx() {
    Sent out;
    mav::Parser p;
    p.set_signing_key(key);
    MavBytes b;
    while (tx.try_pop(b))
      p.feed(Span<const std::uint8_t>(b.data, b.len), [&](const mav::Frame& f) {
        out.frames.push_back(f);
        out.unsigned_frames += !f.signature_verified;
      });
    EXPECT_EQ(p.counters().total(), 0u) << "every frame qnavd sends verifies with the key";
    return out;
  }
};

mav::CommandLong mode_cmd(qc::Mode m) {
  mav::CommandLong c;
  c.target_system = 1;
  c.target_component = 197;
  c.command = kMavCmdSetMode;
  c.param1 = static_cast<float>(static_cast<int>(m));
  return c;
}

TEST(MavlinkSigning, OnlyCommandsSignedWithTheKeyAreActedOnEveryOtherIsRefusedAndCounted) {
  SignedRig r;
  ASSERT_TRUE(r.ep->signing());
  const mav::SigningKey other = key_from_hex("ffeeddccbbaa99887766554433221100ffeeddccbbaa99887766554433221100");
  // Unsigned: refused before the sender is looked at, no answer.
  ASSERT_TRUE(r.push(r.frame(mode_cmd(qc::Mode::kIdle), nullptr, 0)));
  EXPECT_FALSE(r.ep->drain(r.rx).mode_cmd);
  // Signed with another key: the parser drops it (bad_signature).
  ASSERT_TRUE(r.push(r.frame(mode_cmd(qc::Mode::kIdle), &other, ++r.ap_ts)));
  EXPECT_FALSE(r.ep->drain(r.rx).mode_cmd);
  EXPECT_TRUE(r.published(0).frames.size() > 0);
  // Signed with the key: handed to the worker, answered with a signed ACK.
  const MavBytes good = r.frame(mode_cmd(qc::Mode::kRepeat), &r.key, ++r.ap_ts);
  ASSERT_TRUE(r.push(good));
  MavInputs in = r.ep->drain(r.rx);
  ASSERT_TRUE(in.mode_cmd);
  EXPECT_EQ(in.cmd.mode, qc::Mode::kRepeat);
  r.ep->ack(true, nullptr, r.tx);
  SignedRig::Sent sent = r.drain_tx();
  ASSERT_EQ(sent.frames.size(), 1u);
  EXPECT_EQ(sent.frames[0].msgid, mav::CommandAck::kId);
  EXPECT_TRUE(sent.frames[0].signature_verified);
  // The same bytes again: a replay (timestamp not newer on its stream).
  ASSERT_TRUE(r.push(good));
  EXPECT_FALSE(r.ep->drain(r.rx).mode_cmd);
  // Signed, on a new stream (link id 5), 61 s behind qnavd's clock: stale. 59 s behind: accepted.
  const std::uint64_t clock_ts = static_cast<std::uint64_t>((kNow - kEpoch2015Ns) / 10000);
  ASSERT_TRUE(r.push(r.frame(mode_cmd(qc::Mode::kIdle), &r.key, clock_ts - 6100000, 5)));
  EXPECT_FALSE(r.ep->drain(r.rx).mode_cmd);
  ASSERT_TRUE(r.push(r.frame(mode_cmd(qc::Mode::kIdle), &r.key, clock_ts - 5900000, 6)));
  EXPECT_TRUE(r.ep->drain(r.rx).mode_cmd);
  r.ep->ack(true, nullptr, r.tx);
  (void)r.drain_tx();
  // Signed with the key but from another system: signed is not enough (wrong sender, no answer).
  {
    mav::FrameEncoder intruder(7, 1);
    MavBytes b;
    Result<std::size_t> n = mav::encode(intruder, mode_cmd(qc::Mode::kIdle), Span<std::uint8_t>(b.data, kMavBytes));
    ASSERT_TRUE(n);
    Result<std::size_t> s = mav::sign_frame(b.data, n.value(), kMavBytes, r.key, ++r.ap_ts);
    ASSERT_TRUE(s);
    b.len = static_cast<std::uint16_t>(s.value());
    ASSERT_TRUE(r.push(b));
    EXPECT_FALSE(r.ep->drain(r.rx).mode_cmd);
  }
  EXPECT_TRUE(r.drain_tx().frames.empty()) << "no answer to any refused command";
  const auto& k = r.ep->counters();
  EXPECT_EQ(k.get(MavCounter::kCmdUnsigned), 1u);
  EXPECT_EQ(k.get(MavCounter::kCmdWrongSender), 1u);
  EXPECT_EQ(r.ep->signing_rejects(), 3u) << "bad signature, replay, stale";
  EXPECT_EQ(r.ep->commands_accepted(), 2u);
  EXPECT_EQ(r.ep->rejected(), 5u) << "unsigned, bad signature, replay, stale, wrong sender";
  std::printf("signing: cmd_unsigned %u, signing rejects %u (bad signature, replay, stale), accepted %u\n", k.get(MavCounter::kCmdUnsigned),
              r.ep->signing_rejects(), r.ep->commands_accepted());
}

TEST(MavlinkSigning, EverythingSentIsSignedWithIncreasingTimestampsFromTheClock) {
  SignedRig r;
  std::uint64_t last = 0;
  const std::uint64_t clock_ts = static_cast<std::uint64_t>((kNow - kEpoch2015Ns) / 10000);
  std::size_t n = 0;
  for (int i = 0; i < 30; ++i) {
    const std::int64_t t = static_cast<std::int64_t>(i) * 100000000;  // 10 Hz of publishes, the clock still (a burst)
    SignedRig::Sent s = r.published(t);
    EXPECT_EQ(s.unsigned_frames, 0u);
    for (const mav::Frame& f : s.frames) {
      EXPECT_TRUE(f.is_signed);
      EXPECT_EQ(f.link_id, kSignLinkId);
      EXPECT_GT(f.sign_timestamp, last) << "strictly increasing";
      EXPECT_GE(f.sign_timestamp, clock_ts);
      EXPECT_LT(f.sign_timestamp, clock_ts + 1000) << "the clock's, +1 per frame in a burst";
      last = f.sign_timestamp;
      ++n;
    }
  }
  EXPECT_GT(n, 0u);
  // The clock steps back an hour: the timestamps never do.
  r.utc.set_ns(kNow - 3600LL * 1000000000LL);
  for (const mav::Frame& f : r.published(4000000000).frames) EXPECT_GT(f.sign_timestamp, last);
  // It moves on: so do they.
  r.utc.set_ns(kNow + 10LL * 1000000000LL);
  for (const mav::Frame& f : r.published(5000000000).frames) EXPECT_GE(f.sign_timestamp, clock_ts + 1000000);
}

TEST(MavlinkSigning, AKeyFileWhoseKeyWasNotLoadedRefusesEveryCommand) {
  SignedRig r(false);
  EXPECT_TRUE(r.ep->signing_required());
  EXPECT_FALSE(r.ep->signing());
  ASSERT_TRUE(r.push(r.frame(mode_cmd(qc::Mode::kIdle), nullptr, 0)));
  EXPECT_FALSE(r.ep->drain(r.rx).mode_cmd);
  EXPECT_EQ(r.ep->counters().get(MavCounter::kCmdUnsigned), 1u);
}

// ---- the EKF origin ------------------------------------------------------------------------------

TEST(MavlinkOrigin, SentOnceASecondUntilTheAutopilotAnswersAndAgainAfterItRebooted) {
  std::vector<MavBytes> rx_items(16), tx_items(64);
  SpscRing<MavBytes> rx, tx;
  ASSERT_TRUE(rx.init(Span<MavBytes>(rx_items.data(), rx_items.size())));
  ASSERT_TRUE(tx.init(Span<MavBytes>(tx_items.data(), tx_items.size())));
  DaemonConfig c;
  c.mavlink_enabled = true;
  c.mavlink_origin = true;
  c.mavlink_origin_lat_deg = -33.8567844;
  c.mavlink_origin_lon_deg = 151.2152967;
  c.mavlink_origin_alt_m = 2.5;
  c.mavlink_autopilot_system_id = 3;
  MavlinkEndpoint ep(c, nullptr);
  mav::FrameEncoder ap(3, 1);
  c.mavlink_autopilot_component_id = 1;
  std::vector<mav::SetGpsGlobalOrigin> got;
  const auto publish = [&](std::int64_t t) {
    MavSnapshot s;
    s.now_ns = t;
    ep.publish(s, tx);
    mav::Parser p;
    MavBytes b;
    while (tx.try_pop(b))
      p.feed(Span<const std::uint8_t>(b.data, b.len), [&](const mav::Frame& f) {
        mav::SetGpsGlobalOrigin o;
        if (mav::decode(f, o)) got.push_back(o);
      });
  };
  const auto from_ap = [&](const auto& m, std::int64_t t) {
    MavBytes b;
    Result<std::size_t> n = mav::encode(ap, m, Span<std::uint8_t>(b.data, kMavBytes));
    ASSERT_TRUE(n);
    b.len = static_cast<std::uint16_t>(n.value());
    b.arrival_ns = t;
    ASSERT_TRUE(rx.try_push(b));
    (void)ep.drain(rx);
  };
  const std::int64_t s = 1000000000;
  for (std::int64_t t = 0; t <= 3 * s; t += s / 10) publish(t);
  ASSERT_EQ(got.size(), 4u) << "at 0, 1, 2 and 3 s";
  EXPECT_EQ(got[0].target_system, 3);
  EXPECT_EQ(got[0].latitude, -338567844);
  EXPECT_EQ(got[0].longitude, 1512152967);
  EXPECT_EQ(got[0].altitude, 2500);
  mav::Heartbeat hb;
  from_ap(hb, 3 * s);
  mav::GpsGlobalOrigin answer;
  answer.latitude = got[0].latitude;
  answer.longitude = got[0].longitude;
  answer.altitude = 2500;
  from_ap(answer, 3 * s + s / 2);
  EXPECT_TRUE(ep.origin_acknowledged());
  got.clear();
  for (std::int64_t t = 4 * s; t <= 8 * s; t += s / 10) {
    publish(t);
    if (t % s == 0) from_ap(hb, t);  // the autopilot's heartbeat, every second
  }
  EXPECT_TRUE(got.empty()) << "answered: not sent again";
  // The autopilot falls silent for 6 s (a reboot) and comes back: its EKF needs the origin again.
  from_ap(hb, 14 * s);
  EXPECT_FALSE(ep.origin_acknowledged());
  publish(14 * s + 1);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(ep.origins_sent(), 5u);
}

// ---- a signed mission over UDP -------------------------------------------------------------------

TEST(MavlinkSigning, ASignedMissionOverUdpSignsEveryFrameAndActsOnlyOnSignedCommands) {
  const std::string d = temp_dir();
  hal::UdpPort port;
  ASSERT_TRUE(port.open_server(0, "127.0.0.1"));
  // A receive buffer that holds the whole mission (~10,000 datagrams a second of fast mission time),
  // so a reader descheduled on a loaded machine loses nothing (as test_qnavd_mavlink's autopilot).
  const int rcvbuf = 64 << 20;
  if (setsockopt(port.fd(), SOL_SOCKET, SO_RCVBUFFORCE, &rcvbuf, sizeof rcvbuf) != 0)
    (void)setsockopt(port.fd(), SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
  DaemonConfig c = sim_config(d);
  c.mavlink_udp_remote = "127.0.0.1:" + std::to_string(port.local_port());
  c.mavlink_key_owner_uid = hal::current_uid();
  c.mavlink_key_file = write_file(d, "mavlink.key", std::string(kKeyHex) + "\n", 0600);
  c.mavlink_origin = true;
  c.mavlink_origin_lat_deg = 59.9;
  c.mavlink_origin_lon_deg = 10.7;
  Daemon dm(c);
  ASSERT_TRUE(dm.init(nullptr));
  const mav::SigningKey key = key_from_hex(kKeyHex);
  std::mutex mu;
  std::vector<std::uint8_t> raw;
  raw.reserve(8u << 20);
  mav::Parser reader;
  reader.set_signing_key(key);
  std::uint32_t frames = 0, verified = 0, acks = 0, origins = 0;
  std::uint64_t first_ts = 0, last_ts = 0;
  std::vector<std::uint64_t> odo_usec;
  odo_usec.reserve(100000);
  bool increasing = true;
  std::atomic<bool> stop{false};
  std::thread rd([&] {
    std::uint8_t buf[2048];
    while (!stop.load()) {
      Result<hal::SerialRead> r = port.read(Span<std::uint8_t>(buf, sizeof buf), 20);
      if (!r || r.value().bytes == 0) continue;
      std::lock_guard<std::mutex> lock(mu);
      raw.insert(raw.end(), buf, buf + r.value().bytes);
      reader.feed(Span<const std::uint8_t>(buf, r.value().bytes), [&](const mav::Frame& f) {
        ++frames;
        verified += f.signature_verified;
        if (first_ts == 0) first_ts = f.sign_timestamp;
        increasing = increasing && f.sign_timestamp > last_ts;
        last_ts = f.sign_timestamp;
        mav::Odometry o;
        if (mav::decode(f, o)) odo_usec.push_back(o.time_usec);
        acks += f.msgid == mav::CommandAck::kId;
        origins += f.msgid == mav::SetGpsGlobalOrigin::kId;
      });
    }
  });
  ASSERT_TRUE(dm.start());
  std::thread talker([&] {
    mav::FrameEncoder ap(1, 1);
    std::uint64_t ts = 0;
    bool sent = false;
    for (int i = 0; i < 3000 && !dm.mission_done() && !sent; ++i) {
      if (port.has_peer()) {
        const auto send = [&](bool sign) {
          std::uint8_t b[mav::kMaxFrameBytes];
          Result<std::size_t> n = mav::encode(ap, mode_cmd(qc::Mode::kTeach), Span<std::uint8_t>(b, sizeof b));
          std::size_t len = n.value();
          if (sign) {
            const std::int64_t now = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
            ts = std::max(ts + 1, static_cast<std::uint64_t>((now - kEpoch2015Ns) / 10000));
            len = mav::sign_frame(b, len, sizeof b, key, ts).value();
          }
          (void)port.write(Span<const std::uint8_t>(b, len));
        };
        send(false);  // refused: unsigned
        send(true);   // accepted (the mode it is in)
        sent = true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  });
  EXPECT_EQ(dm.run(), 0);
  talker.join();
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  stop.store(true);
  rd.join();
  const MavlinkEndpoint& ep = *dm.nav().mavlink();
  std::lock_guard<std::mutex> lock(mu);
  std::printf("signed mission: %u frames, %u verified, timestamps %s, %u ACK, %u SET_GPS_GLOBAL_ORIGIN, cmd_unsigned %u, accepted %u, "
              "reader rejects %llu\n",
              frames, verified, increasing ? "increasing" : "NOT increasing", acks, origins, ep.counters().get(MavCounter::kCmdUnsigned),
              ep.commands_accepted(), static_cast<unsigned long long>(reader.counters().total()));
  // ODOMETRY at mavlink.odometry_hz (10 Hz) in mission time: the sim's AHRS streams between the
  // 5 Hz pings on the same grid (SimVehicle::ahrs_tick), so the worker has instants to publish at.
  ASSERT_GT(odo_usec.size(), 100u);
  std::vector<double> gaps_ms;
  for (std::size_t i = 1; i < odo_usec.size(); ++i) gaps_ms.push_back(static_cast<double>(odo_usec[i] - odo_usec[i - 1]) * 1e-3);
  std::sort(gaps_ms.begin(), gaps_ms.end());
  const double rate_hz = static_cast<double>(odo_usec.size() - 1) / (static_cast<double>(odo_usec.back() - odo_usec.front()) * 1e-6);
  const double p50 = gaps_ms[gaps_ms.size() / 2], p99 = gaps_ms[gaps_ms.size() * 99 / 100];
  std::printf("signed mission: %zu ODOMETRY at %.2f Hz mission time (configured %.0f Hz), interval p50 %.1f ms, p99 %.1f ms, max %.1f ms\n",
              odo_usec.size(), rate_hz, c.mavlink_odometry_hz, p50, p99, gaps_ms.back());
  if (odo_usec.size() == ep.odometry_sent()) {
    EXPECT_NEAR(rate_hz, c.mavlink_odometry_hz, 0.05 * c.mavlink_odometry_hz);
    EXPECT_NEAR(p99, 1000.0 / c.mavlink_odometry_hz, 0.2 * 1000.0 / c.mavlink_odometry_hz) << "p99 interval within 20 % of nominal";
  } else {  // the kernel dropped datagrams (receive buffer capped by net.core.rmem_max): the rate of what was sent
    std::printf("note: %zu of %u ODOMETRY received (UDP receive buffer full)\n", odo_usec.size(), ep.odometry_sent());
    const double sent_hz = static_cast<double>(ep.odometry_sent() - 1) / (static_cast<double>(odo_usec.back() - odo_usec.front()) * 1e-6);
    EXPECT_NEAR(sent_hz, c.mavlink_odometry_hz, 0.1 * c.mavlink_odometry_hz);
  }
  EXPECT_GT(frames, 100u);
  EXPECT_EQ(verified, frames) << "every frame qnavd sent is signed with the key";
  EXPECT_EQ(reader.counters().total(), 0u);
  EXPECT_TRUE(increasing);
  EXPECT_EQ(ep.counters().get(MavCounter::kCmdUnsigned), 1u);
  EXPECT_EQ(ep.commands_accepted(), 1u);
  EXPECT_EQ(acks, 1u);
  EXPECT_GE(origins, 1u) << "no GPS_GLOBAL_ORIGIN answer: repeated once a second of mission time";
  EXPECT_EQ(SoftwareFaults::count(), 0u);
  if (const char* path = std::getenv("QNAVD_MAVLINK_CAPTURE")) {
    FILE* f = std::fopen((std::string(path) + ".bin").c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fwrite(raw.data(), 1, raw.size(), f);
    std::fclose(f);
    f = std::fopen((std::string(path) + ".json").c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fprintf(f, "{\"key_hex\":\"%s\",\"frames\":%u,\"link_id\":%u,\"system_id\":%d,\"component_id\":%d}\n", kKeyHex, frames, kSignLinkId,
                 c.mavlink_system_id, c.mavlink_component_id);
    std::fclose(f);
  }
}

}  // namespace
}  // namespace qnav::daemon
