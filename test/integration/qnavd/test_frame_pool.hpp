// A FramePool of 4 slots over vectors, as qnavd's daemon sets it up (frame_slot_bytes per slot), and
// read_all (what a source logged to its tmpfile), for the V4L2 frame sources' tests (linux_stereo_test,
// linux_downward_test).
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/messages.hpp"

namespace qnav::daemon {

struct TestFramePool {
  static constexpr std::uint32_t kSlots = 4;
  std::vector<std::uint8_t> pixels;
  std::vector<FrameMsg> msg_store;
  std::vector<std::uint32_t> free_store;
  SpscRing<FrameMsg> frames;
  SpscRing<std::uint32_t> free;
  FramePool view;
  explicit TestFramePool(const DaemonConfig& c) {
    view.slot_bytes = frame_slot_bytes(c);
    pixels.assign(kSlots * view.slot_bytes, 0);
    msg_store.assign(kSlots, FrameMsg{});
    free_store.assign(kSlots, 0);
    EXPECT_TRUE(frames.init(Span<FrameMsg>(msg_store.data(), msg_store.size())));
    EXPECT_TRUE(free.init(Span<std::uint32_t>(free_store.data(), free_store.size())));
    for (std::uint32_t s = 0; s < kSlots; ++s) EXPECT_TRUE(free.try_push(s));
    view.frames = &frames;
    view.free = &free;
    view.pool = pixels.data();
    view.width = c.vo.max_width;
    view.height = c.vo.max_height;
    view.map_width = c.map_width;
    view.map_height = c.map_height;
  }
};

inline std::string read_all(std::FILE* f) {
  std::rewind(f);
  std::string s;
  char buf[512];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) s.append(buf, n);
  return s;
}

}  // namespace qnav::daemon
