// The items that cross qnavd's queues (deployment.hpp declares the queues and their depths).
// Ping samples do not travel in the queue: a PingMsg names a slot of the ping pool (floats owned by
// the Daemon, sized from sonar.max_samples_per_side x sonar.ping_queue), and the slot returns to the
// producer through the free-slot queue when the nav worker is done with it.
#pragma once

#include <atomic>
#include <cstdint>

#include "firmware/pipeline/route_tile_pipeline.hpp"
#include "hal/core/stamp.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/spsc_ring.hpp"

namespace qnav::daemon {

struct PingMsg {
  std::uint32_t slot = 0;
  std::uint32_t ping_number = 0;
  std::uint32_t port_samples = 0, stbd_samples = 0;
  float slant_range_m = 0.0f;
  float altitude_m = -1.0f;
  std::uint64_t device_stamp_ns = 0;  // the sonar's own time field, passed on untouched
  hal::SampleStamp stamp;             // monotonic (linux) or simulated (sim) sample time
  bool has_truth = false;             // sim backend: the simulator's truth for evaluation
  pipeline::PingTruth truth;
};

// A stereo pair or a downward frame in the frame pool (bytes owned by the Daemon: frame_pool_slots
// slots of frame_slot_bytes, config.hpp): slot s starts at s * slot_bytes and holds the left image
// with the right one W * H after it, or the downward frame (downward = true); the slot returns
// through the free-frame queue when the nav worker is done with it.
struct FrameMsg {
  std::uint32_t slot = 0;
  std::uint32_t sequence = 0;
  std::uint16_t width = 0, height = 0;
  bool downward = false;               // a downward camera's frame (Mode = Map), not a stereo pair
  hal::SampleStamp stamp;              // the pair's sample time (exposure)
  bool has_truth = false;              // sim backend: the rover's true body pose (NED, from its start)
  Pose3 truth_world_T_body;
  double truth_path_m = 0.0;
};

// The frame pool and its queues as the producers see them.
struct FramePool {
  SpscRing<FrameMsg>* frames = nullptr;
  SpscRing<std::uint32_t>* free = nullptr;
  std::uint8_t* pool = nullptr;
  int width = 0, height = 0;          // a stereo image (vo.width x vo.height)
  int map_width = 0, map_height = 0;  // a downward frame (map.width x map.height)
  std::size_t slot_bytes = 0;         // bytes per slot (frame_slot_bytes)
  std::uint8_t* slot(std::uint32_t s) const noexcept { return pool + static_cast<std::size_t>(s) * slot_bytes; }
};

// MAVLink bytes between the io thread and the nav worker ([mav_rx], [mav_tx]): rx, bytes link `link`
// delivered (its reads of one poll packed into items of at most kMavBytes, MavlinkIo; the
// nav worker's MavlinkEndpoint parses them, one parser per link); tx, one encoded frame, written by
// the io thread to every open link.
constexpr std::size_t kMavBytes = 280;  // drivers/mavlink kMaxFrameBytes
struct MavBytes {
  std::uint16_t len = 0;
  std::uint8_t link = 0;             // 0 UDP client (udp_remote), 1 UDP server (udp_listen_port), 2 serial
  std::int64_t arrival_ns = 0;       // sample clock at reception (mission time on the sim backend)
  std::uint8_t data[kMavBytes] = {};
};

// Counters the I/O thread owns and the nav worker reads for health (relaxed atomics, monotonic).
constexpr std::size_t kDvlQueueCapacity = 64;  // DVL velocities between the I/O and nav threads

struct IoCounters {
  // Inputs as the I/O thread received them (before any drop): the soak's accounting checks
  // pings_in = nav pings + ping_overflow + sim render failures + queued, and the same for DVL and CAN.
  std::atomic<std::uint64_t> pings_in{0};
  std::atomic<std::uint64_t> dvl_in{0};
  std::atomic<std::uint64_t> can_rx_in{0};
  std::atomic<std::uint32_t> faults_injected{0};  // sim backend, sim.fault: damaged samples it sent
  std::atomic<std::uint32_t> sim_late_steps{0};   // sim backend, sim.speed > 0: steps past their deadline by > 10 ms (SimPacer)
  std::atomic<std::uint32_t> sim_max_late_us{0};  // sim backend, sim.speed > 0: the latest step's lateness
  std::atomic<std::uint32_t> can_rx_overflow{0};
  std::atomic<std::uint32_t> can_rx_dropped{0};  // dropped by the bus before qnavd read them (kernel socket queue: SO_RXQ_OVFL)
  std::atomic<std::uint32_t> can_tx_errors{0};
  std::atomic<std::uint32_t> ping_overflow{0};   // a ping arrived with no free slot / full queue: dropped
  std::atomic<std::uint32_t> dvl_overflow{0};
  std::atomic<std::uint32_t> dvl_rejected{0};    // the DVL parser's rejections (checksum, format, stale ...)
  std::atomic<std::uint32_t> sonar_rejected{0};  // the JSF framer's and assembler's rejections
  std::atomic<std::uint32_t> device_errors{0};   // read/open failures of a device (disappeared, EOF)
  std::atomic<std::uint64_t> frames_in{0};         // stereo pairs and downward frames the cameras delivered
  std::atomic<std::uint32_t> frame_overflow{0};    // a pair or frame arrived with no free slot / full queue: dropped
  std::atomic<std::uint32_t> camera_rejected{0};   // the camera drivers' rejections (corrupt, unpaired, timeouts)
  std::atomic<bool> camera_device_down{false};     // the stereo pair (vo.camera = "v4l2")
  std::atomic<bool> downward_device_down{false};   // the downward camera (map.device; FaultCameraLost in Mode = Map)
  std::atomic<bool> leak{false};                   // the leak detector latched (HEALTH.Leak, FaultLeak)
  std::atomic<std::uint32_t> leak_events{0};       // edges to the active level the detector saw
  std::atomic<bool> leak_device_down{false};       // leak.chip set and its line cannot be read
  std::atomic<bool> sonar_device_down{false};
  std::atomic<bool> can_device_down{false};
  std::atomic<bool> dvl_device_down{false};
  std::atomic<std::uint32_t> mav_rx_overflow{0};   // MAVLink bytes dropped: the mav_rx queue was full
  std::atomic<std::uint32_t> mav_tx_errors{0};     // MAVLink frames not written (no peer yet, socket full, port error)
  std::atomic<std::uint32_t> mav_device_errors{0}; // MAVLink link open / read failures (reopened once a second)
};

}  // namespace qnav::daemon
