#include "drivers/dronecan/ahrs_receiver.hpp"

#include <cmath>

namespace qnav::drivers::dronecan {

const DataTypeSpec DroneCanAhrsReceiver::kTypes[2] = {
    {kSolutionId, kSolutionSignature, kSolutionMaxBytes},
    {kRawImuId, kRawImuSignature, kRawImuMaxBytes},
};

DroneCanAhrsReceiver::DroneCanAhrsReceiver(std::uint8_t node_filter) noexcept
    : reasm_(Span<const DataTypeSpec>(kTypes, 2)), node_filter_(node_filter) {}

namespace {
bool finite3(const float* v, float limit) noexcept {
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(v[i]) || std::fabs(v[i]) > limit) return false;
  return true;
}
}  // namespace

AhrsUpdate DroneCanAhrsReceiver::on_frame(const hal::CanRxFrame& rx) noexcept {
  if (!reasm_.on_frame(rx, transfer_)) return AhrsUpdate::kNone;
  if (node_filter_ != 0 && transfer_.source_node != node_filter_) {
    counters_.increment(AhrsCounter::kOtherNode);
    return AhrsUpdate::kNone;
  }
  const bool tao = !rx.frame.fd;
  if (transfer_.data_type_id == kSolutionId) {
    AhrsSolution s;
    if (!decode_solution(transfer_.payload, transfer_.payload_len, tao, s).is_ok()) {
      counters_.increment(AhrsCounter::kDecode);
      return AhrsUpdate::kNone;
    }
    const float* q = s.orientation_xyzw;
    float n2 = 0;
    bool finite = true;
    for (int i = 0; i < 4; ++i) {
      finite = finite && std::isfinite(q[i]);
      n2 += q[i] * q[i];
    }
    if (!finite || n2 < 0.81f || n2 > 1.21f || !finite3(s.angular_velocity_radps, 35.0f) || !finite3(s.linear_accel_mps2, 1000.0f)) {
      counters_.increment(AhrsCounter::kRange);
      return AhrsUpdate::kNone;
    }
    if (solution_.present && (transfer_.transfer_id == last_tid_solution_ ||
                              (s.timestamp_us != 0 && s.timestamp_us <= solution_.value.timestamp_us))) {
      counters_.increment(AhrsCounter::kStale);
      return AhrsUpdate::kNone;
    }
    last_tid_solution_ = transfer_.transfer_id;
    solution_.value = s;
    solution_.stamp = transfer_.stamp;
    solution_.source_node = transfer_.source_node;
    solution_.present = true;
    ++n_solutions_;
    return AhrsUpdate::kSolution;
  }
  RawImu m;
  if (!decode_raw_imu(transfer_.payload, transfer_.payload_len, tao, m).is_ok()) {
    counters_.increment(AhrsCounter::kDecode);
    return AhrsUpdate::kNone;
  }
  if (!finite3(m.rate_gyro_latest_radps, 35.0f) || !finite3(m.accel_latest_mps2, 1000.0f) ||
      !std::isfinite(m.integration_interval_s) || m.integration_interval_s < 0.0f) {
    counters_.increment(AhrsCounter::kRange);
    return AhrsUpdate::kNone;
  }
  if (raw_.present && (transfer_.transfer_id == last_tid_raw_ || (m.timestamp_us != 0 && m.timestamp_us <= raw_.value.timestamp_us))) {
    counters_.increment(AhrsCounter::kStale);
    return AhrsUpdate::kNone;
  }
  last_tid_raw_ = transfer_.transfer_id;
  raw_.value = m;
  raw_.stamp = transfer_.stamp;
  raw_.source_node = transfer_.source_node;
  raw_.present = true;
  ++n_raw_;
  return AhrsUpdate::kRawImu;
}

}  // namespace qnav::drivers::dronecan
