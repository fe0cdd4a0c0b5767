// JSF stream through the in-process serial pipe in uneven chunks, with junk between messages.
#include "drivers/sonar_stream/jsf_stream_driver.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "hal/sim/manual_clock.hpp"
#include "hal/sim/sim_serial.hpp"
#include "jsf_stream.hpp"
#include "test/support/alloc_guard.hpp"

using namespace qnav;
using namespace qnav::drivers::sonar_stream;

namespace {
struct Sink {
  std::vector<std::uint32_t> numbers;
  std::vector<float> first_port, first_stbd;
  std::int64_t last_stamp = 0;
  static void on_ping(void* ctx, const sonar::SonarPing& p, const hal::SampleStamp& st) {
    auto* s = static_cast<Sink*>(ctx);
    if (s->numbers.size() < s->numbers.capacity()) {
      s->numbers.push_back(p.ping_number);
      s->first_port.push_back(p.port[3]);
      s->first_stbd.push_back(p.stbd[3]);
    }
    s->last_stamp = st.sample_ns;
  }
};
}  // namespace

TEST(JsfStreamDriver, PingsFromAChunkedStreamWithJunk) {
  const std::vector<std::uint8_t> stream = qnav_test::jsf_stream(12, 500, true);
  ASSERT_FALSE(stream.empty());
  hal::ManualClock clock(5000);
  hal::SimSerialPipe pipe(clock);
  JsfStreamDriver drv;
  JsfStreamConfig cfg;
  cfg.max_samples_per_side = 1024;
  cfg.max_message_bytes = 8192;
  ASSERT_TRUE(drv.init(cfg).is_ok());
  Sink sink;
  sink.numbers.reserve(64);
  sink.first_port.reserve(64);
  sink.first_stbd.reserve(64);
  std::size_t pos = 0;
  int delivered = 0;
  const std::size_t chunks[] = {1, 17, 999, 3000, 7};
  int k = 0;
  qnav::test::AllocationGuard guard;
  while (pos < stream.size()) {
    const std::size_t want = chunks[k++ % 5];
    const std::size_t n = want < stream.size() - pos ? want : stream.size() - pos;
    auto w = pipe.a().write(Span<const std::uint8_t>(stream.data() + pos, n));
    ASSERT_TRUE(w.is_ok());
    pos += w.value();
    auto r = drv.poll(pipe.b(), 0, &Sink::on_ping, &sink);
    ASSERT_TRUE(r.is_ok());
    delivered += r.value();
  }
  EXPECT_EQ(guard.allocations(), 0u) << guard.report();
  EXPECT_EQ(delivered, 12);
  ASSERT_EQ(sink.numbers.size(), 12u);
  for (std::size_t i = 0; i < 12; ++i) {
    EXPECT_EQ(sink.numbers[i], 1000u + i);
    EXPECT_FLOAT_EQ(sink.first_port[i], static_cast<float>(i + 3));
    EXPECT_FLOAT_EQ(sink.first_stbd[i], static_cast<float>(100 + i + 3));
  }
  EXPECT_EQ(sink.last_stamp, 5000);
  EXPECT_EQ(drv.bytes(), stream.size());
  EXPECT_GT(drv.framer_counters().get(sidescan::JsfCounter::kResyncBytes), 0u);  // the junk was skipped and counted
  EXPECT_EQ(drv.framer_counters().get(sidescan::JsfCounter::kMessages), 24u);
}

TEST(JsfStreamDriver, NotInitialisedIsAnError) {
  hal::ManualClock clock(0);
  hal::SimSerialPipe pipe(clock);
  JsfStreamDriver drv;
  EXPECT_EQ(drv.poll(pipe.b(), 0, nullptr, nullptr).status(), StatusCode::kNotReady);
}

// A reader that lags gets several pings in one read: they keep the sonar's spacing (its clock mapped
// onto ours by the delay of the ping read promptly before), none is stamped after its arrival, and
// none shares another's time (the nav worker would drop it as out of order).
TEST(JsfStreamDriver, PingsOfOneReadKeepTheSonarsSpacing) {
  const std::vector<std::uint8_t> stream = qnav_test::jsf_stream(6, 32, false);  // pings 100 ms apart
  ASSERT_FALSE(stream.empty());
  ASSERT_LE(stream.size(), JsfStreamDriver::kChunkBytes);
  hal::ManualClock clock(5000000000);
  hal::SimSerialPipe pipe(clock);
  JsfStreamDriver drv;
  JsfStreamConfig cfg;
  cfg.max_samples_per_side = 32;
  cfg.max_message_bytes = 8192;
  ASSERT_TRUE(drv.init(cfg).is_ok());
  struct Stamps {
    std::vector<hal::SampleStamp> v;
    static void on_ping(void* ctx, const sonar::SonarPing&, const hal::SampleStamp& st) { static_cast<Stamps*>(ctx)->v.push_back(st); }
  } stamps;
  // The first ping read promptly (the map learns the sonar's offset), then the reader stalls for
  // 600 ms and gets the next five in one read.
  const std::size_t one = stream.size() / 6;
  ASSERT_TRUE(pipe.a().write(Span<const std::uint8_t>(stream.data(), one)).is_ok());
  auto r = drv.poll(pipe.b(), 0, &Stamps::on_ping, &stamps);
  ASSERT_TRUE(r.is_ok());
  ASSERT_EQ(r.value(), 1);
  clock.advance_ns(600000000);
  ASSERT_TRUE(pipe.a().write(Span<const std::uint8_t>(stream.data() + one, stream.size() - one)).is_ok());
  r = drv.poll(pipe.b(), 0, &Stamps::on_ping, &stamps);
  ASSERT_TRUE(r.is_ok());
  ASSERT_EQ(r.value(), 5);
  ASSERT_EQ(stamps.v.size(), 6u);
  for (std::size_t i = 0; i < stamps.v.size(); ++i) {
    if (i > 1) {
      EXPECT_EQ(stamps.v[i].arrival_ns, stamps.v[1].arrival_ns);  // one read
    }
    EXPECT_LE(stamps.v[i].sample_ns, stamps.v[i].arrival_ns);
    if (i > 0) {
      EXPECT_NEAR(static_cast<double>(stamps.v[i].sample_ns - stamps.v[i - 1].sample_ns), 100e6, 0.021e6) << i;
    }
  }
}
