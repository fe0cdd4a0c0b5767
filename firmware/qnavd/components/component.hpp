// What the components of qnavd's nav thread share (after F Prime's components and ports).
//
// The nav thread is a topology of components, each a class with typed input calls (ports in) and
// outputs it sets on the CAN publisher or returns (ports out); NavWorker (nav_worker.hpp) owns them,
// drains the queues and connects them:
//
//   [can_rx] [dvl] [mav_rx] -> NavInputs (attitude, dead reckoning, depth)  -- ModeCmd --> NavWorker modes
//   [pings] -> SonarTiles (RouteTilePipeline) -> RouteTile -> RouteTeach   (Mode = Teach: durable node append)
//                                                          -> RouteRepeat  (Mode = Repeat: pipeline::RouteRepeatSession)
//   [frames] stereo pair -> VoComponent   (Mode = Vo: VO_STEP increments)
//            downward    -> MapComponent  (Mode = Map: map pose, map file)
//   all of them -> NavHealth (faults, NAV_STATUS, HEALTH, HEARTBEAT, stage times, health log)
//               -> NavSource (MAVLink: the published estimate, route fixes, commands) -> [mav_tx]
//
// Every component is built in NavWorker::init from the configuration and the deployment table (its
// arena a named buffer of the static block), allocates nothing after, and states in its header what
// it consumes, what it produces, its memory and its time bound.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>

#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/static_memory.hpp"
#include "nav/core/arena.hpp"
#include "nav/core/status.hpp"

namespace qnav::daemon {

// Why a mode command was refused (NAV_STATUS ModeReject).
enum class ModeReject : std::uint8_t {
  kNone = 0, kUnsupportedMode, kRouteMissing, kRouteDamaged, kRouteTooShort, kStorage, kNoHeading, kRouteTooLong, kRouteMismatch
};
const char* to_string(ModeReject r) noexcept;

// The navigation time every component reads (sample time: monotonic on the linux backend, the
// mission's clock in sim), and when the worker started (log times are relative to it).
struct NavClock {
  std::int64_t now_ns = 0;
  std::int64_t start_ns = 0;
  double t_s() const noexcept { return static_cast<double>(now_ns - start_ns) * 1e-9; }
};

// What every component is given at construction: the configuration, the log (nullptr: none) and the
// nav clock. Events go to the log as one JSON line each (log.format json), key=value lines for the
// per-sample records (log.format kv), nothing per sample when log.format = off.
struct NavContext {
  const DaemonConfig* cfg = nullptr;
  FILE* log = nullptr;
  const NavClock* clock = nullptr;
  bool json() const noexcept { return log != nullptr && cfg->log == LogFormat::kJson; }
  bool key_value() const noexcept { return log != nullptr && cfg->log == LogFormat::kKeyValue; }
  bool events() const noexcept { return log != nullptr && cfg->log != LogFormat::kOff; }
};

// A stage's arena: its named buffer in the static block (qnavd), or one of its own when mem is null
// (a worker built alone, in a test).
struct StageArena {
  std::unique_ptr<ArenaStorage> own;
  std::unique_ptr<Arena> view;
  Result<Arena*> take(StaticMemory* mem, const char* name, std::size_t bytes);
};

// One sensor's samples in time order: a sample stamped at or before the previous one (a clock stepped
// back, a duplicate, a reordered delivery) cannot be a step forward; the caller counts and drops it.
struct SampleOrder {
  std::int64_t last_ns = -1;
  bool advance(std::int64_t sample_ns) noexcept {
    if (last_ns >= 0 && sample_ns <= last_ns) return false;
    last_ns = sample_ns;
    return true;
  }
};

// daemon.route_dir/route_<id>.qroute<suffix>
void route_file_path(const DaemonConfig& cfg, std::uint16_t id, const char* suffix, char* out, std::size_t n) noexcept;

}  // namespace qnav::daemon
