// DvlSerialDriver over the in-process serial pipe: byte-level framing, queueing, commands, no heap.
#include "drivers/dvl/dvl_driver.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "hal/sim/manual_clock.hpp"
#include "hal/sim/sim_serial.hpp"
#include "recorded.hpp"
#include "test/support/alloc_guard.hpp"

using namespace qnav;
using namespace qnav::drivers::dvl;

namespace {
void send(hal::SerialPort& port, const std::string& s) {
  auto w = port.write(Span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(s.data()), s.size()));
  ASSERT_TRUE(w.is_ok());
  ASSERT_EQ(w.value(), s.size());
}
}  // namespace

TEST(DvlSerialDriver, WaterLinkedStreamSplitAcrossReads) {
  hal::ManualClock clock(2000000000);
  hal::SimSerialPipe pipe(clock);
  DvlSerialDriver drv(pipe.b(), DvlProtocol::kWaterLinked);
  std::string stream;
  for (const char* s : qnav_test::kWlWru) stream += std::string(s) + "\r\n";
  stream += std::string(qnav_test::kWlWrz) + "\r\n";
  stream += std::string(qnav_test::kWlWrp[0]) + "\n";
  // First half, then the rest: the velocity line is completed by the second read.
  send(pipe.a(), stream.substr(0, 100));
  Result<int> r = 0;
  QNAV_EXPECT_NO_ALLOC(r = drv.poll(0));
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(r.value(), 0);
  clock.set_ns(3000000000);
  send(pipe.a(), stream.substr(100));
  QNAV_EXPECT_NO_ALLOC(r = drv.poll(0));
  ASSERT_EQ(r.value(), 1);
  DvlVelocity v;
  ASSERT_TRUE(drv.pop(v));
  EXPECT_DOUBLE_EQ(v.vy_mps, -0.4);
  EXPECT_EQ(v.stamp.arrival_ns, 3000000000);
  EXPECT_EQ(drv.lines(), 6u);
  EXPECT_FALSE(drv.pop(v));
}

TEST(DvlSerialDriver, Pd6AndOverlongLines) {
  hal::ManualClock clock(0);
  hal::SimSerialPipe pipe(clock);
  DvlSerialDriver drv(pipe.b(), DvlProtocol::kPd6);
  send(pipe.a(), std::string(400, 'x') + "\r\n" + qnav_test::kPd6Ensemble);
  auto r = drv.poll(0);
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(r.value(), 1);
  EXPECT_EQ(drv.counter(DvlCounter::kLength), 1u);
  DvlVelocity v;
  ASSERT_TRUE(drv.pop(v));
  EXPECT_DOUBLE_EQ(v.altitude_m, 5.32);
}

TEST(DvlSerialDriver, CommandsCarryTheChecksum) {
  hal::ManualClock clock(0);
  hal::SimSerialPipe pipe(clock);
  DvlSerialDriver drv(pipe.b(), DvlProtocol::kWaterLinked);
  ASSERT_TRUE(drv.send_command("wcv").is_ok());
  std::uint8_t buf[32];
  auto r = pipe.a().read(Span<std::uint8_t>(buf, sizeof buf), 0);
  ASSERT_TRUE(r.is_ok());
  const std::string got(reinterpret_cast<char*>(buf), r.value().bytes);
  ASSERT_EQ(got.size(), 7u);
  EXPECT_EQ(got.substr(0, 4), "wcv*");
  EXPECT_EQ(std::stoi(got.substr(4, 2), nullptr, 16), crc8_07(reinterpret_cast<const std::uint8_t*>("wcv"), 3));
  DvlSerialDriver pd6(pipe.b(), DvlProtocol::kPd6);
  EXPECT_EQ(pd6.send_command("wcv"), StatusCode::kUnsupported);
}

// A reader that lags gets several Water Linked reports in one read: they keep the DVL's own spacing
// (time_of_validity, mapped onto our clock by the report read promptly before) instead of sharing the
// read's arrival time, which would make dead reckoning refuse all but the first.
TEST(DvlSerialDriver, WaterLinkedReportsOfOneReadKeepTheirSpacing) {
  hal::ManualClock clock(5000000000);
  hal::SimSerialPipe pipe(clock);
  DvlSerialDriver drv(pipe.b(), DvlProtocol::kWaterLinked);
  char line[240];
  const long long t0_us = 1700000000000000;  // the DVL's clock: validity = transmission - 2 ms
  auto report = [&](int k) {
    const long long tov = t0_us + k * 100000;
    const std::size_t n = wl_velocity_report(1.5, 0.0, 0.0, 10.0, tov, tov + 2000, line, sizeof line);
    EXPECT_GT(n, 0u);
    return std::string(line, n);
  };
  send(pipe.a(), report(0));  // prompt: read 5 ms after its validity
  clock.set_ns(5005000000);
  ASSERT_EQ(drv.poll(0).value(), 1);
  clock.set_ns(5505000000);  // then the reader stalls, and gets reports 1..4 in one read
  send(pipe.a(), report(1) + report(2) + report(3) + report(4));
  ASSERT_EQ(drv.poll(0).value(), 4);
  DvlVelocity v;
  std::int64_t prev = 0;
  for (int k = 0; k <= 4; ++k) {
    ASSERT_TRUE(drv.pop(v));
    EXPECT_LE(v.stamp.sample_ns, v.stamp.arrival_ns - 2000000);  // at least the DVL's stated latency before arrival
    if (k > 0) {
      EXPECT_NEAR(static_cast<double>(v.stamp.sample_ns - prev), 100e6, 0.021e6) << k;
    }
    prev = v.stamp.sample_ns;
  }
}
