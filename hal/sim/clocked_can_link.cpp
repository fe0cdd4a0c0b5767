#include "hal/sim/clocked_can_link.hpp"

#include <cstring>

namespace qnav::hal {

bool ClockedCanNode::same(const CanFrame& a, const CanFrame& b) noexcept {
  return a.id == b.id && a.extended == b.extended && a.rtr == b.rtr && a.fd == b.fd && a.error == b.error && a.len == b.len &&
         std::memcmp(a.data, b.data, a.len) == 0;
}

Status ClockedCanNode::send(const CanFrame& frame) noexcept {
  if (peer_ != nullptr && peer_->expected_.full()) return Status(StatusCode::kCapacityExceeded, "too many frames in flight to the peer");
  QNAV_RETURN_IF_ERROR(bus_.send(frame));
  if (peer_ != nullptr) {
    Expected e;
    e.frame = frame;
    e.mission_ns = mission_.now_ns();
    e.wall_ns = wall_.now_ns();
    static_cast<void>(peer_->expected_.push(e));  // room checked above
  }
  return Status::ok();
}

Status ClockedCanNode::receive(CanRxFrame& out, int timeout_ms) noexcept {
  QNAV_RETURN_IF_ERROR(bus_.receive(out, timeout_ms));
  // The peer's frame: its send time. One a later frame overtook is lost (the kernel dropped it).
  for (std::size_t i = 0; i < expected_.size(); ++i) {
    if (!same(expected_.at(i)->frame, out.frame)) continue;
    Expected e;
    for (std::size_t k = 0; k <= i; ++k) static_cast<void>(expected_.pop(e));
    lost_ += static_cast<std::uint32_t>(i);
    out.stamp.sample_ns = out.stamp.arrival_ns = e.mission_ns;
    return Status::ok();
  }
  ++foreign_;
  out.stamp.sample_ns = out.stamp.arrival_ns = mission_.now_ns();
  return Status::ok();
}

std::size_t ClockedCanNode::in_flight() noexcept {
  const std::int64_t now = wall_.now_ns();
  Expected e;
  while (!expected_.empty() && now - expected_.at(0)->wall_ns > kLostAfterNs) {
    static_cast<void>(expected_.pop(e));
    ++lost_;
  }
  return expected_.size();
}

}  // namespace qnav::hal
