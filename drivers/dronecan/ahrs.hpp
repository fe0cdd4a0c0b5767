// DSDL decoders/encoders for uavcan.equipment.ahrs.Solution (1000) and RawIMU (1003), UAVCAN v0
// serialization: fields packed in order, multi-byte values little-endian, sub-byte fields MSB-first
// in their byte (void4 then a 4-bit array length share one byte). On classic CAN the last
// variable-length array uses tail array optimisation (no length prefix; length = remaining bytes).
// CAN FD transfers (no TAO) are not supported yet: tao = false returns kUnsupported / 0.
// Signatures are those of the dronecan_dsdlc generator.
// decode_*(): kTruncated (payload ends inside a field), kCorrupt (array length above its DSDL bound,
// or bytes left over). O(payload), no heap.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/status.hpp"

namespace qnav::drivers::dronecan {

constexpr std::uint16_t kSolutionId = 1000;
constexpr std::uint64_t kSolutionSignature = 0x72A63A3C6F41FA9BULL;
constexpr std::size_t kSolutionMaxBytes = 84;
constexpr std::uint16_t kRawImuId = 1003;
constexpr std::uint64_t kRawImuSignature = 0x8280632C40E574B5ULL;
constexpr std::size_t kRawImuMaxBytes = 120;

struct AhrsSolution {
  std::uint64_t timestamp_us = 0;  // uint56, the sender's clock (0 = unknown)
  float orientation_xyzw[4] = {0, 0, 0, 1};
  std::uint8_t orientation_cov_len = 0;
  float orientation_cov[9] = {};
  float angular_velocity_radps[3] = {};
  std::uint8_t angular_velocity_cov_len = 0;
  float angular_velocity_cov[9] = {};
  float linear_accel_mps2[3] = {};
  std::uint8_t linear_accel_cov_len = 0;
  float linear_accel_cov[9] = {};
};

struct RawImu {
  std::uint64_t timestamp_us = 0;
  float integration_interval_s = 0;
  float rate_gyro_latest_radps[3] = {};
  float rate_gyro_integral_rad[3] = {};
  float accel_latest_mps2[3] = {};
  float accel_integral_mps[3] = {};
  std::uint8_t covariance_len = 0;
  float covariance[36] = {};
};

Status decode_solution(const std::uint8_t* p, std::size_t n, bool tao, AhrsSolution& out) noexcept;
Status decode_raw_imu(const std::uint8_t* p, std::size_t n, bool tao, RawImu& out) noexcept;
// Encoders return the payload length (0 when `cap` is too small or an array length is too large).
std::size_t encode_solution(const AhrsSolution& m, bool tao, std::uint8_t* out, std::size_t cap) noexcept;
std::size_t encode_raw_imu(const RawImu& m, bool tao, std::uint8_t* out, std::size_t cap) noexcept;

}  // namespace qnav::drivers::dronecan
