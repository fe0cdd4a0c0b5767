#include "firmware/qnavd/sim_sonar.hpp"

#include <cmath>
#include <cstring>

#include "firmware/tools/sonar_file.hpp"

namespace qnav::daemon {

Status SimSonar::init(double length_m, std::uint64_t seed) {
  survey_ = std::make_unique<pipeline::SimSurvey>();
  QNAV_RETURN_IF_ERROR(survey_->init(length_m, seed));
  sonar_ = std::make_unique<sidescan::SideScanSimulator>();
  return sonar_->init(survey_->sonar, &survey_->seabed);  // sized here; each pass re-seeds it without allocating
}

Status SimSonar::start_pass(const SimPass& p, std::uint64_t seed, std::int64_t now_ns) {
  pass_cfg_ = survey_->pass(p.offset_pct / 100.0 * survey_->swath_m, p.reverse, seed);
  // The first ping one ping period after the last sample between passes (sample times strictly increase).
  pass_cfg_.start_stamp_ns = static_cast<std::uint64_t>(now_ns + static_cast<std::int64_t>(1e9 / pass_cfg_.ping_rate_hz));
  QNAV_RETURN_IF_ERROR(traj_.init(pass_cfg_));
  return sonar_->init(survey_->sonar_for(pass_cfg_.seed), &survey_->seabed);
}

bool SimSonar::next(SimSample& out) noexcept {
  sidescan::TrajectorySample s;
  if (!traj_.next(s)) return false;
  out.t_ns = static_cast<std::int64_t>(s.stamp_ns);
  out.nav = s.nav;
  out.ping_number = s.index;
  out.device_stamp_ns = s.stamp_ns;
  out.altitude_m = s.altitude_m;
  out.has_truth = true;
  out.truth.along_m = s.along_route_m;
  out.truth.pose = s.truth;
  out.truth.lateral_m = pass_cfg_.lateral_offset_m;
  out.recorded = nullptr;
  traj_sample_ = s;
  return true;
}

SimStep SimSonar::emit_ping(const SimSample& smp, std::int64_t t, const SimSensors& sensors, SpscRing<std::uint32_t>& free_slots, float* pool,
                            std::size_t stride, IoCounters& io) noexcept {
  if (sensors.stalled("sonar", t)) return SimStep::kProduced;
  io.pings_in.fetch_add(1, std::memory_order_relaxed);
  std::uint32_t slot = 0;
  if (spare_slot_ >= 0) {
    slot = static_cast<std::uint32_t>(spare_slot_);
    spare_slot_ = -1;
  } else if (!free_slots.try_pop(slot)) {
    io.ping_overflow.fetch_add(1, std::memory_order_relaxed);
    return SimStep::kProduced;
  }
  float* port = pool + static_cast<std::size_t>(slot) * stride;
  float* stbd = port + stride / 2;
  PingMsg m;
  m.slot = slot;
  bool ok = false;
  if (smp.recorded != nullptr) {
    const tools::PingRec& pr = *smp.recorded;
    ok = pr.port.size() <= stride / 2 && pr.stbd.size() <= stride / 2;
    if (ok) {
      std::memcpy(port, pr.port.data(), pr.port.size() * sizeof(float));
      std::memcpy(stbd, pr.stbd.data(), pr.stbd.size() * sizeof(float));
      m.port_samples = static_cast<std::uint32_t>(pr.port.size());
      m.stbd_samples = static_cast<std::uint32_t>(pr.stbd.size());
      m.slant_range_m = pr.ping.slant_range_m;
    }
  } else {
    const std::size_t n = static_cast<std::size_t>(survey_->sonar.samples_per_side);
    ok = n <= stride / 2 &&
         sonar_->ping(traj_sample_.truth, traj_sample_.altitude_m, traj_sample_.index, Span<float>(port, n), Span<float>(stbd, n)).is_ok();
    m.port_samples = m.stbd_samples = static_cast<std::uint32_t>(n);
    m.slant_range_m = survey_->sonar.slant_range_m;
  }
  if (!ok) {
    io.sonar_rejected.fetch_add(1, std::memory_order_relaxed);
    spare_slot_ = slot;  // kept for the next ping (the nav worker is the only producer of free_slots)
    return SimStep::kProduced;
  }
  m.ping_number = smp.ping_number;
  m.altitude_m = smp.altitude_m;
  m.device_stamp_ns = smp.device_stamp_ns;
  m.stamp.sample_ns = m.stamp.arrival_ns = t;
  if (sensors.faulty("sonar_nan", t)) {
    port[m.port_samples / 3] = std::nanf("");
    io.faults_injected.fetch_add(1, std::memory_order_relaxed);
  }
  if (sensors.faulty("sonar_bad_range", t)) {
    m.slant_range_m = 8.8e-38f;  // one flipped exponent bit of 30 m
    io.faults_injected.fetch_add(1, std::memory_order_relaxed);
  }
  if (sensors.faulty("ping_time_back", t)) {
    m.stamp.sample_ns = m.stamp.arrival_ns = t - 3000000000;  // stamped 3 s in the past
    io.faults_injected.fetch_add(1, std::memory_order_relaxed);
  }
  m.has_truth = smp.has_truth;
  m.truth = smp.truth;
  // Held until the I/O thread has queued this instant's attitude frame and DVL sentence
  // (release_ping), as a real sonar's ping arrives with the navigation of its time.
  pending_ = m;
  has_pending_ = true;
  return SimStep::kProduced;
}

void SimSonar::release_ping(SpscRing<PingMsg>& pings, IoCounters& io) noexcept {
  if (!has_pending_) return;
  if (!pings.try_push(pending_)) {
    io.ping_overflow.fetch_add(1, std::memory_order_relaxed);
    spare_slot_ = pending_.slot;  // the slot stays ours (the end of a pass waits for every slot)
  }
  has_pending_ = false;
}

}  // namespace qnav::daemon
