// DroneCAN AHRS receive: transport rules (tail byte, toggle, transfer CRC seeded with the signature),
// DSDL layout, and the path from candump log lines to a validated attitude with one counter per fault.
#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <cstring>
#include <string>

#include "drivers/dronecan/ahrs_receiver.hpp"
#include "drivers/dronecan/float16.hpp"
#include "hal/core/candump.hpp"
#include "hal/sim/can_log_replay.hpp"
#include "nav/core/crc.hpp"
#include "test/support/alloc_guard.hpp"

using namespace qnav;
using namespace qnav::drivers::dronecan;

TEST(DroneCanCrc, SignatureSeedsMatchTheGeneratedTables) {
  // expected_seed values published next to the signatures in DroneCAN's generated test tables.
  EXPECT_EQ(signature_crc_seed(kSolutionSignature), 0x2055);
  EXPECT_EQ(signature_crc_seed(kRawImuSignature), 0x4E3E);
  EXPECT_EQ(signature_crc_seed(0xD8A7486238EC3AF3ULL), 0x5E37);  // actuator.ArrayCommand
}

TEST(DroneCanFloat16, KnownBitPatternsAndRounding) {
  EXPECT_EQ(half_to_float(0x3C00), 1.0f);
  EXPECT_EQ(half_to_float(0xC000), -2.0f);
  EXPECT_EQ(half_to_float(0x7BFF), 65504.0f);
  EXPECT_EQ(half_to_float(0x0001), std::ldexp(1.0f, -24));
  EXPECT_TRUE(std::isinf(half_to_float(0x7C00)));
  EXPECT_TRUE(std::isnan(half_to_float(0x7E00)));
  EXPECT_EQ(float_to_half(1.0f), 0x3C00);
  EXPECT_EQ(float_to_half(-2.0f), 0xC000);
  EXPECT_EQ(float_to_half(1e6f), 0x7C00);           // overflow -> inf
  EXPECT_EQ(float_to_half(1.0f + 1.0f / 2048), 0x3C00);  // tie rounds to even
  EXPECT_EQ(float_to_half(std::ldexp(1.0f, -24)), 0x0001);
  for (std::uint32_t h = 0; h < 0x7C00; h += 7) EXPECT_EQ(float_to_half(half_to_float(static_cast<std::uint16_t>(h))), h);
}

TEST(DroneCanDsdl, SolutionLayoutByHand) {
  AhrsSolution s;
  s.timestamp_us = 0x00ABCDEF012345ULL;
  s.orientation_xyzw[0] = 0;
  s.orientation_xyzw[1] = 0;
  s.orientation_xyzw[2] = 0;
  s.orientation_xyzw[3] = 1;
  s.orientation_cov_len = 1;
  s.orientation_cov[0] = -2;
  s.angular_velocity_radps[0] = 1;
  s.linear_accel_mps2[2] = -2;
  s.linear_accel_cov_len = 1;
  s.linear_accel_cov[0] = 1;
  std::uint8_t buf[kSolutionMaxBytes];
  const std::size_t n = encode_solution(s, true, buf, sizeof buf);
  const std::uint8_t want[] = {0x45, 0x23, 0x01, 0xEF, 0xCD, 0xAB, 0x00,   // uint56 little-endian
                               0, 0, 0, 0, 0, 0, 0x00, 0x3C,               // x y z w = 1.0
                               0x01, 0x00, 0xC0,                           // void4|len=1, -2.0
                               0x00, 0x3C, 0, 0, 0, 0,                     // angular velocity
                               0x00,                                       // void4|len=0
                               0, 0, 0, 0, 0x00, 0xC0,                     // accel z = -2
                               0x00, 0x3C};                                // TAO covariance [1.0]
  ASSERT_EQ(n, sizeof want);
  EXPECT_EQ(std::memcmp(buf, want, n), 0);
  AhrsSolution d;
  ASSERT_TRUE(decode_solution(want, sizeof want, true, d).is_ok());
  EXPECT_EQ(d.timestamp_us, s.timestamp_us);
  EXPECT_EQ(d.orientation_cov_len, 1);
  EXPECT_EQ(d.orientation_cov[0], -2.0f);
  EXPECT_EQ(d.linear_accel_cov_len, 1);
  EXPECT_EQ(d.linear_accel_mps2[2], -2.0f);
  EXPECT_EQ(decode_solution(want, 20, true, d), StatusCode::kTruncated);
  EXPECT_EQ(decode_solution(want, sizeof want - 1, true, d), StatusCode::kCorrupt);  // odd TAO tail
  std::uint8_t bad[sizeof want];
  std::memcpy(bad, want, sizeof want);
  bad[15] = 0x0A;  // orientation covariance length 10 > 9
  EXPECT_EQ(decode_solution(bad, sizeof bad, true, d), StatusCode::kCorrupt);
}

