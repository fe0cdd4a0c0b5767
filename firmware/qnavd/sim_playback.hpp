// SimPlayback: a mission's recorded passes for the sim vehicle (part of SimVehicle, sim_vehicle.hpp;
// driven by the io thread only). A [[sim.pass]] with a file replays a recorded XTF/JSF pass: its pings,
// its navigation (the file's fixes or dead reckoning, sim.replay_nav) as the AHRS heading and DVL
// velocities, its timing (carried on the mission clock, each step kept within 0 < dt <= 2 s).
// Recorded sensor logs (sim_replay.hpp: a candump log, a DVL capture, a stereo sequence in a vo pass)
// replace the simulated AHRS, DVL and rover; a pass's sources play in the order of their own times,
// aligned on the earliest of them kSimPassLeadNs after the pass starts (align), never backwards.
// This class picks the next sample (next, next_recorded); SimVehicle plays it through SimSensors,
// SimCameras and its ping emitter.
// Owns: every recorded pass's file and logs, loaded whole at init (host memory, replay only).
// Memory: no heap after init. Time: O(1) per sample (skipping pings without navigation).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/sim_cameras.hpp"
#include "firmware/qnavd/sim_replay.hpp"
#include "firmware/qnavd/sim_sensors.hpp"
#include "firmware/tools/sonar_file.hpp"

namespace qnav::daemon {

class SimPlayback {
 public:
  enum class Source : std::uint8_t { kNone, kPing, kCan, kDvl, kPair };

  explicit SimPlayback(const DaemonConfig& config) noexcept : cfg_(config) {}
  // At init, for each [[sim.pass]] in order: its recorded sensors (a stereo sequence must fit the
  // frame pool), then its side-scan file (null for a simulated pass).
  Status add_sensors(const SimPass& p, std::size_t index, const SimCameras& cameras);
  Status add_recording(const SimPass& p);

  // The pass `pass` starts: its sources become the current ones.
  void select(std::size_t pass) noexcept;
  bool has_pings() const noexcept { return recording_ != nullptr; }
  bool has_sensors() const noexcept { return rs_ != nullptr; }
  bool has_pairs() const noexcept { return rs_ != nullptr && !rs_->pairs.empty(); }
  bool replays_attitude() const noexcept { return rs_ != nullptr && !rs_->can.empty(); }
  bool replays_dvl() const noexcept { return rs_ != nullptr && !rs_->dvl.empty(); }
  // The pass's range of pings (sim.pass.first_ping / last_ping); an empty range is an error.
  Status start_pings(const SimPass& p);
  // Recorded time -> mission time for the pass starting at now_ns (see above).
  void align(std::int64_t now_ns) noexcept;

  // The source whose next sample is earliest on the mission clock, and its time (kNone: the pass is
  // over). At equal times the navigation goes first: a ping or pair arrives with the navigation of its instant.
  Source next(std::int64_t& t_ns) noexcept;
  const hal::CanFrame& take_can() noexcept { return rs_->can[can_i_++].frame; }
  const ReplayDvlReport& take_dvl() noexcept { return rs_->dvl[dvl_i_++]; }
  const char* dvl_text(const ReplayDvlReport& r) const noexcept { return rs_->dvl_text.data() + r.offset; }
  const tools::StereoFrame& take_pair(std::uint32_t& seq) noexcept {
    seq = static_cast<std::uint32_t>(pair_i_);
    return rs_->pairs[pair_i_++];
  }
  // The next recorded ping with navigation: its time follows the file's from the pass's first sample
  // (pass_start_ns + kSimPassLeadNs) on, after last_sample_ns. False at the end of the range.
  bool next_recorded(SimSample& out, std::int64_t pass_start_ns, std::int64_t last_sample_ns) noexcept;
  // The median slant range of the recorded passes' pings and the distance between tiles
  // (sim.replay_stride pings); false when the mission has no recorded pass.
  bool recorded_geometry(double& range_m, double& spacing_m) const;

 private:
  struct Recording {  // a recorded file's pings and track (loaded at init)
    tools::FileData data;
    tools::NavTrack track;
  };
  // Sample times before this (1973) are relative to their recording's start (a KITTI copy's 10 Hz
  // index), later ones are absolute (ns since the epoch) and shared by a pass's sources.
  static constexpr std::int64_t kEpochFloorNs = 100000000000000000LL;
  std::int64_t replay_time(std::int64_t t) const noexcept { return t + (t >= kEpochFloorNs ? abs_offset_ns_ : rel_offset_ns_); }
  bool peek_recorded(std::int64_t& stamp_ns) noexcept;

  const DaemonConfig& cfg_;
  std::vector<std::unique_ptr<Recording>> recordings_;     // one per [[sim.pass]]; null for a simulated pass
  std::vector<std::unique_ptr<RecordedSensors>> sensors_;  // one per [[sim.pass]]; null without recorded sensors
  const Recording* recording_ = nullptr;                   // the pass being flown
  const RecordedSensors* rs_ = nullptr;
  std::size_t rec_next_ = 0, rec_end_ = 0;
  std::uint64_t rec_prev_stamp_ = 0;
  bool rec_started_ = false;
  std::size_t can_i_ = 0, dvl_i_ = 0, pair_i_ = 0;
  std::int64_t abs_offset_ns_ = 0, rel_offset_ns_ = 0;  // recorded time -> mission time
};

}  // namespace qnav::daemon
