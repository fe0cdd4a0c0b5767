// Water Linked DVL-A50/A125 serial protocol (protocol 2.6/2.7), output sentences:
//   wrz,vx,vy,vz,valid,altitude,fom,cov(9 x ';'),time_of_validity,time_of_transmission,time,status*xx
//   wru,id,velocity,distance,rssi,nsd*xx        (per transducer; distance -1 = no lock)
//   wrp,time,x,y,z,pos_std,roll,pitch,yaw,status*xx   (dead reckoning)
//   other wr? sentences (wra ACK, wrn NAK, wr! bad checksum, wrv version, ...) pass the checksum and
//   come back as kOther.
// Checksum: CRC-8 (poly 0x07, init 0, no reflection, xorout 0; check("123456789") = 0xF4) over every
// byte before '*', two hex digits (the DVL prints lower case; either case accepted).
// One counter per rejected kind: checksum (missing or wrong *xx), length (line > kMaxWlLine),
// format (wrong field count, bad number, unknown prefix), range (|v| > 10 m/s, altitude/fom < 0,
// transducer id > 3, latency outside 0..1 s), stale (time_of_validity not after the previous one).
// A wrz with valid = n is not rejected: it is returned with bottom_lock = false and counted no_lock.
// Sample time = arrival - (time_of_transmission - time_of_validity): the DVL's own latency.
// Worst case: O(kMaxWlLine) per line; no heap.
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivers/dvl/dvl_types.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/status.hpp"

namespace qnav::drivers::dvl {

constexpr std::size_t kMaxWlLine = 256;

std::uint8_t crc8_07(const std::uint8_t* data, std::size_t n) noexcept;

enum class DvlCounter : std::uint8_t { kChecksum, kLength, kFormat, kRange, kStale, kNoLock, kCount };
inline constexpr const char* kDvlCounterNames[] = {"checksum", "length", "format", "range", "stale", "no_lock"};

enum class WlKind : std::uint8_t { kVelocity, kTransducer, kDeadReckoning, kOther };

struct WlTransducer {
  int id = 0;
  double velocity_mps = 0, distance_m = -1, rssi_dbm = 0, nsd_dbm = 0;
  bool locked = false;
};
struct WlDeadReckoning {
  double time_s = 0, x_m = 0, y_m = 0, z_m = 0, pos_std_m = 0, roll_deg = 0, pitch_deg = 0, yaw_deg = 0;
  int status = 0;
};
struct WlMessage {
  WlKind kind = WlKind::kOther;
  char type = 0;  // the letter after "wr"
  DvlVelocity velocity;
  double covariance[9] = {};
  std::int64_t time_of_transmission_us = 0;
  double time_since_last_ms = 0;
  int status = 0;
  WlTransducer transducer;
  WlDeadReckoning dead_reckoning;
};

// What both DVL parsers (Water Linked here, RDI PD6 in pd6_parser.hpp) share: one counter per
// rejected kind, and reject(), which counts a rejected line and returns its named error.
class DvlLineRejects {
 public:
  const CounterSet<DvlCounter>& counters() const noexcept { return counters_; }

 protected:
  Status reject(DvlCounter c, StatusCode code, const char* msg) noexcept {
    counters_.increment(c);
    return Status(code, msg);
  }
  CounterSet<DvlCounter> counters_{kDvlCounterNames};
};

class WlParser : public DvlLineRejects {
 public:
  // `arrival_ns`: monotonic time the line's last byte was read. ok = `out` is valid.
  Status parse_line(const char* line, std::size_t n, std::int64_t arrival_ns, WlMessage& out) noexcept;

 private:
  bool have_last_ = false;
  std::int64_t last_validity_us_ = 0;
};

// Builds a command or sentence with its checksum: "<body>*xx\n" into out (NUL-terminated); returns
// the length without the NUL, 0 when it does not fit.
std::size_t wl_with_checksum(const char* body, char* out, std::size_t cap) noexcept;
// A velocity report as a simulated DVL sends it: "wrz,vx,vy,vz,y,altitude,0.002,<covariance 1e-5 I>,
// tov,tot,125.00,0*xx\n" (bottom lock, times in us since the epoch; a NaN velocity reads "nan"), with its
// checksum. Returns the length, 0 when it does not fit.
std::size_t wl_velocity_report(double vx_mps, double vy_mps, double vz_mps, double altitude_m, long long tov_us, long long tot_us, char* out,
                               std::size_t cap) noexcept;

}  // namespace qnav::drivers::dvl
