// SensorClockMap: a sensor's own timestamps (a sonar's ping time, on its wall clock) mapped onto the
// monotonic clock, so that samples read in one burst keep their true spacing.
// A stream driver stamps a sample with the time of the read() that completed it. When the reader lags
// (a loaded CPU, a TCP stream that delivers several pings in one segment), every sample in the read
// gets the same arrival time, and all but the first look out of order. The sensor's clock knows the
// spacing; its offset to the monotonic clock is unknown. The map keeps the smallest offset seen,
// offset = min(arrival - sensor): the sample that arrived fastest bounds the transport delay from below
// (passive one-way synchronisation), and sample = sensor + offset <= arrival always. Samples before
// any prompt one (a burst at start-up) still share their arrival time.
//  - Drift: the offset may rise by kDriftPpm of the sensor time elapsed, so a sensor clock running slow
//    against ours is followed.
//  - Steps: a sample that would land more than max_lag_ns before its arrival (the sensor's clock was set,
//    a recorded dive replayed from its start) restarts the map at that sample.
//  - No sensor time (0): sample = arrival.
// O(1), no heap, pure (no OS): the caller passes both times.
#pragma once

#include <cstdint>

namespace qnav::hal {

class SensorClockMap {
 public:
  static constexpr std::int64_t kDriftPpm = 200;

  explicit SensorClockMap(std::int64_t max_lag_ns = 2000000000) noexcept : max_lag_ns_(max_lag_ns) {}

  // The sample time of a sample the sensor stamped sensor_ns (0: none) that arrived at arrival_ns.
  std::int64_t map(std::int64_t sensor_ns, std::int64_t arrival_ns) noexcept {
    if (sensor_ns <= 0) return arrival_ns;
    const std::int64_t d = arrival_ns - sensor_ns;
    if (!have_ || sensor_ns < last_sensor_ns_) {
      restart(d);
    } else {
      const std::int64_t allowance = (sensor_ns - last_sensor_ns_) / 1000000 * kDriftPpm;
      offset_ = offset_ + allowance < d ? offset_ + allowance : d;
      if (d - offset_ > max_lag_ns_) restart(d);
    }
    last_sensor_ns_ = sensor_ns;
    return sensor_ns + offset_;
  }
  std::uint32_t restarts() const noexcept { return restarts_; }

 private:
  void restart(std::int64_t d) noexcept {
    restarts_ += have_ ? 1u : 0u;
    offset_ = d;
    have_ = true;
  }
  std::int64_t max_lag_ns_;
  std::int64_t offset_ = 0;
  std::int64_t last_sensor_ns_ = 0;
  bool have_ = false;
  std::uint32_t restarts_ = 0;
};

}  // namespace qnav::hal
