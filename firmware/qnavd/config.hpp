// qnavd's configuration: one TOML file, read and validated once at start-up (before any buffer is
// sized). Every key has a default, a unit and bounds (docs/configuration.md lists them all, generated
// from the same key table: `qnavd --print-config-keys`). Unknown keys, wrong types and values out of
// range are errors that name the key, the line and the allowed range. The route localiser and tile
// settings start from firmware/pipeline/route_defaults (the tuned values `qnav route eval` measured)
// and the [route] keys override them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "drivers/qnavcan/messages.hpp"
#include "firmware/pipeline/route_defaults.hpp"
#include "firmware/pipeline/topo_mapper.hpp"
#include "firmware/pipeline/vo_defaults.hpp"
#include "nav/core/fixed_vector.hpp"
#include "nav/core/status.hpp"

namespace qnav::daemon {

enum class Backend : std::uint8_t { kSim, kLinux };
enum class LogFormat : std::uint8_t { kJson, kKeyValue, kOff };
enum class SonarSource : std::uint8_t { kSim, kJsfTcp };
// sim.speed's named values: 0 = as fast as the pipeline takes it ("fast"), 1 = real time ("recorded":
// a recorded file at its own timing). Any factor in (0, 1000] paces the mission that many times real time.
struct SimSpeed {
  static constexpr double kFast = 0.0;
  static constexpr double kRecorded = 1.0;
  static constexpr double kMax = 1000.0;
};
enum class CameraSource : std::uint8_t { kSim, kV4l2 };
// The tuned VO settings a rig starts from (firmware/pipeline/vo_defaults): the simulated Mars-yard
// bench with an attitude sensor (3D-VME), a car's stereo pair without one (KITTI), a hand-held or
// hovering rig indoors (EuRoC).
enum class VoPreset : std::uint8_t { kBench, kKitti, kEuroc };

// One pass of the simulated mission: the simulated autopilot sends QNAV_MODE_CMD (mode, reverse,
// route id) before it and Idle after it, as a vehicle's autopilot would.
// A pass with a `file` replays a recorded side-scan file (XTF or JSF) instead of the simulated survey:
// pings [first_ping, last_ping) with the file's navigation, their recorded timing, the heading as the
// AHRS and the track's velocity as the DVL would give them (offset_pct does not apply).
struct SimPass {
  drivers::qnavcan::Mode mode = drivers::qnavcan::Mode::kTeach;  // teach, repeat or hold
  double offset_pct = 0.0;  // lateral offset, percent of the full swath, right of the taught direction [-100, 100]
  bool reverse = false;
  double length_m = 6.0;    // sim.pass.length_m [0.5, 1000]: distance the rover drives in a vo pass
  std::string file;         // sim.pass.file: recorded XTF / JSF; "" = the simulated survey
  std::int64_t first_ping = 0;   // sim.pass.first_ping [0, 1e9]
  std::int64_t last_ping = -1;   // sim.pass.last_ping [-1, 1e9]: -1 = to the end of the file
  // Recorded sensors (firmware/qnavd/sim_replay.hpp); each replaces its simulated counterpart:
  std::string candump;      // sim.pass.candump: candump -l log of the CAN sensors (attitude, DroneCAN AHRS)
  std::string dvl_log;      // sim.pass.dvl_log: capture of the DVL's serial output (dvl.protocol)
  std::string images;       // sim.pass.images: mode = "vo": stereo sequence folder (KITTI or EuRoC layout);
                            // mode = "map": a folder of downward frames (.png/.jpg/.pgm, name order), "" = the
                            // synthetic seabed loop (drivers/downward_sim)
  std::int64_t max_frames = 0;  // sim.pass.max_frames [0, 1e6]: pairs / frames of sim.pass.images replayed; 0 = all
  // sim.pass.closed_loop: a simulated repeat pass flown in closed loop: the vehicle steers on the
  // daemon's QNAV_ROUTE_GUIDANCE / STATUS frames (pipeline::RouteAutopilot, as `qnav route follow`),
  // with drift and a current; offset_pct is where it starts. Needs a simulated teach pass before it.
  bool closed_loop = false;
};

struct DaemonConfig {
  // [daemon]
  Backend backend = Backend::kSim;            // daemon.backend = "sim" | "linux"
  std::string route_dir = "routes";          // daemon.route_dir: where route files live (route_<id>.qroute)
  LogFormat log = LogFormat::kJson;          // daemon.log = "json" | "kv" | "off": one line per tile to stdout
  bool realtime = true;                      // daemon.realtime: mlockall + SCHED_FIFO when permitted
  int io_priority = 30;                      // daemon.io_priority [1, 99] (SCHED_FIFO)
  int nav_priority = 20;                     // daemon.nav_priority [1, 99]
  int io_cpu = -1;                           // daemon.io_cpu [-1, 63] (-1 = any)
  int nav_cpu = -1;                          // daemon.nav_cpu [-1, 63]
  double shutdown_timeout_s = 5.0;           // daemon.shutdown_timeout_s [0.1, 60]
  double health_period_s = 1.0;              // daemon.health_period_s [0.1, 60]: log line with the counters

