// SimSonar: the sim vehicle's side-scan (part of SimVehicle, sim_vehicle.hpp; driven by the io thread
// only). It flies a simulated pass over pipeline::SimSurvey (the survey `qnav route eval` uses: the
// pass's trajectory with the dead reckoning of a DVL + compass, its truth) and puts each ping into a
// free slot of the daemon's ping pool: rendered from the true pose, or a recorded ping copied. A
// produced ping is held back (release_ping) until the io thread has queued the navigation of its
// instant. Faults of sim.fault (NaN samples, a damaged range, a stamp in the past) and sim.stall
// ("sonar") are injected here; render failures are counted (sonar_rejected), a full pool too
// (ping_overflow). Truth (along-route, lateral, pose) travels with each ping.
// Owns: the survey (seabed) and the simulator, allocated at init; a pass re-seeds them without
// allocating. Time: one ping render (samples_per_side per side) per produced ping.
#pragma once

#include <cstdint>
#include <memory>

#include "drivers/sidescan/sim_sidescan.hpp"
#include "drivers/sidescan/sim_trajectory.hpp"
#include "firmware/pipeline/sim_survey.hpp"
#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/messages.hpp"
#include "firmware/qnavd/sim_sensors.hpp"
#include "nav/core/spsc_ring.hpp"

namespace qnav::daemon {

class SimSonar {
 public:
  // The survey of sim.length_m and sim.seed, and the simulator sized for it.
  Status init(double length_m, std::uint64_t seed);
  const pipeline::SimSurvey& survey() const noexcept { return *survey_; }
  // A simulated pass (offset, direction of sim.pass, seed); its first ping one ping period after now_ns.
  Status start_pass(const SimPass& p, std::uint64_t seed, std::int64_t now_ns);
  // The altitude of the last simulated pass (the DVL reports it).
  double altitude_m() const noexcept { return pass_cfg_.altitude_m; }
  // The pass's next ping instant; false at the end of its route.
  bool next(SimSample& out) noexcept;
  // The pose the next rendered ping is seen from (a closed-loop pass sets it to the true pose).
  sidescan::TrajectorySample& render_pose() noexcept { return traj_sample_; }
  // The ping of smp (at mission time t) into a free slot of the pool (stride floats per slot), held.
  SimStep emit_ping(const SimSample& smp, std::int64_t t, const SimSensors& sensors, SpscRing<std::uint32_t>& free_slots, float* pool,
                    std::size_t stride, IoCounters& io) noexcept;
  void release_ping(SpscRing<PingMsg>& pings, IoCounters& io) noexcept;
  // Every slot back from the nav worker (the last ping processed, not only popped).
  bool all_slots_back(const SpscRing<std::uint32_t>& free_slots) const noexcept {
    return free_slots.size() + (spare_slot_ >= 0 ? 1u : 0u) >= free_slots.capacity();
  }

 private:
  std::unique_ptr<pipeline::SimSurvey> survey_;
  std::unique_ptr<sidescan::SideScanSimulator> sonar_;
  sidescan::Trajectory traj_;
  sidescan::TrajectoryConfig pass_cfg_;
  sidescan::TrajectorySample traj_sample_{};
  std::int64_t spare_slot_ = -1;  // a slot taken from free_slots but not used (render failed, queue full)
  PingMsg pending_{};
  bool has_pending_ = false;
};

}  // namespace qnav::daemon
