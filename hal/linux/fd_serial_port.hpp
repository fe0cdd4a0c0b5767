// FdSerialPort: what the Linux SerialPorts over one file descriptor share (TermiosSerialPort,
// TcpClientPort, UdpPort): the descriptor (-1: closed), its byte counters, and the accessors. The
// derived port opens, closes, reads and writes it. No heap.
#pragma once

#include "hal/core/serial.hpp"

namespace qnav::hal {

class FdSerialPort : public SerialPort {
 public:
  bool is_open() const noexcept { return fd_ >= 0; }
  int fd() const noexcept { return fd_; }
  SerialStats stats() const noexcept override { return stats_; }

 protected:
  FdSerialPort() noexcept = default;
  int fd_ = -1;
  SerialStats stats_;
};

}  // namespace qnav::hal
