// XTF: round trip through the writer, hostile input (bad magic, zero-length and oversize packets,
// truncation, absurd sample counts, NaN navigation), and the two real files in shared/data.
// Runs on every target: on leon3 (big-endian) it proves the little-endian decoding.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "drivers/sidescan/xtf_parser.hpp"
#include "drivers/sidescan/xtf_reader.hpp"
#include "drivers/sidescan/xtf_writer.hpp"
#include "nav/core/byte_order.hpp"
#include "test/support/alloc_guard.hpp"
#include "firmware/tools/shared_dir.hpp"

namespace qnav::sidescan {
namespace {

std::vector<std::uint8_t> make_file(int pings, int n, std::vector<std::size_t>* offsets = nullptr) {
  std::vector<std::uint8_t> f(kXtfFileHeaderBytes);
  EXPECT_TRUE(encode_xtf_file_header(Span<std::uint8_t>(f.data(), f.size()), 3, "SIM").is_ok());
  std::vector<float> port(static_cast<std::size_t>(n)), stbd(static_cast<std::size_t>(n));
  for (int k = 0; k < pings; ++k) {
    for (int i = 0; i < n; ++i) {
      port[static_cast<std::size_t>(i)] = static_cast<float>(1000 + 10 * k + i);
      stbd[static_cast<std::size_t>(i)] = static_cast<float>(2000 + 10 * k + i);
    }
    XtfWritePing w;
    w.stamp_ns = 1378847588000000000ull + static_cast<std::uint64_t>(k) * 100000000ull;  // 2013-09-10 21:13:08
    w.ping_number = static_cast<std::uint32_t>(k);
    w.sensor_y = 48.4 + k * 1e-5;
    w.sensor_x = -68.8;
    w.heading_deg = 350.0f;
    w.altitude_m = 10.0f;
    w.slant_range_m = 30.0f;
    w.port = Span<const float>(port.data(), port.size());
    w.stbd = Span<const float>(stbd.data(), stbd.size());
    const std::size_t at = f.size();
    if (offsets) offsets->push_back(at);
    f.resize(at + xtf_ping_bytes(static_cast<std::size_t>(n)));
    const Result<std::size_t> r = encode_xtf_ping(Span<std::uint8_t>(f.data() + at, f.size() - at), w);
    EXPECT_TRUE(r.is_ok());
  }
  return f;
}

struct ReadResult {
  int pings = 0, attitudes = 0;
  Status error;
  std::vector<XtfPing> got;
};

ReadResult read_all(const std::vector<std::uint8_t>& bytes, XtfReader& reader, std::size_t max_samples = 4096) {
  ReadResult rr;
  MemorySource src(Span<const std::uint8_t>(bytes.data(), bytes.size()));
  rr.error = reader.open(src);
  if (!rr.error) return rr;
  std::vector<float> port(max_samples), stbd(max_samples);
  XtfRecord rec;
  for (int guard = 0; guard < 1000000; ++guard) {
    const Result<bool> r = reader.next(rec, Span<float>(port.data(), port.size()), Span<float>(stbd.data(), stbd.size()));
    if (!r) {
      rr.error = r.status();
      continue;  // the next call must report the end
    }
    if (!r.value()) break;
    if (rec.kind == XtfRecordKind::kPing) {
      ++rr.pings;
      rr.got.push_back(rec.ping);
      rr.got.back().pitch_deg = port[0];  // stash the first near-range samples for checks
      rr.got.back().roll_deg = stbd[0];
    }
    if (rec.kind == XtfRecordKind::kAttitude) ++rr.attitudes;
  }
  return rr;
}

XtfReader make_reader(std::size_t max_packet = 1u << 20) {
  XtfReader r;
  XtfReaderConfig c;
  c.max_packet_bytes = max_packet;
  EXPECT_TRUE(r.init(c).is_ok());
  return r;
}

TEST(Xtf, WriterReaderRoundTrip) {
  const std::vector<std::uint8_t> f = make_file(5, 300);
  XtfReader reader = make_reader();
  const ReadResult rr = read_all(f, reader);
  ASSERT_TRUE(rr.error.is_ok()) << rr.error.message();
  ASSERT_EQ(rr.pings, 5);
  EXPECT_EQ(reader.header().nav_units, 3);
  EXPECT_STREQ(reader.header().sonar_name, "SIM");
  ASSERT_EQ(reader.header().channels.size(), 2u);
  EXPECT_EQ(reader.header().channels[0].type_of_channel, 1);
  const XtfPing& p = rr.got[3];
  EXPECT_EQ(p.ping_number, 3u);
  EXPECT_EQ(p.samples_per_side, 300u);
  EXPECT_FLOAT_EQ(p.slant_range_m, 30.0f);
  EXPECT_DOUBLE_EQ(p.sensor_y, 48.4 + 3e-5);
  EXPECT_TRUE(p.nav_valid);
  EXPECT_EQ(p.year, 2013);
  EXPECT_EQ(p.hour, 21);
  EXPECT_EQ(p.stamp_ns, 1378847588000000000ull + 300000000ull);
  EXPECT_FLOAT_EQ(p.pitch_deg, 1030.0f);  // port near sample (written far first, read back near first)
  EXPECT_FLOAT_EQ(p.roll_deg, 2030.0f);
  EXPECT_EQ(reader.counters().total(), 0u);
}

TEST(Xtf, HeaderWithMoreThanSixChannelsGrowsBy1024Bytes) {
  // 2 sonar + 6 bathymetry channels: CHANINFO 7 and 8 live in a second 1024-byte block.
  std::vector<std::uint8_t> h(2048, 0);
  ASSERT_TRUE(encode_xtf_file_header(Span<std::uint8_t>(h.data(), 1024), 3, "BIG").is_ok());
  store_le_u16(h.data() + 168, 6);
  h[1024 + 128 + 0] = 3;  // channel 8: bathymetry
  std::memcpy(h.data() + 1024 + 128 + 12, "EIGHTH", 6);
  EXPECT_EQ(parse_xtf_file_header(Span<const std::uint8_t>(h.data(), 1024)).status(), StatusCode::kTruncated);
  const Result<XtfFileHeader> r = parse_xtf_file_header(Span<const std::uint8_t>(h.data(), h.size()));
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(r->header_bytes, 2048u);
  ASSERT_EQ(r->channels.size(), 8u);
  EXPECT_STREQ(r->channels[7].name, "EIGHTH");
  EXPECT_EQ(r->channels[7].type_of_channel, 3);
  // Through the reader: the packets start after the 2048 bytes.
  std::vector<std::uint8_t> f = make_file(2, 64);
  f.insert(f.begin() + 1024, h.begin() + 1024, h.end());
  store_le_u16(f.data() + 168, 6);
  XtfReader reader = make_reader();
  const ReadResult rr = read_all(f, reader);
  EXPECT_TRUE(rr.error.is_ok()) << rr.error.message();
  EXPECT_EQ(rr.pings, 2);
  EXPECT_EQ(reader.header().header_bytes, 2048u);
}

TEST(Xtf, EightBitSamplesNavigationAndAttitudePackets) {
  // A hand-built file: 8-bit channels, one ping, one navigation (42) and one attitude (3) packet.
  std::vector<std::uint8_t> f(kXtfFileHeaderBytes);
  ASSERT_TRUE(encode_xtf_file_header(Span<std::uint8_t>(f.data(), f.size()), 3, "EIGHT").is_ok());
  store_le_u16(f.data() + 256 + 6, 1);
  store_le_u16(f.data() + 256 + 128 + 6, 1);
  const int n = 40;
  std::vector<std::uint8_t> ping(kXtfPingHeaderBytes + 2 * (kXtfPingChanHeaderBytes + n), 0);
  store_le_u16(ping.data(), kXtfMagic);
  store_le_u16(ping.data() + 4, 2);
  store_le_u32(ping.data() + 10, static_cast<std::uint32_t>(ping.size()));
  store_le_u32(ping.data() + 28, 99);
  for (int c = 0; c < 2; ++c) {
    std::uint8_t* q = ping.data() + kXtfPingHeaderBytes + c * (kXtfPingChanHeaderBytes + n);
    store_le_u16(q, static_cast<std::uint16_t>(c));
    store_le_f32(q + 4, 20.0f);
    store_le_u32(q + 42, n);
    for (int i = 0; i < n; ++i) q[kXtfPingChanHeaderBytes + i] = static_cast<std::uint8_t>(c == 0 ? 200 - i : 10 + i);
  }
  std::vector<std::uint8_t> nav(64, 0), att(64, 0);
  store_le_u16(nav.data(), kXtfMagic);
  nav[2] = 42;
  store_le_u32(nav.data() + 10, 64);
  store_le_u32(nav.data() + 29, 123456);
  store_le_f64(nav.data() + 33, 48.5);
  store_le_f64(nav.data() + 41, -68.5);
  store_le_f32(nav.data() + 49, 12.5f);
  store_le_u16(att.data(), kXtfMagic);
  att[2] = 3;
  store_le_u32(att.data() + 10, 64);
  store_le_f32(att.data() + 30, 1.5f);
  store_le_f32(att.data() + 34, -2.5f);
  store_le_f32(att.data() + 50, 271.0f);
  f.insert(f.end(), nav.begin(), nav.end());
  f.insert(f.end(), ping.begin(), ping.end());
  f.insert(f.end(), att.begin(), att.end());
  XtfReader reader = make_reader();
  MemorySource src(Span<const std::uint8_t>(f.data(), f.size()));
  ASSERT_TRUE(reader.open(src).is_ok());
  std::vector<float> port(64), stbd(64);
  XtfRecord rec;
  ASSERT_TRUE(reader.next(rec, Span<float>(port.data(), 64), Span<float>(stbd.data(), 64)).value());
  ASSERT_EQ(rec.kind, XtfRecordKind::kNavigation);
  EXPECT_EQ(rec.navigation.time_tag_ms, 123456u);
  EXPECT_DOUBLE_EQ(rec.navigation.raw_y, 48.5);
  EXPECT_DOUBLE_EQ(rec.navigation.raw_x, -68.5);
  EXPECT_FLOAT_EQ(rec.navigation.raw_altitude_m, 12.5f);
  ASSERT_TRUE(reader.next(rec, Span<float>(port.data(), 64), Span<float>(stbd.data(), 64)).value());
  ASSERT_EQ(rec.kind, XtfRecordKind::kPing);
  EXPECT_EQ(rec.ping.ping_number, 99u);
  EXPECT_EQ(rec.ping.samples_per_side, 40u);
  EXPECT_FLOAT_EQ(port[0], 161.0f);  // stored far first: the last stored byte (200 - 39) is the nearest
  EXPECT_FLOAT_EQ(port[39], 200.0f);
  EXPECT_FLOAT_EQ(stbd[0], 10.0f);
  EXPECT_FLOAT_EQ(stbd[39], 49.0f);
  ASSERT_TRUE(reader.next(rec, Span<float>(port.data(), 64), Span<float>(stbd.data(), 64)).value());
  ASSERT_EQ(rec.kind, XtfRecordKind::kAttitude);
  EXPECT_FLOAT_EQ(rec.attitude.pitch_deg, 1.5f);
  EXPECT_FLOAT_EQ(rec.attitude.roll_deg, -2.5f);
  EXPECT_FLOAT_EQ(rec.attitude.heading_deg, 271.0f);
  EXPECT_FALSE(reader.next(rec, Span<float>(port.data(), 64), Span<float>(stbd.data(), 64)).value());
  EXPECT_EQ(reader.counters().total(), 1u);  // the ping has no position: ping_without_nav
}

TEST(Xtf, RejectsWrongFileMagicAndShortHeader) {
  std::vector<std::uint8_t> f = make_file(1, 64);
  f[0] = 0x7A;
  XtfReader reader = make_reader();
  EXPECT_EQ(read_all(f, reader).error, StatusCode::kCorrupt);
  f.resize(500);
  f[0] = kXtfFileFormat;
  EXPECT_EQ(read_all(f, reader).error, StatusCode::kTruncated);
  EXPECT_EQ(parse_xtf_file_header(Span<const std::uint8_t>(f.data(), f.size())).status(), StatusCode::kTruncated);
}

TEST(Xtf, TruncatedFileGivesOneClearErrorAndKeepsEarlierPings) {
  std::vector<std::uint8_t> f = make_file(3, 128);
  f.resize(f.size() - 100);
  XtfReader reader = make_reader();
  const ReadResult rr = read_all(f, reader);
  EXPECT_EQ(rr.pings, 2);
  EXPECT_EQ(rr.error, StatusCode::kTruncated);
  EXPECT_EQ(reader.counters().get(XtfCounter::kTruncated), 1u);
}

TEST(Xtf, ZeroLengthAndBadMagicPacketsAreResynchronisedNotLoopedOn) {
  std::vector<std::size_t> at;
  std::vector<std::uint8_t> f = make_file(4, 128, &at);
  store_le_u32(f.data() + at[1] + 10, 0);  // ping 1 claims zero length
  f[at[2]] = 0x00;                          // ping 2 lost its magic
  XtfReader reader = make_reader();
  const ReadResult rr = read_all(f, reader);
  EXPECT_TRUE(rr.error.is_ok()) << rr.error.message();
  ASSERT_EQ(rr.pings, 2);
  EXPECT_EQ(rr.got[0].ping_number, 0u);
  EXPECT_EQ(rr.got[1].ping_number, 3u);
  EXPECT_EQ(reader.counters().get(XtfCounter::kBadLength), 1u);
  EXPECT_GE(reader.counters().get(XtfCounter::kResyncBytes), 1u);
}

TEST(Xtf, AbsurdSampleCountsAndOversizePacketsAreCountedAndSkipped) {
  std::vector<std::size_t> at;
  std::vector<std::uint8_t> f = make_file(3, 128, &at);
  store_le_u32(f.data() + at[0] + kXtfPingHeaderBytes + 42, 0x7FFFFFFFu);  // samples run past the packet
  XtfReader reader = make_reader();
  ReadResult rr = read_all(f, reader);
  EXPECT_EQ(rr.pings, 2);
  EXPECT_EQ(reader.counters().get(XtfCounter::kBadPing), 1u);
  EXPECT_EQ(reader.last_decode_error(), StatusCode::kTruncated);
  // More samples than the caller's buffers: capacity error, counted.
  std::vector<std::uint8_t> g = make_file(2, 600);
  XtfReader r2 = make_reader();
  rr = read_all(g, r2, 512);
  EXPECT_EQ(rr.pings, 0);
  EXPECT_EQ(r2.counters().get(XtfCounter::kBadPing), 2u);
  EXPECT_EQ(r2.last_decode_error(), StatusCode::kCapacityExceeded);
  // Packet larger than the reader's buffer: skipped by its length.
  std::vector<std::uint8_t> h = make_file(2, 600);
  XtfReader r3 = make_reader(1024);
  rr = read_all(h, r3);
  EXPECT_EQ(rr.pings, 0);
  EXPECT_TRUE(rr.error.is_ok());
  EXPECT_EQ(r3.counters().get(XtfCounter::kOversize), 2u);
}

TEST(Xtf, NanOrPlaceholderNavigationIsFlaggedAndCounted) {
  std::vector<std::size_t> at;
  std::vector<std::uint8_t> f = make_file(3, 64, &at);
  store_le_f64(f.data() + at[1] + 160, std::nan(""));
  store_le_f64(f.data() + at[2] + 160, 0.0);
  store_le_f64(f.data() + at[2] + 168, 0.0);
  XtfReader reader = make_reader();
  const ReadResult rr = read_all(f, reader);
  ASSERT_EQ(rr.pings, 3);
  EXPECT_TRUE(rr.got[0].nav_valid);
  EXPECT_FALSE(rr.got[1].nav_valid);
  EXPECT_FALSE(rr.got[2].nav_valid);
  EXPECT_EQ(reader.counters().get(XtfCounter::kPingWithoutNav), 2u);
}

// Regression (issue #19): unknown nav units and projected positions beyond the Earth were read as
// positions. The file header's NavUnits byte is at offset 164.
TEST(Xtf, UnknownNavUnitsAndAbsurdProjectedPositionsAreNotNavigation) {
  std::vector<std::size_t> at;
  std::vector<std::uint8_t> f = make_file(3, 64, &at);
  store_le_u16(f.data() + 164, 7);
  {
    XtfReader reader = make_reader();
    const ReadResult rr = read_all(f, reader);
    ASSERT_EQ(rr.pings, 3);
    for (const XtfPing& p : rr.got) EXPECT_FALSE(p.nav_valid);
    EXPECT_EQ(reader.counters().get(XtfCounter::kPingWithoutNav), 3u);
  }
  store_le_u16(f.data() + 164, 0);  // metres
  store_le_f64(f.data() + at[0] + 160, 5.0e6);
  store_le_f64(f.data() + at[0] + 168, 4.0e5);
  store_le_f64(f.data() + at[1] + 160, 7.071e7);  // 70,710 km north
  store_le_f64(f.data() + at[1] + 168, 4.0e5);
  store_le_f64(f.data() + at[2] + 160, 5.0e6);
  store_le_f64(f.data() + at[2] + 168, -3.0e7);
  XtfReader reader = make_reader();
  const ReadResult rr = read_all(f, reader);
  ASSERT_EQ(rr.pings, 3);
  EXPECT_TRUE(rr.got[0].nav_valid);
  EXPECT_FALSE(rr.got[1].nav_valid);
  EXPECT_FALSE(rr.got[2].nav_valid);
}

TEST(Xtf, UnknownPacketTypesAreSkippedByLength) {
  std::vector<std::size_t> at;
  std::vector<std::uint8_t> f = make_file(3, 64, &at);
  f[at[1] + 2] = 200;  // an unknown type, same length
  XtfReader reader = make_reader();
  const ReadResult rr = read_all(f, reader);
  EXPECT_EQ(rr.pings, 2);
  EXPECT_EQ(reader.counters().get(XtfCounter::kSkippedPacket), 1u);
}

TEST(Xtf, ReadingPingsMakesNoHeapAllocation) {
  const std::vector<std::uint8_t> f = make_file(20, 256);
  XtfReader reader = make_reader();
  MemorySource src(Span<const std::uint8_t>(f.data(), f.size()));
  ASSERT_TRUE(reader.open(src).is_ok());
  std::vector<float> port(256), stbd(256);
  XtfRecord rec;
  int n = 0;
  QNAV_EXPECT_NO_ALLOC(while (true) {
    const Result<bool> r = reader.next(rec, Span<float>(port.data(), 256), Span<float>(stbd.data(), 256));
    if (!r.is_ok() || !r.value()) break;
    ++n;
  });
  EXPECT_EQ(n, 20);
}

TEST(Xtf, RandomlyCorruptedFilesNeverCrashOrHang) {
  // 400 seeded corruptions of a valid 3-ping file (bytes overwritten, cut short): every read ends
  // with records, counted skips or a clear error. Under ASan/UBSan this is a small fuzz run.
  const std::vector<std::uint8_t> good = make_file(3, 96);
  std::uint64_t rng = 12345;
  auto next = [&rng]() {
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
  };
  XtfReader reader = make_reader(4096);
  int opened = 0;
  for (int it = 0; it < 400; ++it) {
    std::vector<std::uint8_t> f = good;
    const int edits = 1 + static_cast<int>(next() % 8);
    for (int e = 0; e < edits; ++e) f[next() % f.size()] = static_cast<std::uint8_t>(next());
    if (next() % 3 == 0) f.resize(next() % f.size());
    const ReadResult rr = read_all(f, reader, 128);
    opened += rr.error.is_ok() ? 1 : 0;
    EXPECT_LE(rr.pings, 3);
  }
  EXPECT_GT(opened, 100);
}

std::vector<std::uint8_t> load(const std::string& path) {
  std::vector<std::uint8_t> b;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return b;
  std::uint8_t tmp[65536];
  std::size_t k;
  while ((k = std::fread(tmp, 1, sizeof tmp, f)) > 0) b.insert(b.end(), tmp, tmp + k);
  std::fclose(f);
  return b;
}

TEST(XtfRealData, ScotsmanIver2AllPingsWithNavigation) {
  const std::string path = qnav::tools::shared_dir() + "/data/sidescan/cidco-scotsman-iver2/scotsman-iver2.xtf";
  const std::vector<std::uint8_t> f = load(path);
  if (f.empty()) GTEST_SKIP() << "missing " << path;
  ASSERT_EQ(f.size(), 2066304u);
  XtfReader reader = make_reader();
  const ReadResult rr = read_all(f, reader);
  ASSERT_TRUE(rr.error.is_ok()) << rr.error.message();
  const XtfFileHeader& h = reader.header();
  EXPECT_EQ(h.system_type, 1);
  EXPECT_STREQ(h.recording_program, "SEASCAN");
  EXPECT_STREQ(h.recording_version, "3100");
  EXPECT_STREQ(h.sonar_name, "HDS");
  EXPECT_EQ(h.nav_units, 3);
  EXPECT_EQ(h.num_sonar_channels, 2);
  ASSERT_EQ(h.channels.size(), 2u);
  EXPECT_STREQ(h.channels[0].name, "PORT");
  EXPECT_STREQ(h.channels[1].name, "STARBOARD");
  EXPECT_EQ(h.channels[1].type_of_channel, 2);
  EXPECT_EQ(h.channels[0].bytes_per_sample, 2);
  EXPECT_FLOAT_EQ(h.channels[0].frequency_khz, 600.0f);
  ASSERT_EQ(rr.pings, 461);
  EXPECT_EQ(reader.counters().total(), 1u);  // the first ping has no fix yet (lat/lon 0, 0)
  EXPECT_EQ(reader.counters().get(XtfCounter::kPingWithoutNav), 1u);
  int with_nav = 0;
  for (const XtfPing& p : rr.got) with_nav += p.nav_valid ? 1 : 0;
  EXPECT_EQ(with_nav, 460);
  const XtfPing& p1 = rr.got[1];
  EXPECT_EQ(p1.ping_number, 1u);
  EXPECT_EQ(p1.samples_per_side, 1024u);
  EXPECT_NEAR(p1.slant_range_m, 29.9835f, 1e-4f);
  EXPECT_NEAR(p1.sensor_y, 48.44545, 1e-9);
  EXPECT_NEAR(p1.sensor_x, -68.827935, 1e-9);
  EXPECT_NEAR(p1.altitude_m, 11.45f, 1e-4f);
  EXPECT_NEAR(p1.heading_deg, 354.18f, 1e-3f);
  EXPECT_NEAR(p1.sensor_speed_knots, 1.71014f, 1e-4f);
  EXPECT_FLOAT_EQ(p1.sound_velocity_mps, 750.0f);
  // Near-range samples: port stored far first, so its near sample is the stored last one.
  EXPECT_FLOAT_EQ(p1.pitch_deg, 32767.0f);
  EXPECT_FLOAT_EQ(p1.roll_deg, 32767.0f);
  // Time span 21:13:08.00 .. 21:14:00.23 on 2013-09-10.
  EXPECT_EQ(rr.got.front().stamp_ns, 1378847588000000000ull);
  EXPECT_EQ(rr.got.back().stamp_ns - rr.got.front().stamp_ns, 52230000000ull);
}

TEST(XtfRealData, ScotsmanSampleValues) {
  const std::string path = qnav::tools::shared_dir() + "/data/sidescan/cidco-scotsman-iver2/scotsman-iver2.xtf";
  const std::vector<std::uint8_t> f = load(path);
  if (f.empty()) GTEST_SKIP() << "missing " << path;
  const Result<XtfFileHeader> h = parse_xtf_file_header(Span<const std::uint8_t>(f.data(), f.size()));
  ASSERT_TRUE(h.is_ok());
  std::vector<float> port(1024), stbd(1024);
  XtfPing p;
  ASSERT_TRUE(parse_xtf_sonar_ping(Span<const std::uint8_t>(f.data() + 1024, f.size() - 1024), h.value(), p,
                                   Span<float>(port.data(), 1024), Span<float>(stbd.data(), 1024))
                  .is_ok());
  // Ping 0, as stored: port far-range samples 91, 8460, 17597; starboard far samples ..., 10595, 113.
  EXPECT_FLOAT_EQ(port[1023], 91.0f);
  EXPECT_FLOAT_EQ(port[1022], 8460.0f);
  EXPECT_FLOAT_EQ(port[1021], 17597.0f);
  EXPECT_FLOAT_EQ(stbd[1023], 113.0f);
  EXPECT_FLOAT_EQ(stbd[1022], 10595.0f);
  EXPECT_FLOAT_EQ(stbd[0], 32767.0f);
  EXPECT_FALSE(p.nav_valid);
}

TEST(XtfRealData, MultibeamFileIsReadToTheEndWithPacketsSkipped) {
  const std::string path = qnav::tools::shared_dir() + "/data/sidescan/cidco-r2sonic-multibeam-xtf/0009-150708_R2Testing-0001.xtf";
  const std::vector<std::uint8_t> f = load(path);
  if (f.empty()) GTEST_SKIP() << "missing " << path;
  XtfReader reader = make_reader();
  const ReadResult rr = read_all(f, reader);
  ASSERT_TRUE(rr.error.is_ok()) << rr.error.message();
  EXPECT_EQ(rr.pings, 0);
  EXPECT_EQ(rr.attitudes, 1203);
  EXPECT_EQ(reader.counters().get(XtfCounter::kSkippedPacket), 923u + 1204u);
  EXPECT_EQ(reader.counters().get(XtfCounter::kBadMagic), 0u);
  EXPECT_EQ(reader.bytes_read(), f.size());
  EXPECT_EQ(reader.header().system_type, 202);
  EXPECT_EQ(reader.header().num_bathy_channels, 1);
}

}  // namespace
}  // namespace qnav::sidescan
