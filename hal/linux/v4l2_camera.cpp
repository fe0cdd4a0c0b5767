#include "hal/linux/v4l2_camera.hpp"

#include <errno.h>
#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstring>

#include "hal/core/pixel.hpp"
#include "hal/linux/device_error.hpp"
#include "hal/linux/monotonic_clock.hpp"

namespace qnav::hal {

namespace {
int xioctl(int fd, unsigned long req, void* arg) noexcept {
  int r;
  int tries = 0;
  do {
    r = ::ioctl(fd, req, arg);
  } while (r < 0 && errno == EINTR && ++tries < 8);
  return r;
}
}  // namespace

V4l2Camera::~V4l2Camera() { close(); }

void V4l2Camera::close() noexcept {
  if (fd_ < 0) return;
  if (streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    (void)xioctl(fd_, VIDIOC_STREAMOFF, &type);
    streaming_ = false;
  }
  for (int i = 0; i < n_buffers_; ++i) {
    if (buffers_[i].start != nullptr) ::munmap(buffers_[i].start, buffers_[i].length);
    buffers_[i] = Mapping{};
  }
  n_buffers_ = 0;
  ::close(fd_);
  fd_ = -1;
}

Status V4l2Camera::open(const CameraConfig& c) noexcept {
  close();
  if (c.device == nullptr) return Status(StatusCode::kInvalidArgument, "camera device missing");
  if (c.buffer_count < 2 || c.buffer_count > kMaxBuffers) return Status(StatusCode::kInvalidArgument, "buffer_count must be 2..16");
  if (c.width <= 0 || c.height <= 0 || c.width > kMaxImageSide || c.height > kMaxImageSide)
    return Status(StatusCode::kInvalidArgument, "camera size out of range");
  fd_ = ::open(c.device, O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    const int e = errno;
    return device_error(e == ENOENT ? StatusCode::kNotFound : StatusCode::kIoError, "cannot open video device", c.device, e,
                        v4l2_open_hint(e));
  }
  v4l2_capability cap{};
  if (xioctl(fd_, VIDIOC_QUERYCAP, &cap) < 0) {
    const int e = errno;
    close();
    return device_error(StatusCode::kUnsupported, "not a V4L2 device (VIDIOC_QUERYCAP failed):", c.device, e,
                        "give a capture node: `v4l2-ctl --list-devices` lists them");
  }
  const std::uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  if (!(caps & V4L2_CAP_VIDEO_CAPTURE) || !(caps & V4L2_CAP_STREAMING)) {
    close();
    return Status(StatusCode::kUnsupported, "device lacks VIDEO_CAPTURE or STREAMING");
  }
  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  fmt.fmt.pix.width = static_cast<std::uint32_t>(c.width);
  fmt.fmt.pix.height = static_cast<std::uint32_t>(c.height);
  fmt.fmt.pix.pixelformat = c.format == PixelFormat::kYuyv ? V4L2_PIX_FMT_YUYV : V4L2_PIX_FMT_GREY;
  fmt.fmt.pix.field = V4L2_FIELD_NONE;
  if (xioctl(fd_, VIDIOC_S_FMT, &fmt) < 0) {
    close();
    return Status(StatusCode::kIoError, "VIDIOC_S_FMT failed");
  }
  const std::uint32_t want = c.format == PixelFormat::kYuyv ? V4L2_PIX_FMT_YUYV : V4L2_PIX_FMT_GREY;
  if (fmt.fmt.pix.pixelformat != want || fmt.fmt.pix.width != static_cast<std::uint32_t>(c.width) ||
      fmt.fmt.pix.height != static_cast<std::uint32_t>(c.height)) {
    close();
    return Status(StatusCode::kUnsupported, "driver chose another size or pixel format");
  }
  format_.width = c.width;
  format_.height = c.height;
  format_.format = c.format;
  format_.bytes_per_line = static_cast<int>(fmt.fmt.pix.bytesperline);
  v4l2_requestbuffers req{};
  req.count = static_cast<std::uint32_t>(c.buffer_count);
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  if (xioctl(fd_, VIDIOC_REQBUFS, &req) < 0) {
    close();
    return Status(StatusCode::kIoError, "VIDIOC_REQBUFS failed");
  }
  if (req.count < 2) {
    close();
    return Status(StatusCode::kCapacityExceeded, "driver granted fewer than 2 buffers");
  }
  const int granted = req.count > static_cast<std::uint32_t>(kMaxBuffers) ? kMaxBuffers : static_cast<int>(req.count);
  for (int i = 0; i < granted; ++i) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = static_cast<std::uint32_t>(i);
    if (xioctl(fd_, VIDIOC_QUERYBUF, &b) < 0) {
      close();
      return Status(StatusCode::kIoError, "VIDIOC_QUERYBUF failed");
    }
    void* p = ::mmap(nullptr, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, b.m.offset);
    if (p == MAP_FAILED) {
      close();
      return Status(StatusCode::kIoError, "mmap of a V4L2 buffer failed");
    }
    buffers_[i].start = p;
    buffers_[i].length = b.length;
    n_buffers_ = i + 1;
    if (xioctl(fd_, VIDIOC_QBUF, &b) < 0) {
      close();
      return Status(StatusCode::kIoError, "VIDIOC_QBUF failed");
    }
  }
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(fd_, VIDIOC_STREAMON, &type) < 0) {
    close();
    return Status(StatusCode::kIoError, "VIDIOC_STREAMON failed");
  }
  streaming_ = true;
  stats_ = CameraStats{};
  have_sequence_ = false;
  return Status::ok();
}

