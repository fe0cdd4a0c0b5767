// MAVLink streaming parser: splits, garbage and resynchronisation, MAVLink 1, every reject counter,
// signing (verified, wrong key, replay, refused without a key).
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "drivers/mavlink/frame.hpp"
#include "drivers/mavlink/messages.hpp"
#include "drivers/mavlink/parser.hpp"
#include "nav/core/byte_order.hpp"
#include "test/support/alloc_guard.hpp"
#include "test/unit/drivers/mavlink/mavlink_test_util.hpp"

namespace qnav::drivers::mavlink {
namespace {

using test::Lcg;
using test::Sink;

std::vector<std::uint8_t> frame_of(FrameEncoder& enc, std::uint32_t msgid, Lcg& rng) {
  const MessageInfo* info = message_info(msgid);
  std::uint8_t payload[kMaxPayload] = {};
  for (std::size_t i = 0; i < info->full_len; ++i) payload[i] = rng.byte();
  std::uint8_t buf[kMaxFrameBytes];
  auto n = enc.encode(msgid, payload, info->full_len, Span<std::uint8_t>(buf));
  return std::vector<std::uint8_t>(buf, buf + n.value());
}

std::vector<std::uint8_t> heartbeat(FrameEncoder& enc, std::uint32_t custom_mode) {
  Heartbeat hb;
  hb.custom_mode = custom_mode;
  std::uint8_t buf[kMaxFrameBytes];
  auto n = encode(enc, hb, Span<std::uint8_t>(buf));
  return std::vector<std::uint8_t>(buf, buf + n.value());
}

// A MAVLink 1 frame built by hand: FE len seq sys comp msgid payload crc.
std::vector<std::uint8_t> v1_frame(std::uint8_t msgid, const std::vector<std::uint8_t>& payload, std::uint8_t seq) {
  std::vector<std::uint8_t> f;
  f.reserve(6 + payload.size() + 2);
  for (std::uint8_t b : {kMagicV1, static_cast<std::uint8_t>(payload.size()), seq, std::uint8_t{9}, std::uint8_t{8}, msgid})
    f.push_back(b);
  for (std::uint8_t b : payload) f.push_back(b);
  std::uint16_t crc = crc_mcrf4xx(f.data() + 1, f.size() - 1);
  crc = crc_accumulate(message_info(msgid)->crc_extra, crc);
  f.push_back(static_cast<std::uint8_t>(crc));
  f.push_back(static_cast<std::uint8_t>(crc >> 8));
  return f;
}

TEST(MavlinkParser, StreamSplitAnywhereDeliversEveryFrameInOrder) {
  Lcg rng(11);
  FrameEncoder enc(1, 1);
  std::vector<std::uint8_t> stream;
  std::vector<std::uint32_t> ids;
  const Span<const MessageInfo> known = known_messages();
  for (int i = 0; i < 500; ++i) {
    const std::uint32_t id = known[rng.below(static_cast<std::uint32_t>(known.size()))].id;
    const auto f = frame_of(enc, id, rng);
    stream.insert(stream.end(), f.begin(), f.end());
    ids.push_back(id);
  }
  for (int split_seed = 0; split_seed < 4; ++split_seed) {
    Parser p;
    Sink sink;
    Lcg cut(static_cast<std::uint32_t>(split_seed));
    std::size_t at = 0;
    while (at < stream.size()) {
      std::size_t n = split_seed == 0 ? 1 : 1 + cut.below(300);
      if (n > stream.size() - at) n = stream.size() - at;
      p.feed(Span<const std::uint8_t>(stream.data() + at, n), [&](const Frame& f) { sink(f); });
      at += n;
    }
    ASSERT_EQ(sink.frames.size(), ids.size());
    for (std::size_t i = 0; i < ids.size(); ++i) {
      EXPECT_EQ(sink.frames[i].msgid, ids[i]);
      EXPECT_EQ(sink.frames[i].seq, static_cast<std::uint8_t>(i));
    }
    EXPECT_EQ(p.counters().total(), 0u);
    EXPECT_EQ(p.buffered_bytes(), 0u);
  }
}

TEST(MavlinkParser, GarbageBetweenFramesIsCountedPerByte) {
  FrameEncoder enc(1, 1);
  std::vector<std::uint8_t> stream;
  std::uint32_t garbage = 0;
  for (int i = 0; i < 20; ++i) {
    for (int g = 0; g < i; ++g) {
      stream.push_back(static_cast<std::uint8_t>(0x30 + g));  // no magic bytes
      ++garbage;
    }
    const auto f = heartbeat(enc, static_cast<std::uint32_t>(i));
    stream.insert(stream.end(), f.begin(), f.end());
  }
  Parser p;
  Sink sink;
  test::feed_all(p, stream, sink);
  ASSERT_EQ(sink.frames.size(), 20u);
  EXPECT_EQ(p.counters().get(ParserCounter::kGarbageBytes), garbage);
  EXPECT_EQ(p.counters().total(), garbage);
}

TEST(MavlinkParser, FalseMagicNeverHidesTheFrameBehindIt) {
  // A lone 0xFD whose "length" would swallow the next real frame: the CRC fails, the parser rescans
  // from the byte after it and finds the real frame.
  FrameEncoder enc(1, 1);
  const auto real = heartbeat(enc, 77);
  std::vector<std::uint8_t> stream = {0xFD, 0xF0, 0x00, 0x00, 0x01, 0x02, 0x03, 0x00, 0x00, 0x00};
  stream.insert(stream.end(), real.begin(), real.end());
  // Fill so that the false frame (0xF0 > HEARTBEAT's 9 bytes) would be complete.
  stream.insert(stream.end(), 300, 0x55);
  Parser p;
  Sink sink;
  test::feed_all(p, stream, sink);
  ASSERT_EQ(sink.frames.size(), 1u);
  Heartbeat hb;
  ASSERT_TRUE(decode(sink.frames[0], hb));
  EXPECT_EQ(hb.custom_mode, 77u);
  EXPECT_EQ(p.counters().get(ParserCounter::kBadLength), 1u);  // 0xF0 bytes for a 9-byte message
  EXPECT_EQ(p.counters().get(ParserCounter::kGarbageBytes), 9u + 300u);
}

TEST(MavlinkParser, BadCrcIsCountedAndTheNextFrameStillArrives) {
  FrameEncoder enc(1, 1);
  auto bad = heartbeat(enc, 1);
  bad[12] ^= 0x40;
  const auto good = heartbeat(enc, 2);
  std::vector<std::uint8_t> stream = bad;
  stream.insert(stream.end(), good.begin(), good.end());
  Parser p;
  Sink sink;
  test::feed_all(p, stream, sink);
  ASSERT_EQ(sink.frames.size(), 1u);
  EXPECT_EQ(sink.frames[0].seq, 1);
  EXPECT_EQ(p.counters().get(ParserCounter::kBadCrc), 1u);
  EXPECT_EQ(p.counters().get(ParserCounter::kGarbageBytes), bad.size() - 1);
}

TEST(MavlinkParser, UnknownMessageIsSkippedWholeByItsLength) {
  // Message id 9999 with a payload full of 0xFD bytes: skipped by length, no false frames inside.
  std::vector<std::uint8_t> f = {kMagicV2, 20, 0, 0, 0, 1, 1, 0x0F, 0x27, 0x00};
  f.insert(f.end(), 20, 0xFD);
  f.push_back(0x12);
  f.push_back(0x34);
  FrameEncoder enc(1, 1);
  const auto good = heartbeat(enc, 5);
  f.insert(f.end(), good.begin(), good.end());
  Parser p;
  Sink sink;
  test::feed_all(p, f, sink);
  ASSERT_EQ(sink.frames.size(), 1u);
  EXPECT_EQ(p.counters().get(ParserCounter::kUnknownMessage), 1u);
  EXPECT_EQ(p.counters().total(), 1u);
}

TEST(MavlinkParser, LengthAndIncompatFlagsAreChecked) {
  FrameEncoder enc(1, 1);
  auto too_long = heartbeat(enc, 1);
  too_long[1] = 10;  // HEARTBEAT is at most 9 bytes
  auto flags = heartbeat(enc, 2);
  flags[2] = 0x02;   // an incompat flag nobody defined
  std::vector<std::uint8_t> stream = too_long;
  stream.insert(stream.end(), flags.begin(), flags.end());
  const auto good = heartbeat(enc, 3);
  stream.insert(stream.end(), good.begin(), good.end());
  Parser p;
  Sink sink;
  test::feed_all(p, stream, sink);
  ASSERT_EQ(sink.frames.size(), 1u);
  EXPECT_EQ(sink.frames[0].seq, 2);
  EXPECT_EQ(p.counters().get(ParserCounter::kBadLength), 1u);
  EXPECT_EQ(p.counters().get(ParserCounter::kIncompatFlags), 1u);
}

TEST(MavlinkParser, ZeroLengthPayloadIsAllZeros) {
  // node-mavlink 2.3.0 sends an all-zero SYSTEM_TIME with length 0 (fd 00 ... 99 a3).
  const std::vector<std::uint8_t> f = {0xfd, 0x00, 0x00, 0x00, 0x08, 0x2a, 0xc5, 0x02, 0x00, 0x00, 0x99, 0xa3};
  Parser p;
  Sink sink;
  test::feed_all(p, f, sink);
  ASSERT_EQ(sink.frames.size(), 1u);
  SystemTime t;
  t.time_boot_ms = 5;
  ASSERT_TRUE(decode(sink.frames[0], t));
  EXPECT_EQ(t.time_boot_ms, 0u);
  EXPECT_EQ(t.time_unix_usec, 0u);
}

TEST(MavlinkParser, MavlinkOneFramesAreAcceptedOrRefused) {
  // ATTITUDE as MAVLink 1 (28 bytes, no truncation), then a HEARTBEAT.
  std::uint8_t payload[28] = {};
  Attitude a;
  a.time_boot_ms = 1234;
  a.yaw = -1.25f;
  encode_payload(a, payload);
  const auto v1 = v1_frame(Attitude::kId, std::vector<std::uint8_t>(payload, payload + 28), 5);
  {
    Parser p;
    Sink sink;
    test::feed_all(p, v1, sink);
    ASSERT_EQ(sink.frames.size(), 1u);
    EXPECT_EQ(sink.frames[0].version, 1);
    EXPECT_EQ(sink.frames[0].seq, 5);
    EXPECT_EQ(sink.frames[0].sysid, 9);
    EXPECT_EQ(sink.frames[0].compid, 8);
    Attitude back;
    ASSERT_TRUE(decode(sink.frames[0], back));
    EXPECT_EQ(back.time_boot_ms, 1234u);
    EXPECT_EQ(back.yaw, -1.25f);
    EXPECT_EQ(p.stats().frames_v1, 1u);
  }
  {
    Parser p;
    p.set_accept_v1(false);
    Sink sink;
    test::feed_all(p, v1, sink);
    EXPECT_TRUE(sink.frames.empty());
    EXPECT_EQ(p.counters().get(ParserCounter::kV1Refused), 1u);
  }
  {  // MAVLink 1 has no truncation: a shorter payload is a bad length.
    Parser p;
    Sink sink;
    test::feed_all(p, v1_frame(Attitude::kId, std::vector<std::uint8_t>(payload, payload + 20), 0), sink);
    EXPECT_TRUE(sink.frames.empty());
    EXPECT_EQ(p.counters().get(ParserCounter::kBadLength), 1u);
  }
}

SigningKey key_of(std::uint8_t fill, std::uint8_t link) {
  SigningKey k;
  for (std::size_t i = 0; i < sizeof(k.secret); ++i) k.secret[i] = static_cast<std::uint8_t>(fill + i);
  k.link_id = link;
  return k;
}

std::vector<std::uint8_t> signed_command(FrameEncoder& enc, const SigningKey& key, std::uint64_t ts) {
  CommandLong c;
  c.command = 31010;
  c.param1 = 2.0f;
  std::uint8_t buf[kMaxFrameBytes];
  auto n = encode(enc, c, Span<std::uint8_t>(buf));
  auto s = sign_frame(buf, n.value(), sizeof(buf), key, ts);
  return std::vector<std::uint8_t>(buf, buf + s.value());
}

TEST(MavlinkParser, SignedFramesVerifiedWithTheKeyOnly) {
  const SigningKey key = key_of(1, 3);
  FrameEncoder enc(255, 190);
  const auto f1 = signed_command(enc, key, 1000);
  EXPECT_EQ(f1.size(), kHeaderV2 + 33 - 0 + kChecksumBytes + kSignatureBytes - (33 - f1[1]));
  EXPECT_EQ(f1[2], kIncompatSigned);
  {
    Parser p;  // no key: refused
    Sink sink;
    test::feed_all(p, f1, sink);
    EXPECT_TRUE(sink.frames.empty());
    EXPECT_EQ(p.counters().get(ParserCounter::kSignedRefused), 1u);
    EXPECT_EQ(p.counters().total(), 1u);
  }
  {
    Parser p;
    p.set_signing_key(key);
    Sink sink;
    test::feed_all(p, f1, sink);
    ASSERT_EQ(sink.frames.size(), 1u);
    EXPECT_TRUE(sink.frames[0].is_signed);
    EXPECT_TRUE(sink.frames[0].signature_verified);
    EXPECT_EQ(sink.frames[0].link_id, 3);
    EXPECT_EQ(sink.frames[0].sign_timestamp, 1000u);
    CommandLong c;
    ASSERT_TRUE(decode(sink.frames[0], c));
    EXPECT_EQ(c.command, 31010);
    // The same frame again is a replay; a newer one passes.
    test::feed_all(p, f1, sink);
    EXPECT_EQ(sink.frames.size(), 1u);
    EXPECT_EQ(p.counters().get(ParserCounter::kReplay), 1u);
    test::feed_all(p, signed_command(enc, key, 1001), sink);
    EXPECT_EQ(sink.frames.size(), 2u);
    EXPECT_EQ(p.stats().frames_signed, 2u);
  }
  {
    Parser p;
    p.set_signing_key(key_of(2, 3));  // another key
    Sink sink;
    test::feed_all(p, f1, sink);
    EXPECT_TRUE(sink.frames.empty());
    EXPECT_EQ(p.counters().get(ParserCounter::kBadSignature), 1u);
  }
  {  // a tampered signature byte (the CRC does not cover the signature)
    Parser p;
    p.set_signing_key(key);
    auto t = f1;
    t.back() ^= 1;
    Sink sink;
    test::feed_all(p, t, sink);
    EXPECT_TRUE(sink.frames.empty());
    EXPECT_EQ(p.counters().get(ParserCounter::kBadSignature), 1u);
  }
}

// The signing specification's one-minute rule: a signed frame more than 6,000,000 x 10 us behind the
// local timestamp (the caller's clock, or the newest verified frame) is stale, also on a new stream.
TEST(MavlinkParser, SignedFramesMoreThanAMinuteBehindTheLocalTimestampAreStale) {
  const SigningKey key = key_of(5, 1);
  const std::uint64_t now = 100000000000ull;  // ~11.6 days after 2015-01-01 in 10 us units
  Parser p;
  p.set_signing_key(key);
  p.set_local_timestamp(now);
  p.set_local_timestamp(now - 5);  // never moves back
  EXPECT_EQ(p.local_timestamp(), now);
  Sink sink;
  FrameEncoder a(1, 1), b(2, 1), c(3, 1);
  test::feed_all(p, signed_command(a, key, now - kSigningWindow10us - 1), sink);  // 1 tick past the minute
  EXPECT_TRUE(sink.frames.empty());
  EXPECT_EQ(p.counters().get(ParserCounter::kStaleTimestamp), 1u);
  test::feed_all(p, signed_command(a, key, now - kSigningWindow10us), sink);  // exactly a minute: accepted
  ASSERT_EQ(sink.frames.size(), 1u);
  // A verified frame ahead of the clock moves the local timestamp: an old stream falls behind it.
  test::feed_all(p, signed_command(b, key, now + 2 * kSigningWindow10us), sink);
  EXPECT_EQ(p.local_timestamp(), now + 2 * kSigningWindow10us);
  test::feed_all(p, signed_command(c, key, now), sink);
  EXPECT_EQ(sink.frames.size(), 2u);
  EXPECT_EQ(p.counters().get(ParserCounter::kStaleTimestamp), 2u);
  // A frame that fails its signature never moves the local timestamp.
  test::feed_all(p, signed_command(c, key_of(6, 1), now + 10 * kSigningWindow10us), sink);
  EXPECT_EQ(p.local_timestamp(), now + 2 * kSigningWindow10us);
  EXPECT_EQ(p.counters().get(ParserCounter::kBadSignature), 1u);
}

TEST(MavlinkParser, SigningStreamTableIsBounded) {
  const SigningKey key = key_of(7, 0);
  Parser p;
  p.set_signing_key(key);
  Sink sink;
  for (std::size_t i = 0; i < kMaxSigningStreams + 1; ++i) {
    FrameEncoder enc(static_cast<std::uint8_t>(10 + i), 1);
    test::feed_all(p, signed_command(enc, key, 5), sink);
  }
  EXPECT_EQ(sink.frames.size(), kMaxSigningStreams);
  EXPECT_EQ(p.counters().get(ParserCounter::kSigningStreams), 1u);
}

TEST(MavlinkParser, RandomBytesNeverCrashAndEveryFrameAfterThemArrives) {
  Lcg rng(99);
  FrameEncoder enc(1, 1);
  Parser p;
  Sink sink;
  std::size_t sent = 0;
  for (int round = 0; round < 200; ++round) {
    std::vector<std::uint8_t> noise(rng.below(600));
    for (auto& b : noise) b = rng.byte();
    test::feed_all(p, noise, sink);
    // Flush: a frame is recognised once the noise is behind it (at most one max-length frame of
    // bytes may still be buffered as a candidate, so send enough frames to push it out).
    const std::size_t before = sink.frames.size();
    for (int k = 0; k < 25; ++k) {
      test::feed_all(p, heartbeat(enc, 0xABCD0000u + static_cast<std::uint32_t>(round)), sink);
      ++sent;
    }
    EXPECT_GE(sink.frames.size() - before, 1u);
  }
  std::size_t ours = 0;
  for (const Frame& f : sink.frames) {
    Heartbeat hb;
    if (f.sysid == 1 && decode(f, hb) && (hb.custom_mode & 0xFFFF0000u) == 0xABCD0000u) ++ours;
  }
  // Noise can swallow the first frames after it (a false header's length covering them), never more
  // than a max-length frame's worth (280 bytes = 13 heartbeats of 21 bytes).
  EXPECT_GE(ours, sent - 200u * 14u);
  EXPECT_GT(p.counters().get(ParserCounter::kGarbageBytes), 0u);
}

TEST(MavlinkParser, EncodeSignParseAndDecodeAllocateNothing) {
  const SigningKey key = key_of(5, 1);
  FrameEncoder enc(1, 197);
  Parser p;
  p.set_signing_key(key);
  std::uint8_t buf[kMaxFrameBytes];
  int decoded = 0;
  auto on_frame = [&](const Frame& f) {
    Odometry o;
    if (decode(f, o)) ++decoded;
  };
  QNAV_EXPECT_NO_ALLOC({
    for (int i = 0; i < 100; ++i) {
      Odometry o;
      o.time_usec = static_cast<std::uint64_t>(i);
      o.quality = 50;
      auto n = encode(enc, o, Span<std::uint8_t>(buf));
      std::size_t len = n.is_ok() ? n.value() : 0;
      if (i % 2 == 0) {
        auto s = sign_frame(buf, len, sizeof(buf), key, static_cast<std::uint64_t>(100 + i));
        len = s.is_ok() ? s.value() : 0;
      }
      p.feed(Span<const std::uint8_t>(buf, len), on_frame);
    }
  });
  EXPECT_EQ(decoded, 100);
  EXPECT_EQ(p.stats().frames_signed, 50u);
}

}  // namespace
}  // namespace qnav::drivers::mavlink