  // [can]
  std::string can_interface = "vcan0";       // can.interface (linux backend)
  double attitude_stale_s = 0.5;             // can.attitude_stale_s [0.01, 10]
  double depth_stale_s = 2.0;                // can.depth_stale_s [0.01, 60]
  std::size_t can_rx_queue = 256;            // can.rx_queue [16, 4096] frames, power of two
  std::size_t can_tx_queue = 64;             // can.tx_queue [16, 4096] frames, power of two

  // [sonar]
  SonarSource sonar_source = SonarSource::kSim;  // sonar.source = "sim" | "jsf_tcp"
  std::string sonar_address = "127.0.0.1:1700";  // sonar.address host:port (jsf_tcp)
  double sonar_stale_s = 2.0;                // sonar.stale_s [0.1, 60]
  std::size_t ping_queue = 32;               // sonar.ping_queue [4, 1024] pings, power of two
  std::size_t max_samples_per_side = 1024;   // sonar.max_samples_per_side [64, 16384]

  // [dvl]
  bool dvl_enabled = true;                   // dvl.enabled
  std::string dvl_device = "/dev/ttyUSB0";   // dvl.device (linux backend)
  std::string dvl_protocol = "waterlinked";  // dvl.protocol = "waterlinked" | "pd6"
  int dvl_baud = 115200;                     // dvl.baud: 9600 | 19200 | 38400 | 57600 | 115200 | 230400 | 460800
  double dvl_stale_s = 1.0;                  // dvl.stale_s [0.05, 60]

  // [route]
  std::uint16_t route_id = 1;                // route.id [0, 65535]: route used when a MODE_CMD gives 0
  std::size_t max_nodes = 10000;             // route.max_nodes [2, 65535]
  bool route_learn = false;                  // route.learn: Repeat appends confident tiles to ROUTE.exp (issue 29)
  double route_entry_prior = pipeline::kDefaultEntryPrior;  // route.entry_prior: start belief on the route's entry end
  std::uint16_t max_experiences = 4;         // route.max_experiences [1, 8]: experiences per node (fixed memory)
  // The daemon only extracts features from its tiles: no u8 raster (docs/budgets.md, the demo's peak RSS).
  pipeline::RouteTileConfig tiles = [] {
    pipeline::RouteTileConfig t = pipeline::default_route_tile_config();
    t.tiles.u8_raster = false;
    return t;
  }();
  route::LocaliserConfig localiser = pipeline::default_localiser_config(route::RouteDirection::kForward, 10000);
  //   route.tile_length_m [0, 5000]         -> tiles.tiles.tile_length_m (0: tiles by ping count)
  //   route.tile_stride_m [0.1, tile_length_m] -> tiles.tiles.tile_stride_m
  //   route.scanlines_per_tile [20, 4000]   -> tiles.tiles.scanlines_per_tile (by distance: the most pings a tile holds)
  //   route.scanline_stride [1, scanlines_per_tile] -> tiles.tiles.scanline_stride (used with tile_length_m = 0)
  //   route.resolution_m [0.01, 5]          -> tiles.tiles.resolution_m
  //   route.tile_px [64, 2048]              -> tiles.tiles.tile_width_px/height_px, tiles.features.max_width/height
  //   route.ground_bins_per_side [16, 4096] -> tiles.corrector.ground_bins_per_side, tiles.tiles.max_bins_per_side
  //   route.ground_bin_m [0.01, 5]          -> tiles.corrector.ground_bin_m
  //   route.max_keypoints [8, 128]          -> tiles.features.max_keypoints
  //   route.belief_registrations [1, 64]    -> localiser.filter.belief_registrations
  //   route.searching_registrations [1, 64] -> localiser.filter.searching_registrations
  //   route.min_inliers [3, 100]            -> localiser.registration.robust.min_inliers
  //   route.side_deadband_m [0, 100]        -> localiser.guidance.side_deadband_m
  //   route.dead_reckon_max_m [0, 10000]    -> localiser.guidance.dead_reckon_max_m
  //   route.motion = "odometry" | "eq5"     -> localiser.filter.motion

