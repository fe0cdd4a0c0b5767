// The simulated dive of `qnav sonar simulate` (a straight survey line north over a seeded seabed with
// one wreck), defined once for the command that writes it to files and for `qnav hil play`'s live
// closed-loop pass, which renders it ping by ping from the vehicle's true pose: the seabed, the
// side-scan, and one ping as the two JSF sonar data messages (message 80, port then starboard,
// positions in mm) the topside would send. Header-only; tool code (allocates).
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "drivers/sidescan/jsf_parser.hpp"
#include "drivers/sidescan/sim_seabed.hpp"
#include "drivers/sidescan/sim_sidescan.hpp"
#include "nav/core/geometry.hpp"

namespace qnav::tools {

inline sidescan::SeabedConfig sim_dive_seabed(double length_m, std::uint64_t seed) {
  sidescan::SeabedConfig bc;
  bc.seed = seed;
  sidescan::SeabedObject wreck;
  wreck.north_m = length_m * 0.3;
  wreck.east_m = 12.0;
  wreck.length_m = 14.0f;
  wreck.width_m = 4.0f;
  wreck.height_m = 2.5f;
  wreck.heading_rad = 0.5f;
  (void)bc.objects.push_back(wreck);
  return bc;
}

// The pass seed drives speckle and navigation noise: two passes over one seabed need their own
// (with one seed their vehicle-fixed speckle would register perfectly at any offset).
inline sidescan::SideScanSimConfig sim_dive_sonar(long samples, double range_m, std::uint64_t pass_seed) {
  sidescan::SideScanSimConfig sc;
  sc.samples_per_side = static_cast<int>(samples);
  sc.slant_range_m = static_cast<float>(range_m);
  sc.seed = pass_seed * 7919u;
  return sc;
}

// One ping as two JSF message-80 records appended to out; nav: the navigation the sonar stamps
// (north/east m, heading). False when a record cannot be encoded.
inline bool append_sim_dive_jsf(std::string& out, std::uint32_t ping, std::uint64_t stamp_ns, double range_m, float altitude_m,
                                const Pose2& nav, const std::vector<float>& port, const std::vector<float>& stbd,
                                std::vector<std::uint8_t>& buf) {
  buf.resize(sidescan::jsf_sonar_message_bytes(port.size() > stbd.size() ? port.size() : stbd.size()));
  for (std::uint8_t ch = 0; ch < 2; ++ch) {
    sidescan::JsfWriteSonar j;
    j.channel = ch;
    j.ping_number = ping;
    j.stamp_ns = stamp_ns;
    const std::size_t samples = ch == 0 ? port.size() : stbd.size();
    j.sample_interval_ns = static_cast<std::uint32_t>(std::lround(2.0 * range_m / 1500.0 / static_cast<double>(samples) * 1e9));
    j.altitude_m = altitude_m;
    j.heading_deg = static_cast<float>(rad_to_deg(nav.heading_rad));
    j.coordinate_units = 1;
    j.y_m = nav.x_m;
    j.x_m = nav.y_m;
    j.samples = ch == 0 ? Span<const float>(port.data(), port.size()) : Span<const float>(stbd.data(), stbd.size());
    j.weighting_factor = 2;  // stored x4 (simulator amplitude ~ 0..16000 -> 16-bit)
    const Result<std::size_t> b = sidescan::encode_jsf_sonar_message(Span<std::uint8_t>(buf.data(), buf.size()), j);
    if (!b) return false;
    out.append(reinterpret_cast<const char*>(buf.data()), b.value());
  }
  return true;
}

}  // namespace qnav::tools
