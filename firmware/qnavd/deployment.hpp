// qnavd's deployment table: every thread (priority, CPU), every queue (producer, consumer, depth,
// item size), every stage (thread, rate, time budget in microseconds) and the static memory the
// configuration gives. Read this file and deployment.cpp's table and you know the whole static
// pipeline; `qnavd --print-deployment --config FILE` prints it with the configured sizes.
//
//   io thread  (SCHED_FIFO daemon.io_priority, CPU daemon.io_cpu)
//     waits on the devices, stamps every sample at reception, never blocks on a consumer:
//     CAN rx -> [can_rx]  -> nav         DVL serial -> [dvl] -> nav
//     sonar  -> [pings]   -> nav  (slots of the ping pool; [free_slots] returns them)
//     camera -> [frames]  -> nav  (stereo pairs or downward frames in the frame pool; [free_frames] returns them)
//     nav    -> [can_tx]  -> CAN tx
//     MAVLink UDP / serial -> [mav_rx] -> nav    nav -> [mav_tx] -> MAVLink UDP / serial   (mavlink.enabled)
//   nav thread (SCHED_FIFO daemon.nav_priority, CPU daemon.nav_cpu)
//     mode commands, dead reckoning, ping -> tile -> teach append | repeat update,
//     stereo pair -> visual odometry (Mode = Vo), downward frame -> mapper (Mode = Map) -> outputs, health
//   main thread: signals, sd_notify READY / WATCHDOG (on the nav worker's progress) / STOPPING,
//     drains the io and nav threads' log rings to the log.
//   buffers: every buffer start-up allocates (name, owner, kind, bytes); the kStatic ones are carved
//     from one block (static_memory.hpp) whose size is their sum: the table builds the daemon.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "firmware/qnavd/config.hpp"

namespace qnav::daemon {

struct ThreadSpec {
  const char* name;
  int priority;  // SCHED_FIFO priority when daemon.realtime (else the default policy)
  int cpu;       // -1 = any
  const char* role;
};

struct QueueSpec {
  const char* name;
  const char* producer;
  const char* consumer;
  std::size_t depth;
  std::size_t item_bytes;
  const char* on_full;
};

struct StageSpec {
  const char* name;
  const char* thread;
  const char* trigger;     // what runs it, and how often
  std::uint32_t budget_us; // 0 = not budgeted (I/O waits)
};

// Where a buffer's bytes come from.
enum class BufferKind : std::uint8_t {
  kStatic,  // carved from the one static block (StaticMemory) that start-up allocates from this table
  kOwned,   // allocated at start-up by the component that owns it (a fixed-size member, or its init),
            // with exactly these bytes (the deployment test compares them with the component's own)
  kDevice,  // allocated when its device first opens (a reopen reuses it); may be after start
  kKernel,  // kernel memory the driver maps (V4L2 mmap buffers): not the daemon's heap
};
const char* to_string(BufferKind k) noexcept;

struct BufferSpec {
  const char* name;
  const char* owner;       // the component that uses it
  BufferKind kind;
  std::size_t bytes;       // kStatic: rounded up to kStaticAlign (what StaticMemory hands out)
  const char* what;
};

struct Deployment {
  static constexpr std::size_t kThreads = 3, kQueues = 9, kStages = 10, kMaxBuffers = 32;
  // Static buffer sizes are rounded up to kStaticAlign bytes, and the block is carved in that order at
  // alignof(std::max_align_t): no padding between buffers, so the block is exactly their sum.
  static constexpr std::size_t kStaticAlign = 64;
  ThreadSpec threads[kThreads];
  QueueSpec queues[kQueues];
  StageSpec stages[kStages];
  BufferSpec buffers[kMaxBuffers] = {};
  std::size_t buffer_count = 0;

  // The buffer called `name`, or nullptr.
  const BufferSpec* buffer(const char* name) const noexcept;
  // Bytes of every buffer of one kind; total_static_bytes() is the static block start-up allocates.
  std::size_t bytes(BufferKind k) const noexcept;
  std::size_t total_static_bytes() const noexcept { return bytes(BufferKind::kStatic); }
  // Heap the daemon's buffers take: static + owned + device (kernel memory apart).
  std::size_t total_heap_bytes() const noexcept {
    return bytes(BufferKind::kStatic) + bytes(BufferKind::kOwned) + bytes(BufferKind::kDevice);
  }
};

// The queue storage buffer of queue `name` ("queue.<name>").
const char* queue_buffer_name(const char* queue) noexcept;

// The table for a configuration. The daemon builds itself from it (StaticMemory carves every
// kStatic buffer by name and start-up fails if a carve disagrees), so the printed table is what runs.
Deployment make_deployment(const DaemonConfig& c);
// The repeat localiser's configuration (route.max_nodes applied): what the table sizes and the nav
// worker initialises, from one place.
route::LocaliserConfig repeat_localiser_config(const DaemonConfig& c) noexcept;

// The MAVLink queues' depths (mavlink.enabled; 0 otherwise): at 10 Hz ODOMETRY the nav worker queues
// at most ~6 frames per period; the autopilot's traffic arrives in datagrams of a few frames.
constexpr std::size_t kMavRxQueue = 64, kMavTxQueue = 64;
inline std::size_t mav_rx_depth(const DaemonConfig& c) noexcept { return c.mavlink_enabled ? kMavRxQueue : 0; }
inline std::size_t mav_tx_depth(const DaemonConfig& c) noexcept { return c.mavlink_enabled ? kMavTxQueue : 0; }

// The threads' log rings (hal::LogRing): ring bytes and the stdio line buffer.
constexpr std::size_t kNavLogBytes = 256 * 1024, kIoLogBytes = 64 * 1024, kLogLineBytes = 4096;
std::string deployment_text(const Deployment& d);

// Stage indices (Deployment::stages order), for budget accounting.
enum class Stage : std::uint8_t { kCanRx, kDvlRx, kSonarRx, kInputs, kModes, kPing, kTile, kVo, kMap, kOutputs, kCount };

}  // namespace qnav::daemon
