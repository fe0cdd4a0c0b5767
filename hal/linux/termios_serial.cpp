#include "hal/linux/termios_serial.hpp"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include "hal/linux/monotonic_clock.hpp"

namespace qnav::hal {

namespace {
speed_t to_speed(std::uint32_t baud) noexcept {
  switch (baud) {
    case 1200: return B1200;
    case 2400: return B2400;
    case 4800: return B4800;
    case 9600: return B9600;
    case 19200: return B19200;
    case 38400: return B38400;
    case 57600: return B57600;
    case 115200: return B115200;
    case 230400: return B230400;
    case 460800: return B460800;
    case 500000: return B500000;
    case 576000: return B576000;
    case 921600: return B921600;
    case 1000000: return B1000000;
    case 1500000: return B1500000;
    case 2000000: return B2000000;
    case 3000000: return B3000000;
    case 4000000: return B4000000;
    default: return B0;
  }
}
}  // namespace

Status build_termios(const SerialConfig& c, termios& t) noexcept {
  QNAV_RETURN_IF_ERROR(validate_serial_config(c));
  ::cfmakeraw(&t);
  t.c_cflag &= ~static_cast<tcflag_t>(CSIZE | PARENB | PARODD | CSTOPB | CRTSCTS);
  switch (c.data_bits) {
    case 5: t.c_cflag |= CS5; break;
    case 6: t.c_cflag |= CS6; break;
    case 7: t.c_cflag |= CS7; break;
    default: t.c_cflag |= CS8; break;
  }
  if (c.parity != Parity::kNone) {
    t.c_cflag |= PARENB;
    if (c.parity == Parity::kOdd) t.c_cflag |= PARODD;
    t.c_iflag |= INPCK;
  }
  if (c.stop_bits == 2) t.c_cflag |= CSTOPB;
  if (c.hw_flow_control) t.c_cflag |= CRTSCTS;
  t.c_cflag |= CLOCAL | CREAD;
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 0;
  const speed_t sp = to_speed(c.baud);
  if (sp == B0 || ::cfsetispeed(&t, sp) < 0 || ::cfsetospeed(&t, sp) < 0) return Status(StatusCode::kUnsupported, "baud rate");
  return Status::ok();
}

TermiosSerialPort::~TermiosSerialPort() { close(); }

void TermiosSerialPort::close() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

Status TermiosSerialPort::open(const char* path, const SerialConfig& c) noexcept {
  close();
  if (path == nullptr) return Status(StatusCode::kInvalidArgument, "serial path missing");
  QNAV_RETURN_IF_ERROR(validate_serial_config(c));
  const int fd = ::open(path, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return Status(errno == ENOENT ? StatusCode::kNotFound : StatusCode::kIoError, "cannot open serial device");
  termios t{};
  if (::tcgetattr(fd, &t) < 0) {
    ::close(fd);
    return Status(StatusCode::kIoError, "not a tty (tcgetattr failed)");
  }
  if (!build_termios(c, t).is_ok() || ::tcsetattr(fd, TCSANOW, &t) < 0) {
    ::close(fd);
    return Status(StatusCode::kIoError, "tcsetattr failed");
  }
  ::tcflush(fd, TCIFLUSH);
  fd_ = fd;
  stats_ = SerialStats{};
  return Status::ok();
}

Result<SerialRead> TermiosSerialPort::read(Span<std::uint8_t> buf, int timeout_ms) noexcept {
  if (fd_ < 0) return Status(StatusCode::kNotReady, "serial port not open");
  SerialRead r;
  if (buf.empty()) return r;
  pollfd p{fd_, POLLIN, 0};
  const int pr = ::poll(&p, 1, timeout_ms < 0 ? 0 : timeout_ms);
  if (pr < 0) {
    if (errno == EINTR) return r;
    return Status(StatusCode::kIoError, "poll failed");
  }
  if (pr == 0) return r;
  if (p.revents & (POLLERR | POLLNVAL)) return Status(StatusCode::kIoError, "serial device error");
  const ssize_t n = ::read(fd_, buf.data(), buf.size());
  r.arrival_ns = monotonic_now_ns();
  if (n < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return SerialRead{};
    ++stats_.rx_errors;
    return Status(StatusCode::kIoError, "serial read failed");
  }
  if (n == 0 && (p.revents & POLLHUP)) return Status(StatusCode::kIoError, "serial peer hung up");
  r.bytes = static_cast<std::size_t>(n);
  stats_.rx_bytes += static_cast<std::uint32_t>(n);
  return r;
}

Result<std::size_t> TermiosSerialPort::write(Span<const std::uint8_t> data) noexcept {
  if (fd_ < 0) return Status(StatusCode::kNotReady, "serial port not open");
  if (data.empty()) return std::size_t{0};
  const ssize_t n = ::write(fd_, data.data(), data.size());
  if (n < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) {
      ++stats_.tx_short;
      return std::size_t{0};
    }
    return Status(StatusCode::kIoError, "serial write failed");
  }
  if (static_cast<std::size_t>(n) < data.size()) ++stats_.tx_short;
  stats_.tx_bytes += static_cast<std::uint32_t>(n);
  return static_cast<std::size_t>(n);
}

}  // namespace qnav::hal
