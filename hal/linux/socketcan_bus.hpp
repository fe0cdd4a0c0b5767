// SocketCanBus: CanBus over a Linux CAN_RAW socket bound to one interface (can0, vcan0, ...).
// open(): socket, optional CAN FD (checks the interface MTU), acceptance filters (from the config,
// installed before bind), error-frame mask, SO_TIMESTAMPNS (kernel RX time, converted to the
// monotonic clock), SO_RXQ_OVFL (kernel drop counter), SO_RCVBUF, O_NONBLOCK, bind.
// receive(): poll() up to timeout_ms then one recvmsg(MSG_DONTWAIT); kTimeout when nothing came.
// send(): non-blocking write; ENOBUFS/EAGAIN = kCapacityExceeded (TX queue full, "not now").
// ENETDOWN = kIoError (interface down). No heap after open(). Works against vcan0 for the bench.
#pragma once

#include <cstdint>

#include "hal/core/can.hpp"
#include "nav/core/fixed_vector.hpp"

namespace qnav::hal {

struct SocketCanConfig {
  const char* interface = "can0";
  FixedVector<CanFilter, 16> filters;  // empty = receive everything
  bool receive = true;                 // false: a sender only (no filter at all: the kernel queues nothing for it)
  bool fd = false;
  std::uint32_t error_mask = can_error::kTxTimeout | can_error::kController | can_error::kBusOff |
                             can_error::kRestarted | can_error::kNoAck | can_error::kProtocol;
  int rcvbuf_bytes = 0;  // 0 = kernel default
};

class SocketCanBus final : public CanBus {
 public:
  SocketCanBus() noexcept = default;
  ~SocketCanBus() override;
  SocketCanBus(const SocketCanBus&) = delete;
  SocketCanBus& operator=(const SocketCanBus&) = delete;

  Status open(const SocketCanConfig& config) noexcept;
  void close() noexcept;
  bool is_open() const noexcept { return fd_ >= 0; }
  int fd() const noexcept { return fd_; }  // for the daemon's poll() set

  Status send(const CanFrame& frame) noexcept override;
  Status receive(CanRxFrame& out, int timeout_ms) noexcept override;
  CanBusStats stats() const noexcept override { return stats_; }

 private:
  int fd_ = -1;
  bool fd_frames_ = false;
  std::uint32_t last_drop_count_ = 0;
  CanBusStats stats_;
};

}  // namespace qnav::hal
