// SampleStamp: the two times every sample in qnav carries, both on the monotonic clock (ns).
//  - sample_ns:  when the quantity was measured (best estimate: kernel RX time, V4L2 buffer time,
//                GPIO edge time, device-reported latency subtracted).
//  - arrival_ns: when the daemon received it (read() returned).
// nav/ uses sample time only; arrival - sample is the transport latency health telemetry reports.
#pragma once

#include <cstdint>

namespace qnav::hal {

struct SampleStamp {
  std::int64_t sample_ns = 0;
  std::int64_t arrival_ns = 0;
};

}  // namespace qnav::hal