  // [vo] stereo visual odometry (Mode = Vo): the camera pair, its calibration and mount, the VO settings.
  // The VO settings start from firmware/pipeline/vo_defaults (default_vo_config, what `qnav vo eval`
  // measures) for the simulated bench; the keys override them.
  bool vo_enabled = true;                     // vo.enabled: the camera pair is read and Mode = Vo accepted
  CameraSource vo_camera = CameraSource::kSim; // vo.camera = "sim" | "v4l2"
  std::string vo_left_device = "/dev/video0"; // vo.left_device (v4l2)
  std::string vo_right_device = "/dev/video1";// vo.right_device (v4l2)
  std::string vo_trigger_chip;                // vo.trigger_chip: gpiochip of the trigger line; "" = free-running cameras
  int vo_trigger_line = 0;                    // vo.trigger_line [0, 511]
  double vo_rate_hz = 10.0;                   // vo.rate_hz [0.5, 60]: trigger rate (with vo.trigger_chip)
  double vo_pair_tolerance_ms = 2.0;          // vo.pair_tolerance_ms [0.01, 1000]: left/right stamps this close are a pair
  double vo_tilt_down_deg = 70.0;             // vo.tilt_down_deg [0, 90]: camera mount, forward-looking, tilted down
  double vo_mount_height_m = 0.8;             // vo.mount_height_m [0, 10]: left camera above the body origin
  VoPreset vo_preset = VoPreset::kBench;      // vo.preset = "bench" | "kitti" | "euroc"
  vo::VoConfig vo = pipeline::default_vo_config(sim::StereoBench{});
  pipeline::VoPriorConfig vo_prior{};         // the preset's translation prior (derived, not a key)
  //   vo.width / vo.height [64, 2048] px      -> vo.max_width / max_height (and the frame pool)
  //   vo.focal_px, vo.cu_px, vo.cv_px, vo.baseline_m -> vo.camera
  //   vo.max_corners [32, 1000], vo.vme = "3d" | "6d", vo.attitude_filter, vo.max_step_m
  std::size_t vo_frame_queue = 4;             // vo.frame_queue [2, 64] pairs, power of two
  double vo_stale_s = 2.0;                    // vo.stale_s [0.1, 60]: no pair for this long in Mode = Vo: camera lost

  // [map] downward-camera mapping (Mode = Map): the downward camera's rectified frames through
  // pipeline::TopoMapper (the wiring `qnav map` runs), the topological map saved durably in
  // daemon.route_dir as map_<id>.qmap (firmware/tools/map_file). Frames share the frame pool with
  // the stereo pairs (a slot holds the larger of the two). The camera: on the sim backend a
  // [[sim.pass]] with mode = "map" (a frame folder or the synthetic seabed); on the linux backend the
  // V4L2 device map.device (LinuxDownwardSource; without one Mode = Map is refused, UnsupportedMode).
  // The [map] table holds the camera because it serves this mode only and its intrinsics are [map] keys.
  bool map_enabled = false;                   // map.enabled: the frame pool takes downward frames and Mode = Map is accepted
  std::string map_device;                     // map.device: the downward V4L2 camera (linux backend); "" = none
  int map_width = 320;                        // map.width [64, 2048] px
  int map_height = 240;                       // map.height [64, 2048] px
  double map_focal_px = 0.0;                  // map.focal_px [0, 20000] px: 0 = unknown (the map in mosaic pixels)
  double map_cu_px = -1.0;                    // map.cu_px [-1, 2047] px: principal point; -1 = image centre
  double map_cv_px = -1.0;                    // map.cv_px [-1, 2047] px
  double map_altitude_m = 0.0;                // map.altitude_m [0, 1000] m: above the seabed, constant; with focal_px: metres
  double map_node_spacing = 0.0;              // map.node_spacing [0, 1e6] m or px: 0 = the tool's default (0.2 m / 30 px)
  std::size_t map_max_nodes = 1024;           // map.max_nodes [2, 65534]
  std::size_t map_frame_queue = 4;            // map.frame_queue [2, 64] frames, power of two
  double map_stale_s = 2.0;                   // map.stale_s [0.1, 60]: no downward frame for this long in Mode = Map: camera lost

