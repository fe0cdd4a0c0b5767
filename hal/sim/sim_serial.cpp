#include "hal/sim/sim_serial.hpp"

namespace qnav::hal {

SimSerialPipe::SimSerialPipe(const Clock& clock) noexcept : clock_(clock) {
  a_.pipe_ = this;
  a_.rx_ = &b_to_a_;
  a_.tx_ = &a_to_b_;
  b_.pipe_ = this;
  b_.rx_ = &a_to_b_;
  b_.tx_ = &b_to_a_;
}

Result<SerialRead> SimSerialPipe::End::read(Span<std::uint8_t> buf, int /*timeout_ms*/) noexcept {
  SerialRead r;
  while (r.bytes < buf.size() && rx_->pop(buf[r.bytes]).is_ok()) ++r.bytes;
  r.arrival_ns = pipe_->clock_.now_ns();
  stats_.rx_bytes += static_cast<std::uint32_t>(r.bytes);
  return r;
}

Result<std::size_t> SimSerialPipe::End::write(Span<const std::uint8_t> data) noexcept {
  std::size_t n = 0;
  while (n < data.size() && tx_->push(data[n]).is_ok()) ++n;
  stats_.tx_bytes += static_cast<std::uint32_t>(n);
  if (n < data.size()) ++stats_.tx_short;
  return n;
}

}  // namespace qnav::hal
