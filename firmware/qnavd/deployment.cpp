#include "firmware/qnavd/deployment.hpp"

#include <cstdio>
#include <cstring>

#include "drivers/camera/stereo_pairer.hpp"
#include "drivers/dvl/dvl_driver.hpp"
#include "drivers/dvl/dvl_types.hpp"
#include "drivers/route_store/route_file.hpp"
#include "drivers/camera/stereo_camera.hpp"
#include "drivers/sidescan/jsf_framer.hpp"
#include "drivers/sonar_stream/jsf_stream_driver.hpp"
#include "firmware/pipeline/route_experiences.hpp"
#include "firmware/qnavd/messages.hpp"
#include "hal/core/camera.hpp"
#include "hal/core/can.hpp"
#include "nav/route/route_format.hpp"
#include "nav/route/route_localiser.hpp"
#include "nav/vo/stereo_vo.hpp"

namespace qnav::daemon {

namespace {
constexpr std::size_t round_up(std::size_t n, std::size_t a) noexcept { return (n + a - 1) / a * a; }

void add(Deployment& d, const char* name, const char* owner, BufferKind kind, std::size_t bytes, const char* what) noexcept {
  if (bytes == 0 || d.buffer_count >= Deployment::kMaxBuffers) return;  // kMaxBuffers holds every entry below
  if (kind == BufferKind::kStatic) bytes = round_up(bytes, Deployment::kStaticAlign);
  d.buffers[d.buffer_count++] = BufferSpec{name, owner, kind, bytes, what};
}
}  // namespace

const char* to_string(BufferKind k) noexcept {
  switch (k) {
    case BufferKind::kStatic: return "static";
    case BufferKind::kOwned: return "owned";
    case BufferKind::kDevice: return "device";
    case BufferKind::kKernel: return "kernel";
  }
  return "?";
}

const char* queue_buffer_name(const char* queue) noexcept {
  static const char* const kNames[][2] = {{"can_rx", "queue.can_rx"}, {"can_tx", "queue.can_tx"}, {"dvl", "queue.dvl"}, {"pings", "queue.pings"},
                                          {"free_slots", "queue.free_slots"}, {"frames", "queue.frames"}, {"free_frames", "queue.free_frames"},
                                          {"mav_rx", "queue.mav_rx"}, {"mav_tx", "queue.mav_tx"}};
  for (const auto& n : kNames)
    if (std::strcmp(n[0], queue) == 0) return n[1];
  return "queue.?";
}

const BufferSpec* Deployment::buffer(const char* name) const noexcept {
  for (std::size_t i = 0; i < buffer_count; ++i)
    if (std::strcmp(buffers[i].name, name) == 0) return &buffers[i];
  return nullptr;
}

std::size_t Deployment::bytes(BufferKind k) const noexcept {
  std::size_t n = 0;
  for (std::size_t i = 0; i < buffer_count; ++i)
    if (buffers[i].kind == k) n += buffers[i].bytes;
  return n;
}

route::LocaliserConfig repeat_localiser_config(const DaemonConfig& c) noexcept {
  route::LocaliserConfig lc = c.localiser;
  lc.filter.max_nodes = c.max_nodes;
  pipeline::enable_experiences(lc, c.max_experiences);  // a route's experiences are read when it has them
  return lc;
}

Deployment make_deployment(const DaemonConfig& c) {
  const std::size_t periodic_budget_us = 500;
  Deployment d{
      {{"main", 0, -1, "signals, sd_notify READY / WATCHDOG / STOPPING, drains the log rings to the log"},
       {"io", c.io_priority, c.io_cpu, "devices: wait, read, stamp at reception, push; CAN tx"},
       {"nav", c.nav_priority, c.nav_cpu, "modes, dead reckoning, route pipeline, visual odometry, outputs, health"}},
      {{"can_rx", "io", "nav", c.can_rx_queue, sizeof(hal::CanRxFrame), "drop newest, count can_rx_overflow"},
       {"can_tx", "nav", "io", c.can_tx_queue, sizeof(hal::CanFrame), "not sent now: counted (can_tx_overflow), sent at its next period"},
       {"dvl", "io", "nav", kDvlQueueCapacity, sizeof(drivers::dvl::DvlVelocity), "drop newest, count dvl_overflow"},
       {"pings", "io", "nav", c.ping_queue, sizeof(PingMsg), "drop the ping, count ping_overflow (replay waits instead)"},
       {"free_slots", "nav", "io", c.ping_queue, sizeof(std::uint32_t), "cannot overflow (one entry per slot)"},
       {"frames", "io", "nav", frame_pool_slots(c), sizeof(FrameMsg), "drop the pair / frame, count frame_overflow (the sim waits instead)"},
       {"free_frames", "nav", "io", frame_pool_slots(c), sizeof(std::uint32_t), "cannot overflow (one entry per slot)"},
       {"mav_rx", "io", "nav", mav_rx_depth(c), sizeof(MavBytes), "drop the bytes, count mav_rx_overflow (0 when mavlink is off)"},
       {"mav_tx", "nav", "io", mav_tx_depth(c), sizeof(MavBytes), "not sent, counted (mavlink tx_queue_full); the next period sends anew"}},
      {{"can_rx", "io", "per frame (AHRS 50 Hz, mode commands)", 0},
       {"dvl_rx", "io", "per DVL line (8 Hz)", 0},
       {"sonar_rx", "io", "per ping (5-10 Hz)", 0},
       {"inputs", "nav", "every loop: CAN frames and DVL samples queued (decode, dead reckoning)", static_cast<std::uint32_t>(periodic_budget_us)},
       {"modes", "nav", "per accepted MODE_CMD: close / open a route file (fsync, every node's metadata read)", c.mode_budget_us},
       {"ping", "nav", "per ping: scanline correction, tile builder", c.ping_budget_us},
       {"tile", "nav", "per tile (every route.scanline_stride pings): features, teach append or repeat update", c.tile_budget_us},
       {"vo", "nav", "per stereo pair in Mode = Vo: Harris, stereo, matching, motion, track refinement", c.vo_budget_us},
       {"map", "nav", "per downward frame in Mode = Map: homography chain, topological map, map file rewrite after a new node", c.map_budget_us},
       {"outputs", "nav", "every loop: CAN outputs at their DBC periods, health at daemon.health_period_s",
        static_cast<std::uint32_t>(periodic_budget_us)}}};
  const bool linux_backend = c.backend == Backend::kLinux;
  // Static: one block, carved by name at start-up (Daemon::init_pipeline, NavWorker::init).
  add(d, "ping_pool", "io -> nav", BufferKind::kStatic, c.ping_queue * 2 * c.max_samples_per_side * sizeof(float),
      "sonar.ping_queue slots x 2 sides x sonar.max_samples_per_side floats");
  for (const QueueSpec& q : d.queues) add(d, queue_buffer_name(q.name), "queue", BufferKind::kStatic, q.depth * q.item_bytes, "depth x item");
  add(d, "frame_pool", "io -> nav", BufferKind::kStatic, frame_pool_slots(c) * frame_slot_bytes(c), "stereo pairs / downward frames (0 when vo and map are off)");
  add(d, "log.nav", "nav thread", BufferKind::kStatic, kNavLogBytes + kLogLineBytes, "the nav thread's log ring + its stdio line buffer");
  add(d, "log.io", "io thread", BufferKind::kStatic, kIoLogBytes + kLogLineBytes, "the io thread's log ring + its stdio line buffer");
  add(d, "tile_pipeline", "nav: RouteTilePipeline", BufferKind::kStatic, pipeline::RouteTilePipeline::arena_bytes(c.tiles),
      "corrector + tile builder + feature extractor arena");
  add(d, "localiser", "nav: RouteRepeater", BufferKind::kStatic, route::RouteLocaliser::arena_bytes(repeat_localiser_config(c)),
      "RouteLocaliser arena for route.max_nodes");
  if (c.vo_enabled) add(d, "vo", "nav: VoOdometry", BufferKind::kStatic, vo::StereoVo::arena_bytes(c.vo), "StereoVo arena for vo.width x vo.height, vo.max_corners");
  if (map_runs(c))
    add(d, "map", "nav: TopoMapper", BufferKind::kStatic, pipeline::TopoMapper::arena_bytes(map_mapper_config(c)),
        "mapper arena for map.width x map.height, map.max_nodes");
  if (map_runs(c) && c.mavlink_enabled)
    add(d, "map_fixes", "nav: NavSource", BufferKind::kStatic, c.map_max_nodes * 2 * sizeof(double),
        "the published position where each map node was created (map.max_nodes): a revisit's fix");
  // Owned: allocated by their components at start-up with exactly these bytes.
  add(d, "route_meta", "nav: route reader", BufferKind::kOwned, c.max_nodes * sizeof(route::NodeMeta), "per-node metadata of the loaded route (route.max_nodes)");
  add(d, "route_records", "nav: route writer + reader", BufferKind::kOwned, 2 * route::record_bytes(route::kMaxKeypointsPerNode),
      "one node record buffer each");
  add(d, "route_experiences", "nav: RouteRepeat", BufferKind::kOwned,
      route::ExperienceIndex::arena_bytes(c.max_nodes, c.max_experiences) + route::ExperienceLearner::arena_bytes() + 256,
      "experience index (route.max_nodes x route.max_experiences) + learner; with two ~10 KB experience buffers and a record buffer");
  add(d, "dvl_driver_queue", "io: DvlSerialDriver", BufferKind::kOwned, sizeof(drivers::dvl::DvlVelocity) * drivers::dvl::DvlSerialDriver::kQueueDepth,
      "velocities parsed in one read, before the dvl queue");
  if (linux_backend) {
    add(d, "jsf_framer", "io: JsfStreamDriver", BufferKind::kOwned, drivers::sonar_stream::JsfStreamConfig{}.max_message_bytes,
        "one JSF message (the framer's reassembly buffer)");
    add(d, "jsf_assembler", "io: JsfStreamDriver", BufferKind::kOwned, 3 * c.max_samples_per_side * sizeof(float), "a ping's port + starboard samples");
  }
  if (c.vo_enabled && linux_backend && c.vo_camera == CameraSource::kV4l2) {
    add(d, "stereo_pairer", "io: StereoCamera", BufferKind::kOwned, sizeof(drivers::camera::StereoPairer), "frames waiting for their other side");
    add(d, "stereo_frame_slots", "io: StereoCamera", BufferKind::kDevice,
        static_cast<std::size_t>(c.vo.max_width) * static_cast<std::size_t>(c.vo.max_height) * static_cast<std::size_t>(drivers::camera::StereoCamera::kSlots) * 2,
        "grey frames of both cameras while they are paired (allocated at the first open)");
    add(d, "stereo_v4l2", "kernel", BufferKind::kKernel,
        2 * static_cast<std::size_t>(hal::CameraConfig{}.buffer_count) * static_cast<std::size_t>(c.vo.max_width) * static_cast<std::size_t>(c.vo.max_height) * 2,
        "mmap buffers of both cameras (YUYV worst case)");
  }
  if (map_runs(c) && linux_backend)
    add(d, "downward_v4l2", "kernel", BufferKind::kKernel,
        static_cast<std::size_t>(hal::CameraConfig{}.buffer_count) * static_cast<std::size_t>(c.map_width) * static_cast<std::size_t>(c.map_height) * 2,
        "mmap buffers of the downward camera (YUYV worst case)");
  return d;
}

std::string deployment_text(const Deployment& d) {
  std::string out;
  char line[512];
  out += "threads\n  name  priority  cpu  role\n";
  for (const ThreadSpec& t : d.threads) {
    std::snprintf(line, sizeof line, "  %-5s %8d  %3d  %s\n", t.name, t.priority, t.cpu, t.role);
    out += line;
  }
  out += "queues (single producer, single consumer)\n  name         from -> to    depth  item B   bytes  when full\n";
  for (const QueueSpec& q : d.queues) {
    std::snprintf(line, sizeof line, "  %-11s  %-4s -> %-4s %6zu %7zu %7zu  %s\n", q.name, q.producer, q.consumer, q.depth, q.item_bytes,
                  q.depth * q.item_bytes, q.on_full);
    out += line;
  }
  out += "stages\n  name      thread  budget us  runs\n";
  for (const StageSpec& s : d.stages) {
    if (s.budget_us)
      std::snprintf(line, sizeof line, "  %-9s %-6s %10u  %s\n", s.name, s.thread, s.budget_us, s.trigger);
    else
      std::snprintf(line, sizeof line, "  %-9s %-6s %10s  %s\n", s.name, s.thread, "-", s.trigger);
    out += line;
  }
  out += "buffers (static: carved from one block at start-up; owned: allocated by their component at start-up;\n"
         "         device: at the device's first open; kernel: mapped by the driver, not the heap)\n"
         "  name                kind         bytes  owner                        what\n";
  for (std::size_t i = 0; i < d.buffer_count; ++i) {
    const BufferSpec& b = d.buffers[i];
    std::snprintf(line, sizeof line, "  %-18s  %-6s %12zu  %-27s  %s\n", b.name, to_string(b.kind), b.bytes, b.owner, b.what);
    out += line;
  }
  std::snprintf(line, sizeof line,
                "static memory\n  static %zu B (one block), owned %zu B, device %zu B, kernel %zu B\n"
                "  total %zu B (%.1f MB) of heap, allocated at start-up (device buffers at first open); no heap allocation after\n"
                "  (+ the visual odometry matcher's working set, allocated at start-up outside the table)\n",
                d.bytes(BufferKind::kStatic), d.bytes(BufferKind::kOwned), d.bytes(BufferKind::kDevice), d.bytes(BufferKind::kKernel),
                d.total_heap_bytes(), static_cast<double>(d.total_heap_bytes()) / 1e6);
  out += line;
  return out;
}

}  // namespace qnav::daemon
