#include "drivers/dvl/dvl_driver.hpp"

#include <cstring>

namespace qnav::drivers::dvl {

std::uint32_t DvlSerialDriver::counter(DvlCounter c) const noexcept {
  const std::uint32_t base = protocol_ == DvlProtocol::kWaterLinked ? wl_.counters().get(c) : pd6_.counters().get(c);
  return c == DvlCounter::kLength ? base + lines_asm_.overlong() : base;
}

void DvlSerialDriver::handle_line(std::int64_t arrival_ns, int& produced) noexcept {
  ++lines_;
  DvlVelocity v;
  bool have = false;
  if (protocol_ == DvlProtocol::kWaterLinked) {
    if (wl_.parse_line(lines_asm_.line(), lines_asm_.size(), arrival_ns, wl_msg_).is_ok() && wl_msg_.kind == WlKind::kVelocity) {
      v = wl_msg_.velocity;
      // The DVL's own clock (time_of_validity) mapped onto ours: reports a lagging reader gets in one
      // read keep their spacing (else all but the first share a time and dead reckoning refuses them).
      v.stamp.sample_ns = clock_.map(v.device_time_us * 1000, v.stamp.sample_ns);
      have = true;
    }
  } else {
    auto r = pd6_.parse_line(lines_asm_.line(), lines_asm_.size(), arrival_ns, pd6_ens_);
    if (r.is_ok() && r.value() == Pd6Result::kEnsemble) {
      v = pd6_ens_.velocity;
      have = true;
    }
  }
  if (!have) return;
  if (queue_.push_overwrite(v)) ++dropped_;
  ++produced;
}

Result<int> DvlSerialDriver::poll(int timeout_ms) noexcept {
  int produced = 0;
  for (int i = 0; i < kMaxReadsPerPoll; ++i) {
    auto r = port_.read(Span<std::uint8_t>(buf_, sizeof buf_), i == 0 ? timeout_ms : 0);
    if (!r.is_ok()) return r.status();
    const std::size_t n = r.value().bytes;
    if (n == 0) break;
    for (std::size_t k = 0; k < n; ++k)
      if (lines_asm_.push(buf_[k])) handle_line(r.value().arrival_ns, produced);
  }
  return produced;
}

Status DvlSerialDriver::send_command(const char* body) noexcept {
  if (protocol_ != DvlProtocol::kWaterLinked) return Status(StatusCode::kUnsupported, "commands are Water Linked only");
  char out[96];
  const std::size_t n = wl_with_checksum(body, out, sizeof out);
  if (n == 0) return Status(StatusCode::kInvalidArgument, "command too long");
  auto w = port_.write(Span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(out), n));
  if (!w.is_ok()) return w.status();
  if (w.value() != n) return Status(StatusCode::kCapacityExceeded, "serial TX accepted a partial command");
  return Status::ok();
}

}  // namespace qnav::drivers::dvl