namespace {
// Turns a transfer into candump log text, one frame per line, 1 ms apart.
std::string to_log(const std::uint8_t* payload, std::size_t n, std::uint64_t sig, std::uint16_t dtid, std::uint8_t node,
                   std::uint8_t tid, std::int64_t& t_us) {
  hal::CanFrame frames[24];
  const std::size_t k = split_transfer(sig, make_message_id(16, dtid, node), tid, payload, n, frames, 24);
  EXPECT_GT(k, 0u);
  std::string out;
  for (std::size_t i = 0; i < k; ++i) {
    hal::CanLogRecord r;
    r.frame = frames[i];
    r.has_time = true;
    r.time_us = t_us;
    std::strcpy(r.interface, "can0");
    t_us += 1000;
    char line[hal::kMaxCanLogLine];
    EXPECT_GT(hal::format_can_log_line(r, line, sizeof line), 0u);
    out += line;
    out += '\n';
  }
  return out;
}
AhrsSolution level_solution(std::uint64_t t_us, float yaw_rad) {
  AhrsSolution s;
  s.timestamp_us = t_us;
  s.orientation_xyzw[0] = 0;
  s.orientation_xyzw[1] = 0;
  s.orientation_xyzw[2] = std::sin(yaw_rad / 2);
  s.orientation_xyzw[3] = std::cos(yaw_rad / 2);
  s.angular_velocity_radps[2] = 0.25f;
  s.linear_accel_mps2[2] = -9.81f;
  return s;
}
std::string solution_log(const AhrsSolution& s, std::uint8_t node, std::uint8_t tid, std::int64_t& t_us) {
  std::uint8_t buf[kSolutionMaxBytes];
  const std::size_t n = encode_solution(s, true, buf, sizeof buf);
  return to_log(buf, n, kSolutionSignature, kSolutionId, node, tid, t_us);
}
int feed(DroneCanAhrsReceiver& rx, const std::string& log) {
  hal::CanLogReplay replay(log.data(), log.size(), 0);
  hal::CanRxFrame f;
  int updates = 0;
  while (replay.receive(f, 0).is_ok())
    if (rx.on_frame(f) != AhrsUpdate::kNone) ++updates;
  return updates;
}
}  // namespace

TEST(DroneCanAhrs, MultiFrameSolutionFromACandumpLog) {
  std::int64_t t = 1700000000000000;
  const std::string log = solution_log(level_solution(5000000, 0.5f), 42, 3, t);
  // 29-byte payload + 2 CRC bytes = 31 bytes -> 5 frames; first tail 0x83, last has EOT.
  EXPECT_EQ(std::count(log.begin(), log.end(), '\n'), 5);
  EXPECT_NE(log.find("(1700000000.000000) can0 1003E82A#"), std::string::npos) << log;
  DroneCanAhrsReceiver rx;
  hal::CanLogReplay replay(log.data(), log.size(), 1000);
  hal::CanRxFrame f;
  int updates = 0;
  QNAV_EXPECT_NO_ALLOC(while (replay.receive(f, 0).is_ok()) {
    if (rx.on_frame(f) == AhrsUpdate::kSolution) ++updates;
  });
  ASSERT_EQ(updates, 1);
  const StampedSolution& s = rx.solution();
  EXPECT_EQ(s.source_node, 42);
  EXPECT_EQ(s.value.timestamp_us, 5000000u);
  EXPECT_NEAR(s.value.orientation_xyzw[2], std::sin(0.25), 1e-3);  // float16: 11-bit mantissa
  EXPECT_NEAR(s.value.orientation_xyzw[3], std::cos(0.25), 1e-3);
  EXPECT_NEAR(s.value.linear_accel_mps2[2], -9.81, 0.01);
  EXPECT_EQ(s.stamp.sample_ns, 1000);                 // first frame
  EXPECT_EQ(s.stamp.arrival_ns, 1000 + 4 * 1000000);  // last frame
  EXPECT_EQ(rx.reassembler().counters().total(), 0u);
}

TEST(DroneCanAhrs, RawImuRoundTripsThroughFrames) {
  RawImu m;
  m.timestamp_us = 77;
  m.integration_interval_s = 0.01f;
  m.rate_gyro_latest_radps[0] = 0.125f;
  m.rate_gyro_integral_rad[1] = 0.0012345f;
  m.accel_latest_mps2[2] = -9.8125f;
  m.accel_integral_mps[2] = -0.098f;
  m.covariance_len = 36;
  for (int i = 0; i < 36; ++i) m.covariance[i] = static_cast<float>(i) * 0.5f;
  std::uint8_t buf[kRawImuMaxBytes];
  const std::size_t n = encode_raw_imu(m, true, buf, sizeof buf);
  ASSERT_EQ(n, 119u);  // 47 fixed bytes + 36 float16
  std::int64_t t = 0;
  DroneCanAhrsReceiver rx;
  ASSERT_EQ(feed(rx, to_log(buf, n, kRawImuSignature, kRawImuId, 9, 0, t)), 1);
  const RawImu& d = rx.raw_imu().value;
  EXPECT_EQ(d.integration_interval_s, 0.01f);  // float32 exact
  EXPECT_EQ(d.rate_gyro_integral_rad[1], 0.0012345f);
  EXPECT_EQ(d.accel_latest_mps2[2], -9.8125f);  // representable in float16
  ASSERT_EQ(d.covariance_len, 36);
  EXPECT_EQ(d.covariance[35], 17.5f);
}

