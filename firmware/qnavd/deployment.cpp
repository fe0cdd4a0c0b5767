#include "firmware/qnavd/deployment.hpp"

#include <cstdio>

#include "drivers/dvl/dvl_types.hpp"
#include "firmware/qnavd/messages.hpp"
#include "hal/core/can.hpp"
#include "nav/route/route_localiser.hpp"
#include "nav/vo/stereo_vo.hpp"

namespace qnav::daemon {

Deployment make_deployment(const DaemonConfig& c) {
  const std::size_t periodic_budget_us = 500;
  Deployment d{
      {{"io", c.io_priority, c.io_cpu, "devices: wait, read, stamp at reception, push; CAN tx"},
       {"nav", c.nav_priority, c.nav_cpu, "modes, dead reckoning, route pipeline, visual odometry, outputs, health"}},
      {{"can_rx", "io", "nav", c.can_rx_queue, sizeof(hal::CanRxFrame), "drop newest, count can_rx_overflow"},
       {"can_tx", "nav", "io", c.can_tx_queue, sizeof(hal::CanFrame), "not sent now: counted (can_tx_overflow), sent at its next period"},
       {"dvl", "io", "nav", 64, sizeof(drivers::dvl::DvlVelocity), "drop newest, count dvl_overflow"},
       {"pings", "io", "nav", c.ping_queue, sizeof(PingMsg), "drop the ping, count ping_overflow (replay waits instead)"},
       {"free_slots", "nav", "io", c.ping_queue, sizeof(std::uint32_t), "cannot overflow (one entry per slot)"},
       {"frames", "io", "nav", frame_pool_slots(c), sizeof(FrameMsg), "drop the pair / frame, count frame_overflow (the sim waits instead)"},
       {"free_frames", "nav", "io", frame_pool_slots(c), sizeof(std::uint32_t), "cannot overflow (one entry per slot)"}},
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
  d.ping_pool_bytes = c.ping_queue * 2 * c.max_samples_per_side * sizeof(float);
  for (const QueueSpec& q : d.queues) d.queue_bytes += q.depth * q.item_bytes;
  d.tile_pipeline_bytes = sonar::ScanlineCorrector::arena_bytes(c.tiles.corrector) + sonar::TileBuilder::arena_bytes(c.tiles.tiles) +
                          route::TileFeatureExtractor::arena_bytes(c.tiles.features);
  d.localiser_bytes = route::RouteLocaliser::arena_bytes(c.localiser);
  d.route_meta_bytes = c.max_nodes * sizeof(route::NodeMeta);
  d.frame_pool_bytes = frame_pool_slots(c) * frame_slot_bytes(c);
  if (c.vo_enabled) d.vo_bytes = vo::StereoVo::arena_bytes(c.vo);
  if (map_runs(c)) d.map_bytes = pipeline::TopoMapper::arena_bytes(map_mapper_config(c));
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
  std::snprintf(line, sizeof line,
                "static memory\n  ping pool %zu B, queues %zu B, tile pipeline %zu B, localiser %zu B, route metadata %zu B,\n"
                "  frame pool %zu B, visual odometry %zu B (+ its matcher's working set, allocated at start-up), mapper %zu B\n"
                "  total %zu B (%.1f MB), allocated at start-up; no heap allocation after start\n",
                d.ping_pool_bytes, d.queue_bytes, d.tile_pipeline_bytes, d.localiser_bytes, d.route_meta_bytes, d.frame_pool_bytes, d.vo_bytes,
                d.map_bytes, d.total_static_bytes(),
                static_cast<double>(d.total_static_bytes()) / 1e6);
  out += line;
  return out;
}

}  // namespace qnav::daemon