  // [leak] the leak detector: a GPIO input line (linux backend, libgpiod). Latched: the first edge to
  // the active level (or the level already active at start) sets HEALTH.Leak and FaultLeak until the
  // daemon restarts. The sim backend has a simulated line (sim.fault = "leak").
  std::string leak_chip;                      // leak.chip: gpiochip name or path; "" = no leak detector
  int leak_line = 0;                          // leak.line [0, 511]
  bool leak_active_low = false;               // leak.active_low: the detector pulls the line low when wet

  // [mavlink] qnavd as the external navigation source of an ArduSub or PX4 autopilot (docs/interfaces.md,
  // MAVLink): UDP to udp_remote and/or a server on udp_listen_port, and/or the serial device.
  bool mavlink_enabled = false;               // mavlink.enabled
  std::string mavlink_udp_remote;             // mavlink.udp_remote: "HOST:PORT" (IPv4) or "" = none
  int mavlink_udp_listen_port = 0;            // mavlink.udp_listen_port [0, 65535]: 0 = none
  std::string mavlink_serial_device;          // mavlink.serial_device: "" = none (linux backend)
  int mavlink_baud = 115200;                  // mavlink.baud: 57600 | 115200 | 230400 | 460800 | 921600
  int mavlink_system_id = 1;                  // mavlink.system_id [1, 255]: the vehicle's system
  int mavlink_component_id = 197;             // mavlink.component_id [1, 255]: MAV_COMP_ID_VISUAL_INERTIAL_ODOMETRY
  double mavlink_odometry_hz = 10.0;          // mavlink.odometry_hz [1, 50]
  bool mavlink_guided = false;                // mavlink.guided: send SET_POSITION_TARGET_LOCAL_NED in GUIDED (Repeat)
  int mavlink_autopilot_system_id = 1;        // mavlink.autopilot_system_id [1, 255]: who may command qnav
  int mavlink_autopilot_component_id = 1;     // mavlink.autopilot_component_id [1, 255]: MAV_COMP_ID_AUTOPILOT1
  std::string mavlink_key_file;               // mavlink.key_file: MAVLink 2 signing key (64 hex digits, root-owned, 0600); "" = unsigned
  double mavlink_origin_lat_deg = 0.0;        // mavlink.origin_lat_deg [-90, 90]: with origin_lon_deg, sent as SET_GPS_GLOBAL_ORIGIN
  double mavlink_origin_lon_deg = 0.0;        // mavlink.origin_lon_deg [-180, 180]
  double mavlink_origin_alt_m = 0.0;          // mavlink.origin_alt_m [-1000, 10000] m above mean sea level
  // Set by the configuration reader (not keys): an origin was configured (origin_lat_deg and
  // origin_lon_deg given); the key file's uid rule (root; a test passes its own uid) and, after
  // Daemon::init read mavlink.key_file (load_mavlink_key), its secret.
  bool mavlink_origin = false;
  std::uint32_t mavlink_key_owner_uid = 0;
  bool mavlink_key_loaded = false;
  std::uint8_t mavlink_key_secret[32] = {};

  // [budget] per-stage time budgets on the host, microseconds (docs/budgets.md)
  std::uint32_t ping_budget_us = 2000;       // budget.ping_us [10, 1000000]
  std::uint32_t tile_budget_us = 50000;      // budget.tile_us [100, 10000000]: features + localiser update
  std::uint32_t mode_budget_us = 200000;     // budget.mode_us [100, 10000000]: a mode change (route file open/close, fsync)
  std::uint32_t vo_budget_us = 100000;       // budget.vo_us [100, 10000000]: one stereo pair through the VO
  std::uint32_t map_budget_us = 50000;       // budget.map_us [100, 10000000]: one downward frame through the mapper (+ map save)