TEST(DroneCanAhrs, EachFaultHasItsCounter) {
  std::int64_t t = 1000000;
  DroneCanAhrsReceiver rx;
  // 1. corrupted payload byte -> transfer CRC mismatch.
  std::string bad_crc = solution_log(level_solution(1000, 0.1f), 42, 1, t);
  const std::size_t hash = bad_crc.find('#', bad_crc.find('\n') + 1);  // second frame
  bad_crc[hash + 1] = bad_crc[hash + 1] == '0' ? '1' : '0';
  EXPECT_EQ(feed(rx, bad_crc), 0);
  EXPECT_EQ(rx.reassembler().counters().get(ReasmCounter::kCrc), 1u);
  // 2. a frame lost in the middle -> toggle error.
  std::string lost = solution_log(level_solution(2000, 0.1f), 42, 2, t);
  const std::size_t l1 = lost.find('\n');
  const std::size_t l2 = lost.find('\n', l1 + 1);
  lost.erase(l1 + 1, l2 - l1);
  EXPECT_EQ(feed(rx, lost), 0);
  EXPECT_EQ(rx.reassembler().counters().get(ReasmCounter::kToggle), 1u);
  // 3. a good one, then the same transfer again -> stale.
  const std::string good = solution_log(level_solution(3000, 0.1f), 42, 3, t);
  EXPECT_EQ(feed(rx, good), 1);
  EXPECT_EQ(feed(rx, good), 0);
  EXPECT_EQ(rx.counters().get(AhrsCounter::kStale), 1u);
  // 4. NaN attitude -> range.
  AhrsSolution nan_q = level_solution(4000, 0.1f);
  nan_q.orientation_xyzw[3] = std::nanf("");
  EXPECT_EQ(feed(rx, solution_log(nan_q, 42, 4, t)), 0);
  EXPECT_EQ(rx.counters().get(AhrsCounter::kRange), 1u);
  // 5. continuation frames without their start -> missed_start.
  std::string tail_only = solution_log(level_solution(5000, 0.1f), 42, 5, t);
  tail_only.erase(0, tail_only.find('\n') + 1);
  EXPECT_EQ(feed(rx, tail_only), 0);
  EXPECT_GE(rx.reassembler().counters().get(ReasmCounter::kMissedStart), 1u);
  // 6. a transfer whose frames are > 2 s apart -> timeout.
  std::string slow = solution_log(level_solution(6000, 0.1f), 42, 6, t);
  std::string slow_log;
  std::size_t pos = 0;
  int i = 0;
  while (pos < slow.size()) {
    const std::size_t e = slow.find('\n', pos);
    std::string line = slow.substr(pos, e - pos);
    hal::CanLogRecord r;
    ASSERT_TRUE(hal::parse_can_log_line(line.data(), line.size(), r).is_ok());
    r.time_us += static_cast<std::int64_t>(i++) * 2500000;
    char buf[hal::kMaxCanLogLine];
    hal::format_can_log_line(r, buf, sizeof buf);
    slow_log += buf;
    slow_log += '\n';
    pos = e + 1;
  }
  EXPECT_EQ(feed(rx, slow_log), 0);
  EXPECT_EQ(rx.reassembler().counters().get(ReasmCounter::kTimeout), 1u);
  // 7. standard-id frames are not DroneCAN.
  EXPECT_EQ(feed(rx, "(1.000000) can0 123#00112233\n"), 0);
  EXPECT_EQ(rx.reassembler().counters().get(ReasmCounter::kNotExtended), 1u);
  // And a clean transfer still goes through afterwards.
  EXPECT_EQ(feed(rx, solution_log(level_solution(9000, 0.2f), 42, 9, t)), 1);
  EXPECT_EQ(rx.solutions(), 2u);
}

TEST(DroneCanAhrs, NodeFilterAndUnknownTypes) {
  std::int64_t t = 0;
  DroneCanAhrsReceiver rx(7);
  EXPECT_EQ(feed(rx, solution_log(level_solution(1, 0), 8, 0, t)), 0);
  EXPECT_EQ(rx.counters().get(AhrsCounter::kOtherNode), 1u);
  const std::uint8_t p[3] = {1, 2, 3};
  EXPECT_EQ(feed(rx, to_log(p, 3, 0, 341, 7, 0, t)), 0);  // NodeStatus-like id: ignored, not an error
  EXPECT_EQ(rx.reassembler().ignored_frames(), 1u);
  EXPECT_EQ(rx.reassembler().counters().total(), 0u);
}
