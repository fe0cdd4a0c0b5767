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
//   nav thread (SCHED_FIFO daemon.nav_priority, CPU daemon.nav_cpu)
//     mode commands, dead reckoning, ping -> tile -> teach append | repeat update,
//     stereo pair -> visual odometry (Mode = Vo), downward frame -> mapper (Mode = Map) -> outputs, health
//   main thread: signals, sd_notify READY / WATCHDOG (on the nav worker's progress) / STOPPING.
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

struct Deployment {
  static constexpr std::size_t kThreads = 2, kQueues = 7, kStages = 10;
  ThreadSpec threads[kThreads];
  QueueSpec queues[kQueues];
  StageSpec stages[kStages];
  std::size_t ping_pool_bytes = 0;     // sonar.ping_queue x 2 x sonar.max_samples_per_side floats
  std::size_t queue_bytes = 0;         // all queue storage
  std::size_t tile_pipeline_bytes = 0; // corrector + tile builder + feature extractor arenas
  std::size_t localiser_bytes = 0;     // RouteLocaliser arena for route.max_nodes
  std::size_t route_meta_bytes = 0;    // per-node metadata of the loaded route (route.max_nodes)
  std::size_t frame_pool_bytes = 0;    // frame_pool_slots x frame_slot_bytes (config.hpp; 0 when vo and map are disabled)
  std::size_t vo_bytes = 0;            // StereoVo arena for vo.width x vo.height and vo.max_corners
  std::size_t map_bytes = 0;           // TopoMapper arena for map.width x map.height and map.max_nodes (0 when map.enabled = false)
  std::size_t total_static_bytes() const noexcept {
    return ping_pool_bytes + queue_bytes + tile_pipeline_bytes + localiser_bytes + route_meta_bytes + frame_pool_bytes + vo_bytes + map_bytes;
  }
};

Deployment make_deployment(const DaemonConfig& c);
std::string deployment_text(const Deployment& d);

// Stage indices (Deployment::stages order), for budget accounting.
enum class Stage : std::uint8_t { kCanRx, kDvlRx, kSonarRx, kInputs, kModes, kPing, kTile, kVo, kMap, kOutputs, kCount };

}  // namespace qnav::daemon
