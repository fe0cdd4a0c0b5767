// Recorded sensors for the sim backend: what a [[sim.pass]] replays besides a side-scan file.
//  - candump (`sim.pass.candump`): a `candump -l` log of the vehicle bus. Every frame is played at its
//    log time, except QNAV_MODE_CMD (the simulated autopilot commands the pass's mode) and qnavd's own
//    frames (standard ids 0x200-0x2FF, its outputs in docs/qnav.dbc): those are skipped and counted.
//  - DVL capture (`sim.pass.dvl_log`): the DVL's serial output as `qnav dvl parse` reads it. It is
//    replayed in reports (a Water Linked velocity report with the lines after it; a PD6 ensemble from
//    its first line), each at the time the DVL stamped on it: Water Linked wrz time_of_transmission (us
//    since the epoch), PD6 :TS (YYMMDDHHmmsshh, UTC). Lines before the first report go with it.
//  - stereo sequence (`sim.pass.images`): a rectified pair per frame, KITTI layout (left/ right/,
//    calib.txt; 10 Hz: the copy has no times) or EuRoC (cam0/ cam1/ data.csv, their ns stamps).
// Times are absolute (ns since the epoch) on every source; SimPlayback aligns a pass's sources on the
// earliest of them. Loaded whole at init (host memory, replay only; a log is refused beyond
// kMaxLogBytes); images are read from disk when their pair is due.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "firmware/tools/sequence_reader.hpp"
#include "hal/core/can.hpp"
#include "nav/core/status.hpp"

namespace qnav::daemon {

struct ReplayCanFrame {
  std::int64_t t_ns = 0;
  hal::CanFrame frame;
};

struct ReplayDvlReport {
  std::int64_t t_ns = 0;
  std::uint32_t offset = 0, length = 0;  // bytes of RecordedSensors::dvl_text
};

class RecordedSensors {
 public:
  static constexpr std::size_t kMaxLogBytes = std::size_t{256} << 20;

  // Each load names the file and the reason in its error.
  Status load_candump(const std::string& path);
  Status load_dvl(const std::string& path, bool pd6);
  // max_frames: 0 = all.
  Status load_images(const std::string& dir, std::size_t max_frames);

  std::vector<ReplayCanFrame> can;
  std::uint32_t can_skipped = 0;     // mode commands and qnavd's own frames in the log
  std::uint32_t can_bad_lines = 0;   // lines that are not candump -l records
  std::string dvl_text;
  std::vector<ReplayDvlReport> dvl;
  std::vector<tools::StereoFrame> pairs;
  std::string what;                  // for the log: the files, counts and time spans
};

// Seconds since the epoch of a UTC calendar date and time (proleptic Gregorian).
std::int64_t utc_seconds(int year, int month, int day, int hour, int minute, int second) noexcept;

}  // namespace qnav::daemon