  // [sim] (backend = "sim")
  double sim_length_m = 2000.0;              // sim.length_m [200, 50000]
  std::uint64_t sim_seed = 1;                // sim.seed [0, 2^32)
  double sim_speed = SimSpeed::kFast;        // sim.speed [0, 1000] x real time, or "fast" (0) | "recorded" (1)
  // sim.can_interface: "" = the vehicle and qnavd share an in-process CAN bus; else the SocketCAN
  // interface (vcan0, can0) both put their frames on (candump sees them, a person can send commands).
  std::string sim_can_interface;
  bool sim_exit_at_end = true;               // sim.exit_at_end: qnavd exits 0 when the mission is flown
  FixedVector<SimPass, 16> sim_mission;      // [[sim.pass]] mode = "teach"|"repeat"|"hold", offset_pct, reverse
  // Recorded passes (a [[sim.pass]] with a file): the tiles and the localiser take the recorded
  // files' geometry (as `qnav route train|repeat --sonar` does): sim.replay_lines [10, 2000] pings per
  // tile every sim.replay_stride [1, replay_lines] pings; navigation from the fixes or dead reckoning.
  int sim_replay_lines = 100;
  int sim_replay_stride = 50;
  std::string sim_replay_nav = "fix";        // sim.replay_nav = "fix" | "dr"
  std::string sim_ahrs = "qnav";              // sim.ahrs = "qnav" (QNAV_ATTITUDE_IN) | "dronecan" (uavcan.equipment.ahrs.Solution, node 42)
  std::string sim_candump;                   // sim.candump: the autopilot records the bus here (candump -l format); "" = off
  std::string sim_closed_loop_csv;           // sim.closed_loop_csv: the closed-loop passes' tracks (scripts/route_follow_plot.py); "" = off
  // A sensor of the simulated vehicle stops for a while (fault tests): sim.stall = "none" | "dvl" |
  // "attitude" | "sonar", from sim.stall_start_s [0, 100000] after the start of pass sim.stall_pass
  // [0, 15] for sim.stall_s [0, 3600] seconds of mission time.
  std::string sim_stall = "none";
  int sim_stall_pass = 1;
  double sim_stall_start_s = 0.0;
  double sim_stall_s = 0.0;
  // Fault injection (tests, the soak, the bench): damaged or disordered input for a while, with the
  // same window keys (sim.fault_pass, sim.fault_start_s, sim.fault_s). Each kind and the daemon's
  // expected answer: docs/reliability.md.
  std::string sim_fault = "none";
  int sim_fault_pass = 1;
  double sim_fault_start_s = 0.0;
  double sim_fault_s = 0.0;
};

// sim.fault's kinds, in the order docs/reliability.md lists them.
inline constexpr const char* kSimFaultKinds[] = {
    "none",          "dvl_nan",          "dvl_time_back",      "dvl_duplicate",   "dvl_line_noise",
    "attitude_out_of_range", "attitude_duplicate", "can_error_frames", "can_bus_off",
    "sonar_nan",     "sonar_bad_range",  "ping_time_back",     "disk_full",       "leak"};

// Where a configuration error is: key (dotted), line (0 if unknown) and a message with the allowed range.
struct ConfigError {
  std::string key;
  int line = 0;
  std::string message;
  std::string to_string() const;  // "FILE:LINE: key: message"
  std::string file;
};

// The left camera's mount on the body (FRD) from vo.tilt_down_deg and vo.mount_height_m: optical axis
// forward and tilted down, image x to the right; the simulated rover's bench (drivers/stereo_sim).
Pose3 vo_body_T_cam(const DaemonConfig& c) noexcept;

// Mode = Map can run: map.enabled with the sim backend, or with the linux backend and a map.device
// (without a camera the mode is refused with UnsupportedMode and nothing is sized for it).
bool map_runs(const DaemonConfig& c) noexcept;
// The frame pool: slots (the deeper of vo.frame_queue and map.frame_queue, of the enabled ones) of
// the larger of a stereo pair (2 x vo.width x vo.height) and a downward frame (map.width x map.height).
std::size_t frame_pool_slots(const DaemonConfig& c) noexcept;
std::size_t frame_slot_bytes(const DaemonConfig& c) noexcept;
// The mapper's settings from the [map] keys (pipeline::topo_mapper_config: the tool's defaults).
pipeline::TopoMapperConfig map_mapper_config(const DaemonConfig& c) noexcept;

// Reads and validates a file. On failure returns false and fills err; out is left default.
bool load_config(const char* path, DaemonConfig& out, ConfigError& err);
// The same from a string (tests); `name` stands in for the file name in errors.
bool parse_config(const std::string& text, const char* name, DaemonConfig& out, ConfigError& err);
// Every key with its type, default, unit and bounds, one per line as a markdown table row.
std::string config_keys_markdown();

}  // namespace qnav::daemon
