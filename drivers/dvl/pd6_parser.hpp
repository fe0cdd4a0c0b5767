// Teledyne RDI PD6 (ASCII) DVL output, as sent by WorkHorse/Pathfinder DVLs and by Water Linked
// (`wcp,2`). One sentence per line, comma-separated, space-padded, NO checksum:
//   :SA,pitch,roll,heading   :TS,YYMMDDHHmmsshh,salinity,temp,depth,sos,BIT
//   :WI/:BI,x,y,z,error(mm/s),A|V   :WS/:BS,trans,long,normal,A|V   :WE/:BE,e,n,u,A|V
//   :WD/:BD,east,north,up(m),range_to_bottom(m),time_since_good(s)
// An ensemble runs from :SA/:TS to :BD; at :BD a DvlVelocity is produced from :BI (instrument frame:
// +X = beam 1 -> 2, +Y = beam 4 -> 3, +Z away from the bottom; qnav reports these as given) and :BD
// (altitude). Bottom lock = BI status 'A' and no component equal to the bad marker -32768.
// Since there is no checksum, lines are checked by field count, number syntax, ranges and order.
// Counters (shared DvlCounter names): length (line > kMaxPd6Line), format (field count / syntax /
// :BD without :BI), range (|v| > 20 m/s other than -32768, negative range), stale (TS time not
// after the previous ensemble's), no_lock (ensemble with status V or bad marker; still delivered).
// Worst case O(kMaxPd6Line) per line; no heap.
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivers/dvl/dvl_types.hpp"
#include "drivers/dvl/wl_parser.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/status.hpp"

namespace qnav::drivers::dvl {

constexpr std::size_t kMaxPd6Line = 128;

struct Pd6Ensemble {
  DvlVelocity velocity;
  bool has_attitude = false;
  double pitch_deg = 0, roll_deg = 0, heading_deg = 0;
  bool has_ts = false;
  double temperature_c = 0, depth_m = 0, sound_speed_mps = 0;
  double error_velocity_mps = 0;
  double time_since_good_s = 0;
};

enum class Pd6Result : std::uint8_t { kConsumed, kEnsemble };

class Pd6Parser : public DvlLineRejects {
 public:
  // Feeds one line. kEnsemble: `out` holds a finished ensemble. A non-ok Status = line rejected.
  Result<Pd6Result> parse_line(const char* line, std::size_t n, std::int64_t arrival_ns, Pd6Ensemble& out) noexcept;

 private:
  Pd6Ensemble cur_;
  bool have_bi_ = false;
  bool bi_good_ = false;
  std::int64_t first_arrival_ns_ = 0;
  bool in_ensemble_ = false;
  bool stale_ensemble_ = false;  // its :TS was stale: drop the rest of it
  bool have_last_time_ = false;
  std::int64_t last_time_cs_ = 0;
};

}  // namespace qnav::drivers::dvl
