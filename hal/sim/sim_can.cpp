#include "hal/sim/sim_can.hpp"

namespace qnav::hal {

Status SimCanBus::attach(SimCanNetwork& net) noexcept {
  if (net_ != nullptr) return Status(StatusCode::kInvalidArgument, "node already attached");
  QNAV_RETURN_IF_ERROR(net.nodes_.push_back(this));
  net_ = &net;
  return Status::ok();
}

Status SimCanBus::send(const CanFrame& frame) noexcept {
  if (net_ == nullptr) return Status(StatusCode::kNotReady, "node not attached");
  if (frame.error) return Status(StatusCode::kInvalidArgument, "cannot send an error frame");
  if (frame.fd && !fd_) return Status(StatusCode::kUnsupported, "CAN FD not enabled on this node");
  QNAV_RETURN_IF_ERROR(validate_can_frame(frame));
  net_->broadcast(this, frame);
  ++stats_.tx_frames;
  return Status::ok();
}

Status SimCanBus::receive(CanRxFrame& out, int /*timeout_ms*/) noexcept {
  if (rx_.pop(out).is_ok()) return Status::ok();
  return Status(StatusCode::kTimeout, "no frame");
}

void SimCanBus::deliver(const CanFrame& f, std::int64_t t_ns) noexcept {
  if (f.error) {
    if (!errors_on_) return;
    ++stats_.error_frames;
    if (f.id & can_error::kBusOff) ++stats_.bus_off;
  } else {
    if (f.fd && !fd_) return;  // a classic-only socket never sees FD frames
    if (!filters_.empty()) {
      bool any = false;
      for (const CanFilter& flt : filters_) any = any || can_filter_matches(flt, f);
      if (!any) return;
    }
  }
  CanRxFrame rx;
  rx.frame = f;
  rx.stamp.sample_ns = t_ns;
  rx.stamp.arrival_ns = t_ns;
  if (!rx_.push(rx).is_ok()) {
    ++stats_.rx_dropped;
    return;
  }
  ++stats_.rx_frames;
}

void SimCanNetwork::broadcast(const SimCanBus* from, const CanFrame& f) noexcept {
  const std::int64_t t = clock_.now_ns();
  for (SimCanBus* n : nodes_)
    if (n != from) n->deliver(f, t);
}

void SimCanNetwork::inject_error(std::uint32_t class_bits, const std::uint8_t (&data)[8]) noexcept {
  CanFrame f;
  f.error = true;
  f.id = class_bits;
  f.len = 8;
  for (int i = 0; i < 8; ++i) f.data[i] = data[i];
  broadcast(nullptr, f);
}

}  // namespace qnav::hal
