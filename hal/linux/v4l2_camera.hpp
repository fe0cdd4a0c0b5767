// V4l2Camera: Camera over a V4L2 capture device with mmap streaming (a real sensor, a UVC camera or
// the vivid test driver). open(): QUERYCAP (needs VIDEO_CAPTURE + STREAMING), S_FMT with the config's
// size and GREY/YUYV and reads back what the driver chose (a different size or format is rejected:
// the pipeline is sized at init), REQBUFS(MMAP, n) (the driver may grant fewer, at least 2 accepted),
// QUERYBUF + mmap each buffer, QBUF all, STREAMON. All mapping happens in open(); capture() only
// polls, DQBUF, converts to grey into the caller's view and QBUFs the buffer back.
// Stamps: the buffer timestamp when the driver says it is CLOCK_MONOTONIC, otherwise the DQBUF time.
// Sequence gaps count `dropped`, V4L2_BUF_FLAG_ERROR counts `corrupt`. close(): STREAMOFF, munmap.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hal/core/camera.hpp"

namespace qnav::hal {

class V4l2Camera final : public Camera {
 public:
  static constexpr int kMaxBuffers = 16;
  V4l2Camera() noexcept = default;
  ~V4l2Camera() override;
  V4l2Camera(const V4l2Camera&) = delete;
  V4l2Camera& operator=(const V4l2Camera&) = delete;

  Status open(const CameraConfig& config) noexcept;
  void close() noexcept;
  int fd() const noexcept { return fd_; }
  int buffer_count() const noexcept { return n_buffers_; }

  CameraFormat format() const noexcept override { return format_; }
  Result<CameraFrameInfo> capture(ImageView<std::uint8_t> gray_out, int timeout_ms) noexcept override;
  CameraStats stats() const noexcept override { return stats_; }

 private:
  struct Mapping {
    void* start = nullptr;
    std::size_t length = 0;
  };
  int fd_ = -1;
  bool streaming_ = false;
  CameraFormat format_;
  Mapping buffers_[kMaxBuffers];
  int n_buffers_ = 0;
  bool have_sequence_ = false;
  std::uint32_t last_sequence_ = 0;
  CameraStats stats_;
};

}  // namespace qnav::hal
