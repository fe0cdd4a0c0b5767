// SimCameras: the sim vehicle's cameras, the producer of the daemon's frame pool (part of SimVehicle,
// sim_vehicle.hpp; driven by the io thread only).
//   - a simulated `vo` pass: the rover (SimRover) renders the Mars-yard stereo pair into a free slot
//     at each step, with the body's measured roll, pitch and heading on the AHRS and its wheel
//     odometry as DVL velocities, at the pair's time;
//   - a `map` pass: the next downward frame every kMapFramePeriodNs of mission time, from the pass's
//     folder (sim.pass.images) or rendered from the synthetic seabed loop (`qnav map eval`'s);
//   - a recorded stereo sequence (sim_replay.hpp): the pair SimPlayback says is due, read from disk.
// A frame is held back (release_pair) until the io thread has queued its instant's navigation.
// Unreadable or wrong-size images are counted (camera_rejected), a full pool too (frame_overflow).
// Owns: the rover and the synthetic seabed (built at init), each map pass's file list. Memory: no heap
// per frame for the rover and the synthetic seabed (rendered in place); a file read decodes into a
// temporary image (replay only). Time: one render or one image read per produced frame.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "drivers/downward_sim/seabed_scene.hpp"
#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/messages.hpp"
#include "firmware/qnavd/sim_pacer.hpp"
#include "firmware/qnavd/sim_rover.hpp"
#include "firmware/qnavd/sim_sensors.hpp"
#include "firmware/tools/sequence_reader.hpp"

namespace qnav::daemon {

class SimCameras {
 public:
  SimCameras(SimClock& clock, SimPacer& pacer, SimSensors& sensors) noexcept : clock_(clock), pacer_(pacer), sensors_(sensors) {}
  // The stereo pairs' and downward frames' pool and queues (vo.enabled, map.enabled).
  void set_frame_pool(const FramePool& frames) noexcept { frames_ = frames; }
  const FramePool& pool() const noexcept { return frames_; }
  // At init, for each [[sim.pass]] in order: a map pass's frames (the folder's file names, the first
  // must be map.width x map.height; or the synthetic loop); a simulated vo pass's rover.
  Status add_map_pass(const SimPass& p);
  Status add_rover(const SimPass& p);
  // A recorded stereo sequence's first image must be vo.width x vo.height.
  Status check_stereo(const SimPass& p, const std::string& first_left_path) const;

  void start_map_pass(std::int64_t t0_ns) noexcept { map_next_ = 0, map_t_ns_ = t0_ns; }
  void start_rover(std::uint64_t seed, double length_m, std::int64_t t0_ns) noexcept { rover_->start(seed, length_m, t0_ns); }
  // The pass's next frame; pass_over is set (with kWaiting) when the pass has no more.
  SimStep fly_rover(IoCounters& io, bool& pass_over) noexcept;
  SimStep fly_downward(std::size_t pass, IoCounters& io, bool& pass_over) noexcept;
  // A recorded pair (sequence number seq) at mission time t.
  SimStep replay_pair(const tools::StereoFrame& pf, std::uint32_t seq, std::int64_t t, IoCounters& io) noexcept;
  // A frame is in the queue or no slot is free: the consumer sets the pace.
  bool busy() const noexcept { return frames_.frames->size() >= 1 || (spare_frame_ < 0 && frames_.free->front() == nullptr); }
  // Every slot back from the nav worker (the end of a pass waits for it); true without a pool.
  bool all_slots_back() const noexcept {
    return frames_.free == nullptr || frames_.free->size() + (spare_frame_ >= 0 ? 1u : 0u) >= frames_.free->capacity();
  }
  void release_pair(IoCounters& io) noexcept;

 private:
  static constexpr std::int64_t kMapFramePeriodNs = 200000000;  // downward frames at 5 Hz (the sparus snippet's rate)
  static constexpr int kSeabedFramesPerLap = 90;                 // the loop `qnav map eval` flies
  bool take_frame_slot(std::uint32_t& slot, IoCounters& io) noexcept;
  void hold(const FrameMsg& m) noexcept { pending_pair_ = m, has_pending_pair_ = true; }

  SimClock& clock_;
  SimPacer& pacer_;
  SimSensors& sensors_;
  FramePool frames_;
  std::unique_ptr<SimRover> rover_;  // created at init when the mission has a simulated vo pass
  bool has_held_rover_ = false;
  RoverSample held_rover_{};
  std::vector<std::vector<std::string>> map_files_;  // per pass: its downward frames (map passes), else empty
  std::vector<std::size_t> map_synthetic_;           // per pass: frames of the synthetic seabed loop (0 = none)
  std::unique_ptr<sim::downward::Seabed> seabed_;    // the synthetic seabed (built once at init)
  std::size_t map_next_ = 0;
  std::int64_t map_t_ns_ = 0;
  std::int64_t spare_frame_ = -1;  // a frame slot taken from the free queue but not sent
  FrameMsg pending_pair_{};
  bool has_pending_pair_ = false;
};

}  // namespace qnav::daemon
