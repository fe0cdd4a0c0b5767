// SensorClockMap: a sensor's timestamps onto the monotonic clock by the smallest delay seen.
#include "hal/core/clock_map.hpp"

#include <gtest/gtest.h>

using qnav::hal::SensorClockMap;

namespace {
constexpr std::int64_t kMs = 1000000;
constexpr std::int64_t kSensor0 = 1700000000000000000;  // a sonar's wall clock (ns since the epoch)
}  // namespace

TEST(SensorClockMap, SamplesOfOneBurstKeepTheirSpacing) {
  SensorClockMap m;
  // Pings every 100 ms; the first three arrive 20 ms after their time, then the reader lags and the
  // next three arrive together at one read, 260 ms after the first of them.
  EXPECT_EQ(m.map(kSensor0, 5000 * kMs), 5000 * kMs);
  // 20 ms slower than the first: its offset holds (plus the drift allowance, 200 ppm: 20 us per 100 ms).
  EXPECT_NEAR(static_cast<double>(m.map(kSensor0 + 100 * kMs, 5120 * kMs)), 5100.0 * kMs, 0.021 * kMs);
  EXPECT_EQ(m.map(kSensor0 + 200 * kMs, 5200 * kMs), 5200 * kMs);
  const std::int64_t burst = 5560 * kMs;
  const std::int64_t a = m.map(kSensor0 + 300 * kMs, burst);
  const std::int64_t b = m.map(kSensor0 + 400 * kMs, burst);
  const std::int64_t c = m.map(kSensor0 + 500 * kMs, burst);
  EXPECT_NEAR(static_cast<double>(a), 5300.0 * kMs, 0.1 * kMs);
  EXPECT_NEAR(static_cast<double>(b - a), 100.0 * kMs, 0.021 * kMs);
  EXPECT_NEAR(static_cast<double>(c - b), 100.0 * kMs, 0.021 * kMs);
  EXPECT_LE(c, burst);  // never after its arrival
}

TEST(SensorClockMap, AFasterArrivalLowersTheOffset) {
  SensorClockMap m;
  EXPECT_EQ(m.map(kSensor0, 1000 * kMs), 1000 * kMs);  // offset 1000 ms - sensor
  // 5 ms less delay than the first: the first was late by at least 5 ms.
  EXPECT_EQ(m.map(kSensor0 + 100 * kMs, 1095 * kMs), 1095 * kMs);
  EXPECT_NEAR(static_cast<double>(m.map(kSensor0 + 200 * kMs, 1300 * kMs)), 1195.0 * kMs, 0.021 * kMs);
}

TEST(SensorClockMap, FollowsASlowSensorClockAndRestartsOnSteps) {
  SensorClockMap m;
  // The sensor's clock runs 100 ppm slow against ours: each 100 ms of its time is 100.01 ms of ours.
  std::int64_t arrival = 0;
  for (int k = 0; k <= 10000; ++k) {  // 1000 s
    arrival = 7000 * kMs + static_cast<std::int64_t>(k) * 100010000;
    const std::int64_t t = m.map(kSensor0 + static_cast<std::int64_t>(k) * 100 * kMs, arrival);
    EXPECT_LE(t, arrival);
    if (k == 10000) {
      EXPECT_LT(arrival - t, 1 * kMs);  // followed (200 ppm allowance), not left 100 ms behind
    }
  }
  EXPECT_EQ(m.restarts(), 0u);
  // The sonar's clock set back 10 minutes (a replayed dive, a new fix): the map restarts there.
  EXPECT_EQ(m.map(kSensor0 - 600000 * kMs, arrival + 100 * kMs), arrival + 100 * kMs);
  EXPECT_EQ(m.restarts(), 1u);
  // Set forward by 5 minutes: the first sample's delay would be negative; the smaller offset is taken.
  EXPECT_EQ(m.map(kSensor0 + 300000 * kMs, arrival + 200 * kMs), arrival + 200 * kMs);
  // A sample arriving 3 s late against the map (over max_lag 2 s): a step of our view; restarted.
  const std::int64_t t = m.map(kSensor0 + 300100 * kMs, arrival + 3300 * kMs);
  EXPECT_EQ(t, arrival + 3300 * kMs);
  EXPECT_EQ(m.restarts(), 2u);
}

TEST(SensorClockMap, NoSensorTimeMeansArrival) {
  SensorClockMap m;
  EXPECT_EQ(m.map(0, 123), 123);
  EXPECT_EQ(m.map(-5, 456), 456);
}
