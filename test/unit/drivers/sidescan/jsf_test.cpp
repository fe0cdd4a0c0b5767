// JSF: message decoding, the live-stream framer fed in arbitrary chunks (including 1 byte at a
// time), garbage and corrupt headers between messages, oversize and truncated messages, and the
// port/starboard ping assembler.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "drivers/sidescan/jsf_framer.hpp"
#include "drivers/sidescan/jsf_parser.hpp"
#include "nav/core/byte_order.hpp"
#include "test/support/alloc_guard.hpp"

namespace qnav::sidescan {
namespace {

void append_message(std::vector<std::uint8_t>& s, std::uint32_t ping, std::uint8_t channel, int n, std::uint8_t subsystem = 20) {
  std::vector<float> v(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) v[static_cast<std::size_t>(i)] = static_cast<float>(100 * channel + ping + i);
  JsfWriteSonar w;
  w.subsystem = subsystem;
  w.channel = channel;
  w.ping_number = ping;
  w.stamp_ns = 1700000000000000000ull + ping * 100000000ull;
  w.altitude_m = 7.5f;
  w.heading_deg = 123.45f;
  w.lat_deg = 48.5;
  w.lon_deg = -68.75;
  w.samples = Span<const float>(v.data(), v.size());
  w.weighting_factor = 2;
  const std::size_t at = s.size();
  s.resize(at + jsf_sonar_message_bytes(static_cast<std::size_t>(n)));
  ASSERT_TRUE(encode_jsf_sonar_message(Span<std::uint8_t>(s.data() + at, s.size() - at), w).is_ok());
}

std::vector<std::uint8_t> stream(int pings, int n) {
  std::vector<std::uint8_t> s;
  for (int p = 0; p < pings; ++p) {
    append_message(s, static_cast<std::uint32_t>(p), 0, n);
    append_message(s, static_cast<std::uint32_t>(p), 1, n);
  }
  return s;
}

struct Feed {
  JsfFramer framer;
  JsfPingAssembler pings;
  std::vector<std::uint32_t> ping_numbers;
  int messages = 0;
  explicit Feed(std::size_t cap = 65536) {
    EXPECT_TRUE(framer.init(cap).is_ok());
    EXPECT_TRUE(pings.init(4096).is_ok());
  }
  void push(Span<const std::uint8_t> chunk) {
    while (!chunk.empty()) {
      const std::size_t used = framer.feed(chunk);
      chunk = chunk.subspan(used, chunk.size() - used);
      JsfMessageView m;
      while (framer.next(m)) {
        ++messages;
        if (pings.add(m)) ping_numbers.push_back(pings.ping().ping_number);
      }
    }
  }
};

TEST(Jsf, DecodesASonarDataMessage) {
  std::vector<std::uint8_t> s;
  append_message(s, 7, 1, 500);
  const Result<JsfMessageHeader> h = parse_jsf_message_header(Span<const std::uint8_t>(s.data(), s.size()));
  ASSERT_TRUE(h.is_ok());
  EXPECT_EQ(h->message_type, 80);
  EXPECT_EQ(h->channel, 1);
  EXPECT_EQ(h->subsystem, 20);
  EXPECT_EQ(static_cast<std::size_t>(h->body_bytes), 240u + 1000u);
  std::vector<float> samples(1000);
  JsfSonarData d;
  ASSERT_TRUE(parse_jsf_sonar_data(h.value(), Span<const std::uint8_t>(s.data() + 16, s.size() - 16), d,
                                   Span<float>(samples.data(), samples.size()))
                  .is_ok());
  EXPECT_EQ(d.ping_number, 7u);
  EXPECT_EQ(d.samples, 500u);
  EXPECT_FLOAT_EQ(samples[0], 107.0f);  // weighting 2: stored x4, read back / 4
  EXPECT_FLOAT_EQ(samples[499], 606.0f);
  EXPECT_NEAR(d.slant_range_m, 500 * 20e-6 * 1500.0 / 2.0, 1e-3);
  EXPECT_NEAR(d.altitude_m, 7.5f, 1e-3f);
  EXPECT_NEAR(d.heading_deg, 123.45f, 0.006f);
  EXPECT_TRUE(d.position_valid);
  EXPECT_NEAR(d.y, 48.5, 1e-6);
  EXPECT_NEAR(d.x, -68.75, 1e-6);
  EXPECT_EQ(d.stamp_ns, 1700000000700000000ull);
}

TEST(Jsf, AnalyticSamplesBecomeMagnitudes) {
  // Data format 1: I, Q int16 pairs -> sqrt(I^2 + Q^2), scaled by 2^-weighting.
  const int n = 16;
  std::vector<std::uint8_t> s(16 + 240 + 4 * n, 0);
  store_le_u16(s.data(), kJsfSync);
  store_le_u16(s.data() + 4, 80);
  s[7] = 21;
  store_le_u32(s.data() + 12, static_cast<std::uint32_t>(240 + 4 * n));
  std::uint8_t* b = s.data() + 16;
  store_le_u16(b + 34, 1);
  store_le_u16(b + 114, n);
  store_le_u32(b + 116, 10000);
  store_le_u16(b + 168, 1);
  for (int i = 0; i < n; ++i) {
    store_le_u16(b + 240 + 4 * i, static_cast<std::uint16_t>(3 * i));
    store_le_u16(b + 240 + 4 * i + 2, static_cast<std::uint16_t>(static_cast<std::int16_t>(-4 * i)));
  }
  const JsfMessageHeader h = parse_jsf_message_header(Span<const std::uint8_t>(s.data(), s.size())).value();
  std::vector<float> out(n);
  JsfSonarData d;
  ASSERT_TRUE(parse_jsf_sonar_data(h, Span<const std::uint8_t>(b, s.size() - 16), d, Span<float>(out.data(), out.size())).is_ok());
  EXPECT_EQ(d.samples, 16u);
  EXPECT_FLOAT_EQ(out[5], 12.5f);  // |3*5 - 4*5 i| = 25, / 2
  EXPECT_LT(d.altitude_m, 0.0f);   // validity bit 6 not set: no altitude
  EXPECT_FALSE(d.position_valid);
}

TEST(Jsf, RejectsBadSyncSizesAndFormats) {
  std::vector<std::uint8_t> s;
  append_message(s, 1, 0, 64);
  std::vector<float> out(64);
  JsfSonarData d;
  std::vector<std::uint8_t> bad = s;
  bad[0] = 0x02;
  EXPECT_EQ(parse_jsf_message_header(Span<const std::uint8_t>(bad.data(), bad.size())).status(), StatusCode::kCorrupt);
  bad = s;
  store_le_u32(bad.data() + 12, 0x80000000u);
  EXPECT_EQ(parse_jsf_message_header(Span<const std::uint8_t>(bad.data(), bad.size())).status(), StatusCode::kCorrupt);
  const JsfMessageHeader h = parse_jsf_message_header(Span<const std::uint8_t>(s.data(), s.size())).value();
  // Absurd sample count (20 bits) against a short body.
  bad = s;
  store_le_u16(bad.data() + 16 + 114, 0xFFFF);
  EXPECT_EQ(parse_jsf_sonar_data(h, Span<const std::uint8_t>(bad.data() + 16, bad.size() - 16), d, Span<float>(out.data(), 64)),
            StatusCode::kCorrupt);
  // Unknown sample format.
  bad = s;
  store_le_u16(bad.data() + 16 + 34, 300);
  EXPECT_EQ(parse_jsf_sonar_data(h, Span<const std::uint8_t>(bad.data() + 16, bad.size() - 16), d, Span<float>(out.data(), 64)),
            StatusCode::kUnsupported);
  // Body shorter than the size field says.
  EXPECT_EQ(parse_jsf_sonar_data(h, Span<const std::uint8_t>(s.data() + 16, 100), d, Span<float>(out.data(), 64)), StatusCode::kTruncated);
  // Buffer too small.
  EXPECT_EQ(parse_jsf_sonar_data(h, Span<const std::uint8_t>(s.data() + 16, s.size() - 16), d, Span<float>(out.data(), 10)),
            StatusCode::kCapacityExceeded);
}

TEST(JsfFramer, AnyChunkingGivesTheSameMessages) {
  const std::vector<std::uint8_t> s = stream(6, 300);
  for (std::size_t chunk : {std::size_t{1}, std::size_t{7}, std::size_t{16}, std::size_t{17}, std::size_t{255}, s.size()}) {
    Feed f;
    for (std::size_t at = 0; at < s.size(); at += chunk)
      f.push(Span<const std::uint8_t>(s.data() + at, std::min(chunk, s.size() - at)));
    EXPECT_EQ(f.messages, 12) << "chunk " << chunk;
    ASSERT_EQ(f.ping_numbers.size(), 6u) << "chunk " << chunk;
    for (std::uint32_t k = 0; k < 6; ++k) EXPECT_EQ(f.ping_numbers[k], k);
    EXPECT_EQ(f.framer.counters().get(JsfCounter::kResyncBytes), 0u);
    EXPECT_EQ(f.framer.pending_bytes(), 0u);
  }
}

TEST(JsfFramer, ResynchronisesAfterGarbageAndCorruptHeaders) {
  std::vector<std::uint8_t> s;
  const std::uint8_t junk[] = {0x00, 0x01, 0x01, 0x16, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x42};
  s.insert(s.end(), junk, junk + sizeof junk);  // includes a fake sync with a negative size
  append_message(s, 0, 0, 100);
  append_message(s, 0, 1, 100);
  s.insert(s.end(), junk, junk + 5);
  append_message(s, 1, 0, 100);
  append_message(s, 1, 1, 100);
  Feed f;
  for (std::size_t at = 0; at < s.size(); at += 3) f.push(Span<const std::uint8_t>(s.data() + at, std::min<std::size_t>(3, s.size() - at)));
  ASSERT_EQ(f.ping_numbers.size(), 2u);
  EXPECT_EQ(f.messages, 4);
  EXPECT_GE(f.framer.counters().get(JsfCounter::kBadHeader), 1u);
  EXPECT_GE(f.framer.counters().get(JsfCounter::kResyncBytes), 5u);
}

TEST(JsfFramer, OversizeMessagesAreResynchronisedPastAndTruncationIsVisible) {
  std::vector<std::uint8_t> s;
  append_message(s, 0, 0, 2000);  // 4256 bytes: above a 1024-byte framer
  append_message(s, 1, 0, 100);
  append_message(s, 1, 1, 100);
  append_message(s, 2, 0, 100);
  s.resize(s.size() - 50);  // the stream stops inside the last message
  Feed f(1024);
  f.push(Span<const std::uint8_t>(s.data(), s.size()));
  EXPECT_EQ(f.framer.counters().get(JsfCounter::kOversize), 1u);
  EXPECT_EQ(f.messages, 2);
  ASSERT_EQ(f.ping_numbers.size(), 1u);
  EXPECT_EQ(f.ping_numbers[0], 1u);
  // The oversize message was searched through for the next sync, not skipped by its length.
  EXPECT_GE(f.framer.counters().get(JsfCounter::kResyncBytes), 4256u - 16u);
  EXPECT_GT(f.framer.pending_bytes(), 0u);
}

// Regression (issue #19): one damaged size field made the framer swallow megabytes (every message up
// to the claimed length). The size of a sonar message must match its own sample count, and a size
// larger than the buffer is never trusted to skip data: the messages after it are all framed.
TEST(JsfFramer, ADamagedSizeFieldLosesOnlyItsOwnMessage) {
  for (std::uint32_t bad_size : {3000000u, 2u << 20, 240u + 2u * 64u + 2u, 100u}) {
    std::vector<std::uint8_t> s;
    append_message(s, 0, 0, 64);
    append_message(s, 0, 1, 64);
    const std::size_t damaged = s.size();
    append_message(s, 1, 0, 64);
    for (std::uint32_t p = 1; p < 6; ++p) {
      if (p > 1) append_message(s, p, 0, 64);
      append_message(s, p, 1, 64);
    }
    store_le_u32(s.data() + damaged + 12, bad_size);
    for (std::size_t chunk : {std::size_t{1}, std::size_t{100}, s.size()}) {
      Feed f(4u << 20);
      for (std::size_t at = 0; at < s.size(); at += chunk)
        f.push(Span<const std::uint8_t>(s.data() + at, std::min(chunk, s.size() - at)));
      EXPECT_EQ(f.messages, 11) << bad_size << " chunk " << chunk;
      ASSERT_EQ(f.ping_numbers.size(), 5u) << bad_size << " chunk " << chunk;  // ping 1 lost its port side only
      EXPECT_EQ(f.ping_numbers[1], 2u);
      EXPECT_EQ(f.ping_numbers[4], 5u);
      EXPECT_GE(f.framer.counters().get(JsfCounter::kBadHeader), 1u);
      EXPECT_EQ(f.framer.pending_bytes(), 0u);
    }
  }
}

// Regression (issue #19): heading 0xFFFF (655.35 degrees) was passed on as a direction.
TEST(Jsf, HeadingOutsideTheCircleIsNotADirection) {
  std::vector<std::uint8_t> s;
  append_message(s, 1, 0, 64);
  std::vector<float> out(64);
  JsfSonarData d;
  const JsfMessageHeader h = parse_jsf_message_header(Span<const std::uint8_t>(s.data(), s.size())).value();
  store_le_u16(s.data() + 16 + 172, 0xFFFF);
  ASSERT_TRUE(parse_jsf_sonar_data(h, Span<const std::uint8_t>(s.data() + 16, s.size() - 16), d, Span<float>(out.data(), 64)).is_ok());
  EXPECT_TRUE(std::isnan(d.heading_deg));
  store_le_u16(s.data() + 16 + 172, 35999);
  ASSERT_TRUE(parse_jsf_sonar_data(h, Span<const std::uint8_t>(s.data() + 16, s.size() - 16), d, Span<float>(out.data(), 64)).is_ok());
  EXPECT_NEAR(d.heading_deg, 359.99f, 1e-3f);
}

TEST(JsfPingAssembler, PairsSidesCountsOrphansAndOtherMessages) {
  std::vector<std::uint8_t> s;
  append_message(s, 0, 0, 64);
  append_message(s, 1, 0, 64);  // ping 0 starboard never came
  append_message(s, 1, 1, 64);
  append_message(s, 1, 0, 64, 0);  // sub-bottom subsystem: not side-scan
  std::vector<std::uint8_t> other(16 + 8, 0);
  store_le_u16(other.data(), kJsfSync);
  store_le_u16(other.data() + 4, 182);
  store_le_u32(other.data() + 12, 8);
  s.insert(s.end(), other.begin(), other.end());
  Feed f;
  f.push(Span<const std::uint8_t>(s.data(), s.size()));
  ASSERT_EQ(f.ping_numbers.size(), 1u);
  EXPECT_EQ(f.ping_numbers[0], 1u);
  EXPECT_EQ(f.pings.counters().get(JsfPingCounter::kUnpairedChannel), 1u);
  EXPECT_EQ(f.pings.counters().get(JsfPingCounter::kOtherChannels), 1u);
  EXPECT_EQ(f.pings.counters().get(JsfPingCounter::kOtherMessages), 1u);
  const sonar::SonarPing& p = f.pings.ping();
  EXPECT_EQ(p.port.size(), 64u);
  EXPECT_FLOAT_EQ(p.port[0], 1.0f);
  EXPECT_FLOAT_EQ(p.stbd[0], 101.0f);
  EXPECT_NEAR(p.altitude_m, 7.5f, 1e-3f);
}

TEST(JsfFramer, RandomlyCorruptedStreamsNeverCrashOrStall) {
  const std::vector<std::uint8_t> good = stream(3, 64);
  std::uint64_t rng = 777;
  auto next = [&rng]() {
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
  };
  int pings = 0;
  for (int it = 0; it < 400; ++it) {
    std::vector<std::uint8_t> s = good;
    const int edits = 1 + static_cast<int>(next() % 8);
    for (int e = 0; e < edits; ++e) s[next() % s.size()] = static_cast<std::uint8_t>(next());
    Feed f(2048);
    const std::size_t chunk = 1 + next() % 50;
    for (std::size_t at = 0; at < s.size(); at += chunk) f.push(Span<const std::uint8_t>(s.data() + at, std::min(chunk, s.size() - at)));
    EXPECT_LE(f.ping_numbers.size(), 3u);
    pings += static_cast<int>(f.ping_numbers.size());
  }
  EXPECT_GT(pings, 0);
}

TEST(JsfFramer, FramingAndAssemblyMakeNoHeapAllocation) {
  const std::vector<std::uint8_t> s = stream(10, 512);
  Feed f;
  f.ping_numbers.reserve(64);  // the test's own record of pings must not count
  QNAV_EXPECT_NO_ALLOC(for (std::size_t at = 0; at < s.size(); at += 1000)
                           f.push(Span<const std::uint8_t>(s.data() + at, std::min<std::size_t>(1000, s.size() - at))));
  EXPECT_EQ(f.ping_numbers.size(), 10u);
}

}  // namespace
}  // namespace qnav::sidescan
