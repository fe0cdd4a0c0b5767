#include "hal/linux/socketcan_bus.hpp"

#include <errno.h>
#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstring>

#include "hal/linux/monotonic_clock.hpp"

namespace qnav::hal {

SocketCanBus::~SocketCanBus() { close(); }

void SocketCanBus::close() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

Status SocketCanBus::open(const SocketCanConfig& c) noexcept {
  close();
  if (c.interface == nullptr || std::strlen(c.interface) >= IFNAMSIZ)
    return Status(StatusCode::kInvalidArgument, "CAN interface name missing or too long");
  const int s = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (s < 0) return Status(StatusCode::kIoError, "socket(PF_CAN) failed");
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, c.interface, IFNAMSIZ - 1);
  if (::ioctl(s, SIOCGIFINDEX, &ifr) < 0) {
    ::close(s);
    return Status(StatusCode::kNotFound, "CAN interface not found");
  }
  const int ifindex = ifr.ifr_ifindex;
  if (c.fd) {
    if (::ioctl(s, SIOCGIFMTU, &ifr) < 0 || ifr.ifr_mtu != CANFD_MTU) {
      ::close(s);
      return Status(StatusCode::kUnsupported, "interface MTU is not CAN FD (72)");
    }
    const int on = 1;
    if (::setsockopt(s, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) < 0) {
      ::close(s);
      return Status(StatusCode::kIoError, "CAN_RAW_FD_FRAMES failed");
    }
  }
  if (!c.receive) {
    if (::setsockopt(s, SOL_CAN_RAW, CAN_RAW_FILTER, nullptr, 0) < 0) {
      ::close(s);
      return Status(StatusCode::kIoError, "CAN_RAW_FILTER (receive nothing) failed");
    }
  } else if (!c.filters.empty()) {
    can_filter kf[16];
    std::size_t n = 0;
    for (const CanFilter& f : c.filters) {
      kf[n].can_id = f.id | (f.extended ? CAN_EFF_FLAG : 0u) | (f.invert ? CAN_INV_FILTER : 0u);
      kf[n].can_mask = f.mask | (f.match_ide_rtr ? (CAN_EFF_FLAG | CAN_RTR_FLAG) : 0u);
      ++n;
    }
    if (::setsockopt(s, SOL_CAN_RAW, CAN_RAW_FILTER, kf, static_cast<socklen_t>(n * sizeof(can_filter))) < 0) {
      ::close(s);
      return Status(StatusCode::kIoError, "CAN_RAW_FILTER failed");
    }
  }
  const can_err_mask_t emask = c.error_mask;
  if (::setsockopt(s, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &emask, sizeof emask) < 0) {
    ::close(s);
    return Status(StatusCode::kIoError, "CAN_RAW_ERR_FILTER failed");
  }
  const int on = 1;
  if (::setsockopt(s, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on) < 0 ||
      ::setsockopt(s, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on) < 0) {
    ::close(s);
    return Status(StatusCode::kIoError, "SO_TIMESTAMPNS / SO_RXQ_OVFL failed");
  }
  if (c.rcvbuf_bytes > 0) {
    (void)::setsockopt(s, SOL_SOCKET, SO_RCVBUF, &c.rcvbuf_bytes, sizeof c.rcvbuf_bytes);
  }
  const int fl = ::fcntl(s, F_GETFL, 0);
  if (fl < 0 || ::fcntl(s, F_SETFL, fl | O_NONBLOCK) < 0) {
    ::close(s);
    return Status(StatusCode::kIoError, "O_NONBLOCK failed");
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifindex;
  if (::bind(s, reinterpret_cast<sockaddr*>(&addr), sizeof addr) < 0) {
    ::close(s);
    return Status(StatusCode::kIoError, "bind(CAN) failed");
  }
  fd_ = s;
  fd_frames_ = c.fd;
  stats_ = CanBusStats{};
  last_drop_count_ = 0;
  return Status::ok();
}

Status SocketCanBus::send(const CanFrame& f) noexcept {
  if (fd_ < 0) return Status(StatusCode::kNotReady, "CAN socket not open");
  if (f.error) return Status(StatusCode::kInvalidArgument, "cannot send an error frame");
  if (f.fd && !fd_frames_) return Status(StatusCode::kUnsupported, "CAN FD not enabled");
  QNAV_RETURN_IF_ERROR(validate_can_frame(f));
  canfd_frame k{};
  k.can_id = f.id | (f.extended ? CAN_EFF_FLAG : 0u) | (f.rtr ? CAN_RTR_FLAG : 0u);
  k.len = f.len;
  if (f.fd) k.flags = static_cast<__u8>((f.brs ? CANFD_BRS : 0) | (f.esi ? CANFD_ESI : 0));
  std::memcpy(k.data, f.data, f.len);
  const std::size_t mtu = f.fd ? CANFD_MTU : CAN_MTU;
  const ssize_t w = ::write(fd_, &k, mtu);
  if (w == static_cast<ssize_t>(mtu)) {
    ++stats_.tx_frames;
    return Status::ok();
  }
  if (w < 0 && (errno == ENOBUFS || errno == EAGAIN || errno == EWOULDBLOCK)) {
    ++stats_.tx_busy;
    return Status(StatusCode::kCapacityExceeded, "CAN TX queue full");
  }
  if (w < 0 && errno == ENETDOWN) return Status(StatusCode::kIoError, "CAN interface down");
  return Status(StatusCode::kIoError, "CAN write failed");
}

Status SocketCanBus::receive(CanRxFrame& out, int timeout_ms) noexcept {
  if (fd_ < 0) return Status(StatusCode::kNotReady, "CAN socket not open");
  pollfd p{fd_, POLLIN, 0};
  const int pr = ::poll(&p, 1, timeout_ms < 0 ? 0 : timeout_ms);
  if (pr == 0) return Status(StatusCode::kTimeout, "no CAN frame");
  if (pr < 0) return errno == EINTR ? Status(StatusCode::kTimeout, "poll interrupted") : Status(StatusCode::kIoError, "poll failed");
  canfd_frame k{};
  iovec iov{&k, sizeof k};
  alignas(cmsghdr) char ctrl[CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(std::uint32_t)) + 64];
  msghdr msg{};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = ctrl;
  msg.msg_controllen = sizeof ctrl;
  const ssize_t r = ::recvmsg(fd_, &msg, MSG_DONTWAIT);
  const std::int64_t arrival = monotonic_now_ns();
  if (r < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK) return Status(StatusCode::kTimeout, "no CAN frame");
    if (errno == ENETDOWN) return Status(StatusCode::kIoError, "CAN interface down");
    return Status(StatusCode::kIoError, "CAN recvmsg failed");
  }
  if (r != CAN_MTU && r != CANFD_MTU) return Status(StatusCode::kCorrupt, "CAN read of unexpected size");
  out = CanRxFrame{};
  out.stamp.arrival_ns = arrival;
  out.stamp.sample_ns = arrival;
  for (cmsghdr* cm = CMSG_FIRSTHDR(&msg); cm != nullptr; cm = CMSG_NXTHDR(&msg, cm)) {
    if (cm->cmsg_level != SOL_SOCKET) continue;
    if (cm->cmsg_type == SO_TIMESTAMPNS) {
      timespec ts;
      std::memcpy(&ts, CMSG_DATA(cm), sizeof ts);
      out.stamp.sample_ns = realtime_to_monotonic_ns(static_cast<std::int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec);
    } else if (cm->cmsg_type == SO_RXQ_OVFL) {
      std::uint32_t drops;
      std::memcpy(&drops, CMSG_DATA(cm), sizeof drops);
      stats_.rx_dropped = drops;  // the kernel's running count for this socket
      last_drop_count_ = drops;
    }
  }
  CanFrame& f = out.frame;
  f.fd = (r == CANFD_MTU);
  if (k.can_id & CAN_ERR_FLAG) {
    f.error = true;
    f.id = k.can_id & CAN_ERR_MASK;
    ++stats_.error_frames;
    if (f.id & CAN_ERR_BUSOFF) ++stats_.bus_off;
  } else {
    f.extended = (k.can_id & CAN_EFF_FLAG) != 0;
    f.rtr = (k.can_id & CAN_RTR_FLAG) != 0;
    f.id = k.can_id & (f.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
  }
  f.len = k.len > (f.fd ? CANFD_MAX_DLEN : CAN_MAX_DLEN) ? static_cast<std::uint8_t>(f.fd ? CANFD_MAX_DLEN : CAN_MAX_DLEN) : k.len;
  if (f.fd) {
    f.brs = (k.flags & CANFD_BRS) != 0;
    f.esi = (k.flags & CANFD_ESI) != 0;
  }
  std::memcpy(f.data, k.data, f.len);
  ++stats_.rx_frames;
  return Status::ok();
}

}  // namespace qnav::hal