Result<CameraFrameInfo> V4l2Camera::capture(ImageView<std::uint8_t> gray_out, int timeout_ms) noexcept {
  if (fd_ < 0 || !streaming_) return Status(StatusCode::kNotReady, "camera not streaming");
  pollfd p{fd_, POLLIN, 0};
  const int pr = ::poll(&p, 1, timeout_ms < 0 ? 0 : timeout_ms);
  if (pr == 0) {
    ++stats_.timeouts;
    return Status(StatusCode::kTimeout, "no camera frame");
  }
  if (pr < 0) return Status(StatusCode::kIoError, "poll failed");
  v4l2_buffer b{};
  b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.memory = V4L2_MEMORY_MMAP;
  if (xioctl(fd_, VIDIOC_DQBUF, &b) < 0) {
    if (errno == EAGAIN) {
      ++stats_.timeouts;
      return Status(StatusCode::kTimeout, "no camera frame");
    }
    return Status(StatusCode::kIoError, "VIDIOC_DQBUF failed");
  }
  CameraFrameInfo info;
  info.stamp.arrival_ns = monotonic_now_ns();
  info.sequence = b.sequence;
  if ((b.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC) {
    info.stamp.sample_ns = static_cast<std::int64_t>(b.timestamp.tv_sec) * 1000000000LL +
                           static_cast<std::int64_t>(b.timestamp.tv_usec) * 1000LL;
  } else {
    info.stamp.sample_ns = info.stamp.arrival_ns;
  }
  if (have_sequence_ && b.sequence > last_sequence_ + 1) stats_.dropped += b.sequence - last_sequence_ - 1;
  have_sequence_ = true;
  last_sequence_ = b.sequence;
  info.corrupt = (b.flags & V4L2_BUF_FLAG_ERROR) != 0;
  Status conv = Status::ok();
  if (b.index < static_cast<std::uint32_t>(n_buffers_)) {
    conv = convert_to_gray(static_cast<const std::uint8_t*>(buffers_[b.index].start), b.bytesused ? b.bytesused : buffers_[b.index].length,
                           format_, gray_out);
  } else {
    conv = Status(StatusCode::kCorrupt, "driver returned an unknown buffer index");
  }
  if (b.index < static_cast<std::uint32_t>(n_buffers_) && xioctl(fd_, VIDIOC_QBUF, &b) < 0)
    return Status(StatusCode::kIoError, "VIDIOC_QBUF failed");
  QNAV_RETURN_IF_ERROR(conv);
  ++stats_.frames;
  if (info.corrupt) ++stats_.corrupt;
  return info;
}

}  // namespace qnav::hal
