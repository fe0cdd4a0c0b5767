#include "hal/core/serial.hpp"

namespace qnav::hal {
Status validate_serial_config(const SerialConfig& c) noexcept {
  if (c.data_bits < 5 || c.data_bits > 8) return Status(StatusCode::kInvalidArgument, "data bits must be 5..8");
  if (c.stop_bits != 1 && c.stop_bits != 2) return Status(StatusCode::kInvalidArgument, "stop bits must be 1 or 2");
  switch (c.baud) {
    case 1200: case 2400: case 4800: case 9600: case 19200: case 38400: case 57600: case 115200:
    case 230400: case 460800: case 500000: case 576000: case 921600: case 1000000: case 1500000:
    case 2000000: case 3000000: case 4000000:
      return Status::ok();
    default:
      return Status(StatusCode::kUnsupported, "baud rate not supported");
  }
}
}  // namespace qnav::hal
