// qnavd's configuration: the example files load, the documented defaults are DaemonConfig{}'s, every
// key reaches its field, every class of mistake names its key and line, and every configuration the
// bounds allow initialises the nav stages it sizes.
#include "firmware/qnavd/config.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "nav/core/arena.hpp"
#include "nav/route/route_localiser.hpp"
#include "nav/route/tile_features.hpp"
#include "nav/sonar/scanline_corrector.hpp"
#include "nav/sonar/tile_builder.hpp"

namespace qnav::daemon {
namespace {

// ---- Helpers -------------------------------------------------------------------------------------

template <typename T>
std::string repr(const T& v) {
  std::ostringstream s;
  if constexpr (std::is_enum_v<T>) {
    s << static_cast<long long>(v);
  } else if constexpr (std::is_floating_point_v<T>) {
    s.precision(17);
    s << static_cast<double>(v);
  } else if constexpr (std::is_same_v<T, std::string>) {
    s << '"' << v << '"';
  } else {
    s << v;
  }
  return s.str();
}

// Every field the configuration sets (the [route] keys through the nav configs they map to).
struct Field {
  const char* name;
  std::function<std::string(const DaemonConfig&)> get;
};
#define QNAV_FIELD(expr)                                      \
  Field {                                                     \
#expr, [](const DaemonConfig& c) { return repr(c.expr); } \
  }
const std::vector<Field>& fields() {
  static const std::vector<Field> f = {
      QNAV_FIELD(backend),
      QNAV_FIELD(route_dir),
      QNAV_FIELD(log),
      QNAV_FIELD(realtime),
      QNAV_FIELD(io_priority),
      QNAV_FIELD(nav_priority),
      QNAV_FIELD(io_cpu),
      QNAV_FIELD(nav_cpu),
      QNAV_FIELD(shutdown_timeout_s),
      QNAV_FIELD(health_period_s),
      QNAV_FIELD(can_interface),
      QNAV_FIELD(attitude_stale_s),
      QNAV_FIELD(depth_stale_s),
      QNAV_FIELD(can_rx_queue),
      QNAV_FIELD(can_tx_queue),
      QNAV_FIELD(sonar_source),
      QNAV_FIELD(sonar_address),
      QNAV_FIELD(sonar_stale_s),
      QNAV_FIELD(ping_queue),
      QNAV_FIELD(max_samples_per_side),
      QNAV_FIELD(tiles.corrector.max_samples_per_side),
      QNAV_FIELD(dvl_enabled),
      QNAV_FIELD(dvl_device),
      QNAV_FIELD(dvl_protocol),
      QNAV_FIELD(dvl_baud),
      QNAV_FIELD(dvl_stale_s),
      QNAV_FIELD(route_id),
      QNAV_FIELD(max_nodes),
      QNAV_FIELD(route_learn),
      QNAV_FIELD(route_entry_prior),
      QNAV_FIELD(max_experiences),
      QNAV_FIELD(localiser.filter.max_nodes),
      QNAV_FIELD(tiles.tiles.tile_length_m),
      QNAV_FIELD(tiles.tiles.tile_stride_m),
      QNAV_FIELD(tiles.tiles.scanlines_per_tile),
      QNAV_FIELD(tiles.tiles.scanline_stride),
      QNAV_FIELD(tiles.tiles.resolution_m),
      QNAV_FIELD(tiles.tiles.tile_width_px),
      QNAV_FIELD(tiles.tiles.tile_height_px),
      QNAV_FIELD(tiles.features.max_width),
      QNAV_FIELD(tiles.features.max_height),
      QNAV_FIELD(tiles.corrector.ground_bins_per_side),
      QNAV_FIELD(tiles.tiles.max_bins_per_side),
      QNAV_FIELD(tiles.corrector.ground_bin_m),
      QNAV_FIELD(tiles.features.max_keypoints),
      QNAV_FIELD(localiser.filter.belief_registrations),
      QNAV_FIELD(localiser.filter.searching_registrations),
      QNAV_FIELD(localiser.window_slots),
      QNAV_FIELD(localiser.registration.robust.min_inliers),
      QNAV_FIELD(localiser.guidance.side_deadband_m),
      QNAV_FIELD(localiser.guidance.dead_reckon_max_m),
      QNAV_FIELD(localiser.filter.motion),
      QNAV_FIELD(ping_budget_us),
      QNAV_FIELD(tile_budget_us),
      QNAV_FIELD(mode_budget_us),
      QNAV_FIELD(vo_budget_us),
      QNAV_FIELD(leak_chip),
      QNAV_FIELD(leak_line),
      QNAV_FIELD(leak_active_low),
      QNAV_FIELD(mavlink_enabled),
      QNAV_FIELD(mavlink_udp_remote),
      QNAV_FIELD(mavlink_udp_listen_port),
      QNAV_FIELD(mavlink_serial_device),
      QNAV_FIELD(mavlink_baud),
      QNAV_FIELD(mavlink_system_id),
      QNAV_FIELD(mavlink_component_id),
      QNAV_FIELD(mavlink_odometry_hz),
      QNAV_FIELD(mavlink_guided),
      QNAV_FIELD(mavlink_autopilot_system_id),
      QNAV_FIELD(mavlink_autopilot_component_id),
      QNAV_FIELD(mavlink_key_file),
      QNAV_FIELD(mavlink_origin_lat_deg),
      QNAV_FIELD(mavlink_origin_lon_deg),
      QNAV_FIELD(mavlink_origin_alt_m),
      QNAV_FIELD(vo_enabled),
      QNAV_FIELD(vo_camera),
      QNAV_FIELD(vo_left_device),
      QNAV_FIELD(vo_right_device),
      QNAV_FIELD(vo_trigger_chip),
      QNAV_FIELD(vo_trigger_line),
      QNAV_FIELD(vo_rate_hz),
      QNAV_FIELD(vo_preset),
      QNAV_FIELD(vo_pair_tolerance_ms),
      QNAV_FIELD(vo.max_width),
      QNAV_FIELD(vo.max_height),
      QNAV_FIELD(vo.camera.focal_px),
      QNAV_FIELD(vo.camera.cu_px),
      QNAV_FIELD(vo.camera.cv_px),
      QNAV_FIELD(vo.camera.baseline_m),
      QNAV_FIELD(vo_tilt_down_deg),
      QNAV_FIELD(vo_mount_height_m),
      QNAV_FIELD(vo.max_corners),
      QNAV_FIELD(vo.mode),
      QNAV_FIELD(vo.estimate_attitude_bias),
      QNAV_FIELD(vo.max_step_m),
      QNAV_FIELD(vo_frame_queue),
      QNAV_FIELD(vo_stale_s),
      QNAV_FIELD(map_enabled),
      QNAV_FIELD(map_device),
      QNAV_FIELD(map_width),
      QNAV_FIELD(map_height),
      QNAV_FIELD(map_focal_px),
      QNAV_FIELD(map_cu_px),
      QNAV_FIELD(map_cv_px),
      QNAV_FIELD(map_altitude_m),
      QNAV_FIELD(map_node_spacing),
      QNAV_FIELD(map_max_nodes),
      QNAV_FIELD(map_frame_queue),
      QNAV_FIELD(map_stale_s),
      QNAV_FIELD(map_budget_us),
      QNAV_FIELD(sim_length_m),
      QNAV_FIELD(sim_seed),
      QNAV_FIELD(sim_speed),
      QNAV_FIELD(sim_can_interface),
      QNAV_FIELD(sim_exit_at_end),
      QNAV_FIELD(sim_replay_lines),
      QNAV_FIELD(sim_replay_stride),
      QNAV_FIELD(sim_replay_nav),
      QNAV_FIELD(sim_ahrs),
      QNAV_FIELD(sim_candump),
      QNAV_FIELD(sim_closed_loop_csv),
      QNAV_FIELD(sim_stall),
      QNAV_FIELD(sim_stall_pass),
      QNAV_FIELD(sim_stall_start_s),
      QNAV_FIELD(sim_stall_s),
      QNAV_FIELD(sim_fault),
      QNAV_FIELD(sim_fault_pass),
      QNAV_FIELD(sim_fault_start_s),
      QNAV_FIELD(sim_fault_s),
  };
  return f;
}
#undef QNAV_FIELD

// One row of config_keys_markdown(), backticks removed.
struct Row {
  std::string key, type, def, unit, allowed, meaning;
  std::string section() const { return key.substr(0, key.rfind('.')); }
  std::string leaf() const { return key.substr(key.rfind('.') + 1); }
  bool in_pass() const { return key.rfind("sim.pass.", 0) == 0; }
};

std::string trim(const std::string& s) {
  const std::size_t a = s.find_first_not_of(' ');
  const std::size_t b = s.find_last_not_of(' ');
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

std::string unquote_code(std::string s) {
  std::string out;
  for (char ch : s)
    if (ch != '`') out += ch;
  return out;
}

std::vector<Row> markdown_rows() {
  std::vector<Row> rows;
  std::istringstream in(config_keys_markdown());
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    if (n++ < 2) continue;  // header and separator
    std::vector<std::string> cells;
    std::size_t start = 1;
    for (std::size_t bar = line.find('|', start); bar != std::string::npos; bar = line.find('|', start)) {
      cells.push_back(trim(line.substr(start, bar - start)));
      start = bar + 1;
    }
    EXPECT_EQ(cells.size(), 6u) << line;
    if (cells.size() != 6) continue;
    rows.push_back(
        {unquote_code(cells[0]), cells[1], unquote_code(cells[2]), cells[3], unquote_code(cells[4]), cells[5]});
  }
  return rows;
}

// "[a, b]..." -> a, b as text (false when the allowed column is a list, not a range).
bool range_of(const Row& r, std::string& lo, std::string& hi) {
  if (r.allowed.empty() || r.allowed[0] != '[') return false;
  const std::size_t comma = r.allowed.find(", ");
  const std::size_t close = r.allowed.find(']');
  lo = r.allowed.substr(1, comma - 1);
  hi = r.allowed.substr(comma + 2, close - comma - 2);
  return true;
}

std::vector<std::string> list_of(const Row& r) {
  std::vector<std::string> items;
  std::istringstream in(r.allowed);
  std::string item;
  while (std::getline(in, item, ',')) items.push_back(trim(item));
  return items;
}

// A file setting each key to value(row) (rows whose value is empty are left out); the [[sim.pass]]
// keys go into one pass, which is always there.
std::string config_text(const std::vector<Row>& rows, const std::function<std::string(const Row&)>& value) {
  std::string out, section, pass = "[[sim.pass]]\nmode = \"teach\"\n";
  for (const Row& r : rows) {
    const std::string v = value(r);
    if (v.empty()) continue;
    if (r.in_pass()) {
      if (r.leaf() == "mode") pass = "[[sim.pass]]\n";
      pass += r.leaf() + " = " + v + "\n";
      continue;
    }
    if (r.section() != section) {
      section = r.section();
      out += "\n[" + section + "]\n";
    }
    out += r.leaf() + " = " + v + "\n";
  }
  return out + "\n" + pass;
}

ConfigError expect_error(const std::string& text) {
  DaemonConfig c;
  ConfigError err;
  EXPECT_FALSE(parse_config(text, "qnavd.toml", c, err)) << text;
  return err;
}

DaemonConfig expect_ok(const std::string& text) {
  DaemonConfig c;
  ConfigError err;
  EXPECT_TRUE(parse_config(text, "qnavd.toml", c, err)) << err.to_string() << "\n" << text;
  return c;
}

// Initialises every nav stage the configuration sizes, each in an arena of its declared size.
template <typename Stage, typename Config>
void expect_stage_inits(const Config& config, const char* what) {
  ArenaStorage arena(Stage::arena_bytes(config));
  ASSERT_TRUE(arena.valid()) << what;
  Stage stage;
  const Status s = stage.init(config, arena);
  EXPECT_TRUE(s.is_ok()) << what << ": " << s.message();
}
void expect_stages_init(const DaemonConfig& c) {
  expect_stage_inits<sonar::ScanlineCorrector>(c.tiles.corrector, "scanline corrector");
  expect_stage_inits<sonar::TileBuilder>(c.tiles.tiles, "tile builder");
  expect_stage_inits<route::TileFeatureExtractor>(c.tiles.features, "tile features");
  expect_stage_inits<route::RouteLocaliser>(c.localiser, "route localiser");
  expect_stage_inits<vo::StereoVo>(c.vo, "stereo visual odometry");
}

std::string source_path(const char* relative) { return std::string(QNAV_SOURCE_DIR) + "/" + relative; }

constexpr const char* kOnePass = "[[sim.pass]]\nmode = \"teach\"\n";

// ---- Example files --------------------------------------------------------------------------------

TEST(QnavdConfig, SimExampleLoadsAndFliesTheDocumentedMission) {
  DaemonConfig c;
  ConfigError err;
  ASSERT_TRUE(load_config(source_path("firmware/qnavd/config/sim.toml").c_str(), c, err)) << err.to_string();
  EXPECT_EQ(c.backend, Backend::kSim);
  EXPECT_EQ(c.route_dir, "build/demo/routes");
  EXPECT_EQ(c.log, LogFormat::kJson);
  EXPECT_FALSE(c.realtime);
  EXPECT_EQ(c.sim_length_m, 2000.0);
  EXPECT_EQ(c.sim_seed, 1u);
  EXPECT_EQ(c.sim_speed, SimSpeed::kFast);
  using drivers::qnavcan::Mode;
  ASSERT_EQ(c.sim_mission.size(), 5u);
  const Mode modes[] = {Mode::kTeach, Mode::kRepeat, Mode::kRepeat, Mode::kRepeat, Mode::kVo};
  const double offsets[] = {0.0, 10.0, -20.0, 30.0, 0.0};
  const bool reverse[] = {false, false, true, false, false};
  for (std::size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(c.sim_mission[i].mode, modes[i]) << i;
    EXPECT_EQ(c.sim_mission[i].offset_pct, offsets[i]) << i;
    EXPECT_EQ(c.sim_mission[i].reverse, reverse[i]) << i;
  }
  EXPECT_EQ(c.sim_mission[4].length_m, 10.0);
  EXPECT_TRUE(c.sim_mission[3].closed_loop);  // the demo's closed-loop repeat
  EXPECT_FALSE(c.sim_mission[1].closed_loop);
  EXPECT_EQ(c.sim_closed_loop_csv, "build/demo/qnavd_closed_loop.csv");
  EXPECT_TRUE(c.vo_enabled);
  EXPECT_EQ(c.vo_camera, CameraSource::kSim);
  expect_stages_init(c);
}

TEST(QnavdConfig, VehicleExampleLoads) {
  DaemonConfig c;
  ConfigError err;
  ASSERT_TRUE(load_config(source_path("firmware/qnavd/config/vehicle.toml").c_str(), c, err)) << err.to_string();
  EXPECT_EQ(c.backend, Backend::kLinux);
  EXPECT_EQ(c.can_interface, "can0");
  EXPECT_EQ(c.sonar_source, SonarSource::kJsfTcp);
  EXPECT_EQ(c.sonar_address, "192.168.1.20:1700");
  EXPECT_EQ(c.dvl_device, "/dev/ttyUSB0");
  EXPECT_EQ(c.dvl_protocol, "waterlinked");
  EXPECT_EQ(c.dvl_baud, 115200);
  EXPECT_EQ(c.route_dir, "/var/lib/qnav/routes");
  EXPECT_TRUE(c.realtime);
  EXPECT_TRUE(c.sim_mission.empty());
  EXPECT_EQ(c.vo_camera, CameraSource::kV4l2);
  EXPECT_EQ(c.vo_left_device, "/dev/video0");
  EXPECT_EQ(c.vo_right_device, "/dev/video1");
  EXPECT_EQ(c.vo_trigger_chip, "gpiochip0");
  EXPECT_EQ(c.map_device, "/dev/video2");
  EXPECT_FALSE(map_runs(c));  // map.enabled = false: the downward camera is not opened
  c.map_enabled = true;
  EXPECT_TRUE(map_runs(c));
  expect_stages_init(c);
}

// ---- The key table --------------------------------------------------------------------------------

TEST(QnavdConfig, KeyTableIsAMarkdownTableWithOneRowPerKey) {
  const std::string md = config_keys_markdown();
  EXPECT_EQ(md.rfind("| key | type | default | unit | allowed | meaning |\n|---|---|---|---|---|---|\n", 0), 0u);
  const std::vector<Row> rows = markdown_rows();
  ASSERT_FALSE(rows.empty());
  std::set<std::string> keys;
  for (const Row& r : rows) {
    EXPECT_TRUE(keys.insert(r.key).second) << "duplicate " << r.key;
    EXPECT_FALSE(r.allowed.empty()) << r.key;
    EXPECT_FALSE(r.meaning.empty()) << r.key;
    EXPECT_FALSE(r.def.empty()) << r.key;
  }
}

TEST(QnavdConfig, DocsCarryTheGeneratedKeyTable) {
  std::ifstream in(source_path("docs/configuration.md"));
  ASSERT_TRUE(in.good());
  std::stringstream doc;
  doc << in.rdbuf();
  EXPECT_NE(doc.str().find(config_keys_markdown()), std::string::npos)
      << "docs/configuration.md: paste the output of `qnavd --print-config-keys` under \"## Keys\"";
}

TEST(QnavdConfig, DocumentedDefaultsAreThoseOfADefaultConfig) {
  const std::vector<Row> rows = markdown_rows();
  // A file that sets every key to its documented default reads as DaemonConfig{} ...
  const std::string text =
      config_text(rows, [](const Row& r) { return r.def == "(required)" ? std::string() : r.def; });
  const DaemonConfig documented = expect_ok(text);
  // ... and so does a file that sets nothing but the one pass the sim backend needs.
  const DaemonConfig implicit = expect_ok(kOnePass);
  const DaemonConfig defaults;
  for (const Field& f : fields()) {
    EXPECT_EQ(f.get(documented), f.get(defaults)) << f.name << "\n" << text;
    EXPECT_EQ(f.get(implicit), f.get(defaults)) << f.name;
  }
  ASSERT_EQ(documented.sim_mission.size(), 1u);
  EXPECT_EQ(documented.sim_mission[0].offset_pct, SimPass{}.offset_pct);
  EXPECT_EQ(documented.sim_mission[0].reverse, SimPass{}.reverse);
}

// Sets every key to an in-range value other than its default.
constexpr const char* kEveryKey = R"(
[daemon]
backend = "linux"
route_dir = "/srv/routes"
log = "kv"
realtime = false
io_priority = 50
nav_priority = 40
io_cpu = 2
nav_cpu = 3
shutdown_timeout_s = 2.5
health_period_s = 10

[can]
interface = "can1"
attitude_stale_s = 0.25
depth_stale_s = 5.0
rx_queue = 1024
tx_queue = 128

[sonar]
source = "jsf_tcp"
address = "10.0.0.5:1701"
stale_s = 3.0
ping_queue = 64
max_samples_per_side = 4096

[dvl]
enabled = false
device = "/dev/ttyS1"
protocol = "pd6"
baud = 9600
stale_s = 0.5

[leak]
chip = "gpiochip3"
line = 5
active_low = true

[mavlink]
enabled = true
udp_remote = "192.168.2.1:14550"
udp_listen_port = 14560
serial_device = "/dev/ttyAMA0"
baud = 921600
system_id = 2
component_id = 191
odometry_hz = 20.0
guided = true
autopilot_system_id = 2
autopilot_component_id = 2
key_file = "/etc/qnav/mavlink.key"
origin_lat_deg = 47.25
origin_lon_deg = -122.5
origin_alt_m = 3.5

[vo]
enabled = false
preset = "euroc"
pair_tolerance_ms = 40.0
camera = "v4l2"
left_device = "/dev/video4"
right_device = "/dev/video5"
trigger_chip = "gpiochip2"
trigger_line = 17
rate_hz = 15.0
width = 640
height = 480
focal_px = 900.0
cu_px = 319.5
cv_px = 239.5
baseline_m = 0.12
tilt_down_deg = 45.0
mount_height_m = 1.2
max_corners = 500
vme = "6d"
attitude_filter = false
max_step_m = 1.5
frame_queue = 8
stale_s = 5.0

[map]
enabled = true
device = "/dev/video2"
width = 384
height = 288
focal_px = 405.6
cu_px = 189.9
cv_px = 139.9
altitude_m = 2.5
node_spacing = 0.3
max_nodes = 200
frame_queue = 8
stale_s = 4.0

[route]
id = 7
max_nodes = 20000
learn = true
entry_prior = 0.25
max_experiences = 2
tile_length_m = 0
tile_stride_m = 30.0
scanlines_per_tile = 500
scanline_stride = 250
resolution_m = 0.1
tile_px = 1024
ground_bins_per_side = 512
ground_bin_m = 0.1
max_keypoints = 64
belief_registrations = 8
searching_registrations = 40
min_inliers = 6
side_deadband_m = 2.0
dead_reckon_max_m = 300.0
motion = "eq5"

[budget]
ping_us = 5000
tile_us = 100000
mode_us = 300000
vo_us = 250000
map_us = 80000

[sim]
length_m = 5000.0
seed = 42
speed = "recorded"
can_interface = "vcan1"
exit_at_end = false
replay_lines = 300
replay_stride = 150
replay_nav = "dr"
ahrs = "dronecan"
candump = "/tmp/qnavd.candump"
closed_loop_csv = "/tmp/qnavd_closed_loop.csv"
stall = "dvl"
stall_pass = 0
stall_start_s = 30.0
stall_s = 20.0
fault = "disk_full"
fault_pass = 2
fault_start_s = 30.0
fault_s = 5.0

[[sim.pass]]
mode = "hold"
offset_pct = -55.5
reverse = true
length_m = 12.5
file = "dive.xtf"
first_ping = 90
last_ping = 461
candump = "dive.can"
dvl_log = "dive.dvl"
images = "dive_stereo"
max_frames = 30

[[sim.pass]]
mode = "repeat"
offset_pct = 100
closed_loop = true
)";

TEST(QnavdConfig, EveryKeyReachesItsFields) {
  // The file above names every documented key.
  std::set<std::string> documented, in_file;
  for (const Row& r : markdown_rows()) documented.insert(r.key);
  std::istringstream in(kEveryKey);
  std::string line, section;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    if (line[0] == '[') {
      section = line == "[[sim.pass]]" ? "sim.pass" : line.substr(1, line.size() - 2);
    } else {
      in_file.insert(section + "." + line.substr(0, line.find(' ')));
    }
  }
  EXPECT_EQ(in_file, documented);

  const DaemonConfig c = expect_ok(kEveryKey);
  const DaemonConfig defaults;
  for (const Field& f : fields()) EXPECT_NE(f.get(c), f.get(defaults)) << f.name << " kept its default";

  // The keys that set more than one field set all of them.
  EXPECT_EQ(c.localiser.filter.max_nodes, 20000u);
  EXPECT_EQ(c.tiles.tiles.tile_width_px, 1024);
  EXPECT_EQ(c.tiles.tiles.tile_height_px, 1024);
  EXPECT_EQ(c.tiles.features.max_width, 1024);
  EXPECT_EQ(c.tiles.features.max_height, 1024);
  EXPECT_EQ(c.tiles.corrector.ground_bins_per_side, 512);
  EXPECT_EQ(c.tiles.tiles.max_bins_per_side, 512);
  EXPECT_EQ(c.tiles.corrector.max_samples_per_side, 4096);
  EXPECT_EQ(c.localiser.filter.motion, route::MotionModel::kPaperEq5);
  EXPECT_EQ(c.localiser.window_slots, 41u);  // grown to hold every node of one searching update
  EXPECT_EQ(c.tiles.corrector.ground_bin_m, 0.1f);

  ASSERT_EQ(c.sim_mission.size(), 2u);
  EXPECT_EQ(c.sim_mission[0].mode, drivers::qnavcan::Mode::kHold);
  EXPECT_EQ(c.sim_mission[0].offset_pct, -55.5);
  EXPECT_TRUE(c.sim_mission[0].reverse);
  EXPECT_EQ(c.sim_mission[0].file, "dive.xtf");
  EXPECT_EQ(c.sim_mission[0].first_ping, 90);
  EXPECT_EQ(c.sim_mission[0].last_ping, 461);
  EXPECT_EQ(c.sim_mission[0].length_m, 12.5);
  EXPECT_EQ(c.sim_mission[0].candump, "dive.can");
  EXPECT_EQ(c.sim_mission[0].dvl_log, "dive.dvl");
  EXPECT_EQ(c.sim_mission[0].images, "dive_stereo");
  EXPECT_EQ(c.sim_mission[0].max_frames, 30);
  EXPECT_TRUE(c.sim_mission[1].closed_loop);
  EXPECT_EQ(c.vo_preset, VoPreset::kEuroc);
  EXPECT_EQ(c.vo.stereo.max_disparity_px, pipeline::euroc_vo_config(64, 64, 100.0, 10.0, 10.0, 0.1).stereo.max_disparity_px)
      << "the preset's settings that have no key";
  EXPECT_TRUE(c.vo_prior.zero_motion);
  EXPECT_EQ(c.sim_mission[1].mode, drivers::qnavcan::Mode::kRepeat);
  EXPECT_EQ(c.sim_mission[1].offset_pct, 100.0);  // an integer where a float is expected
  EXPECT_FALSE(c.sim_mission[1].reverse);
  EXPECT_TRUE(c.sim_mission[1].file.empty());
  EXPECT_EQ(c.sim_mission[1].last_ping, -1);
  EXPECT_TRUE(map_runs(c));  // the linux backend with a downward camera
  EXPECT_EQ(frame_pool_slots(c), 8u);
  EXPECT_EQ(frame_slot_bytes(c), 384u * 288u);  // vo.enabled = false: downward frames only
  expect_stages_init(c);
}

// Every key at the low end of its documented range (or first choice), then at the high end (or last
// choice): both load, and every nav stage initialises with them.
TEST(QnavdConfig, EveryConfigurationTheBoundsAllowInitialisesTheStages) {
  const std::vector<Row> rows = markdown_rows();
  for (const bool high : {false, true}) {
    const std::string text = config_text(rows, [high](const Row& r) -> std::string {
      std::string lo, hi;
      if (range_of(r, lo, hi)) return high ? hi : lo;
      // (sim.pass.closed_loop needs a repeat pass after a teach: its own rows in kBadConfigs, the demo's sim.toml)
      if (r.key == "sim.pass.closed_loop") return "";
      if (r.type == "boolean") return high ? "true" : "false";
      if (r.type == "string" && r.allowed[0] == '"') {
        const std::vector<std::string> items = list_of(r);
        return high ? items.back() : items.front();
      }
      if (r.type == "integer") {  // a list of values (dvl.baud)
        const std::vector<std::string> items = list_of(r);
        return high ? items.back() : items.front();
      }
      return "";  // free strings keep their defaults
    });
    SCOPED_TRACE(text);
    const DaemonConfig c = expect_ok(text);
    expect_stages_init(c);
  }
}

// sim.speed: a factor of real time, or the words it had before it was a number (issue #31).
TEST(QnavdConfig, SimSpeedIsAFactorOfRealTimeOrAWord) {
  EXPECT_EQ(expect_ok(kOnePass).sim_speed, 0.0);
  EXPECT_EQ(expect_ok("[sim]\nspeed = \"fast\"\n" + std::string(kOnePass)).sim_speed, SimSpeed::kFast);
  EXPECT_EQ(expect_ok("[sim]\nspeed = \"recorded\"\n" + std::string(kOnePass)).sim_speed, 1.0);
  EXPECT_EQ(expect_ok("[sim]\nspeed = 20\n" + std::string(kOnePass)).sim_speed, 20.0);
  EXPECT_EQ(expect_ok("[sim]\nspeed = 0.5\n" + std::string(kOnePass)).sim_speed, 0.5);
  const DaemonConfig c = expect_ok("[sim]\ncan_interface = \"vcan0\"\nspeed = 1\n" + std::string(kOnePass));
  EXPECT_EQ(c.sim_can_interface, "vcan0");
  EXPECT_EQ(c.sim_speed, 1.0);
}

// ---- Errors ---------------------------------------------------------------------------------------

struct BadConfig {
  const char* what;
  std::string text;
  const char* key;
  int line;
  const char* message;  // a part of the message
};

class QnavdConfigError : public ::testing::TestWithParam<BadConfig> {};

TEST_P(QnavdConfigError, NamesTheKeyAndTheLine) {
  const BadConfig& b = GetParam();
  const ConfigError err = expect_error(b.text);
  EXPECT_EQ(err.key, b.key) << err.to_string();
  EXPECT_EQ(err.line, b.line) << err.to_string();
  EXPECT_NE(err.message.find(b.message), std::string::npos) << err.to_string();
  EXPECT_EQ(err.file, "qnavd.toml");
}

std::string passes(int n) {
  std::string s = "[sim]\nseed = 3\n";
  for (int i = 0; i < n; ++i) s += "\n[[sim.pass]]\nmode = \"repeat\"\n";
  return s;
}

const BadConfig kBadConfigs[] = {
    {"syntax", "[daemon]\nlog = \"json\"\nbackend = \n", "", 3, "expected value"},
    {"unterminated_string", "[daemon]\nroute_dir = \"routes\n", "", 2, ""},
    {"duplicate_key", "[daemon]\nio_cpu = 1\nio_cpu = 2\n", "", 3, ""},
    {"unknown_key", "[route]\nid = 3\n\nmax_node = 5000\n", "route.max_node", 4,
     "unknown key (did you mean route.max_nodes?)"},
    {"unknown_key_far", "[dvl]\nbaudrate = 9600\n", "dvl.baudrate", 2, "unknown key"},
    {"unknown_key_other_table", "[leak]\nstale_s = 1.0\n", "leak.stale_s", 2,
     "did you mean sonar.stale_s or dvl.stale_s or vo.stale_s or map.stale_s?"},
    {"unknown_key_near_another_table", "[can]\nstale_s = 1.0\n", "can.stale_s", 2, "did you mean map.stale_s?"},
    {"key_outside_tables", "backend = \"linux\"\n", "backend", 1, "did you mean daemon.backend?"},
    {"unknown_table", "[daemon]\nlog = \"off\"\n[rout]\nid = 2\n", "rout", 3, "unknown table (did you mean [route]?)"},
    {"unknown_table_far", "[logging]\nlevel = 2\n", "logging", 1, "unknown table; the tables are [daemon], [can]"},
    {"unknown_subtable", "[daemon.extra]\nx = 1\n", "daemon.extra", 1, "unknown table"},
    {"table_is_a_value", "daemon = 3\n", "daemon", 1, "expected a table, got an integer"},
    {"string_for_integer", "[daemon]\nio_priority = \"high\"\n", "daemon.io_priority", 2,
     "expected an integer, got a string"},
    {"float_for_integer", "[daemon]\nio_priority = 2.5\n", "daemon.io_priority", 2, "expected an integer, got a float"},
    {"string_for_float", "[can]\ndepth_stale_s = \"2\"\n", "can.depth_stale_s", 2, "expected a number, got a string"},
    {"integer_for_bool", "[daemon]\nrealtime = 1\n", "daemon.realtime", 2,
     "expected a boolean (true or false), got an integer"},
    {"date_for_string", "[daemon]\nroute_dir = 2024-01-01\n", "daemon.route_dir", 2, "expected a string, got a date"},
    {"integer_out_of_range", "[daemon]\nio_priority = 120\n", "daemon.io_priority", 2, "must be in [1, 99], got 120"},
    {"float_out_of_range", "[can]\nattitude_stale_s = 0.001\n", "can.attitude_stale_s", 2,
     "must be in [0.01, 10], got 0.001"},
    {"negative_size", "[sonar]\nmax_samples_per_side = -1024\n", "sonar.max_samples_per_side", 2,
     "must be in [64, 16384], got -1024"},
    {"seed_beyond_32_bits", "[sim]\nseed = 4294967296\n", "sim.seed", 2, "must be in [0, 4294967295]"},
    {"bad_enum", "[daemon]\nbackend = \"sym\"\n", "daemon.backend", 2, "must be one of sim, linux, got \"sym\""},
    {"bad_baud", "[dvl]\nbaud = 1200\n", "dvl.baud", 2, "must be one of 9600, 19200"},
    {"queue_not_power_of_two", "[can]\nrx_queue = 100\n", "can.rx_queue", 2,
     "must be a power of two in [16, 4096], got 100"},
    {"negative_queue", "[sonar]\nping_queue = -32\n", "sonar.ping_queue", 2,
     "must be a power of two in [4, 1024], got -32"},
    {"nan", "[daemon]\nshutdown_timeout_s = nan\n", "daemon.shutdown_timeout_s", 2, "must be a finite number, got nan"},
    {"inf", "[sim]\nlength_m = +inf\n", "sim.length_m", 2, "must be a finite number, got inf"},
    {"empty_route_dir", "[daemon]\nroute_dir = \"\"\n", "daemon.route_dir", 2, "must not be empty"},
    {"interface_too_long", "[can]\ninterface = \"a_very_long_can_name\"\n", "can.interface", 2, "1 to 15 characters"},
    {"address_without_port", "[sonar]\naddress = \"192.168.1.20\"\n", "sonar.address", 2, "must be HOST:PORT"},
    {"port_out_of_range", "[sonar]\naddress = \"host:70000\"\n", "sonar.address", 2, "must be HOST:PORT"},
    {"stride_beyond_tile", "[route]\ntile_length_m = 0\nscanlines_per_tile = 100\nscanline_stride = 150\n" + std::string(kOnePass),
     "route.scanline_stride", 4, "must be <= route.scanlines_per_tile (100), got 150"},
    {"ping_stride_beyond_tile_by_distance", "[route]\nscanline_stride = 2000\n" + std::string(kOnePass), "route.scanline_stride", 2,
     "must be <= route.scanlines_per_tile (1802), got 2000"},
    {"by_ping_count_without_pings", "[route]\ntile_length_m = 0\n" + std::string(kOnePass), "route.tile_length_m", 2,
     "0 frames tiles by ping count: give route.scanlines_per_tile"},
    {"tile_stride_beyond_length", "[route]\ntile_length_m = 40.0\ntile_stride_m = 50.0\n" + std::string(kOnePass), "route.tile_stride_m", 3,
     "must be <= route.tile_length_m (40), got 50"},
    {"negative_tile_length", "[route]\ntile_length_m = -5.0\n", "route.tile_length_m", 2, "must be in [0, 5000]"},
    {"searching_below_belief",
     "[route]\nbelief_registrations = 8\nsearching_registrations = 6\n" + std::string(kOnePass),
     "route.searching_registrations", 3, "must be >= route.belief_registrations (8), got 6"},
    {"belief_beyond_what_the_filter_keeps", "[route]\nbelief_registrations = 60\nsearching_registrations = 64\n",
     "route.belief_registrations", 2, "must be in [1, 58], got 60"},
    {"sim_without_passes", "[daemon]\nbackend = \"sim\"\n", "sim.pass", 2, "needs at least one [[sim.pass]]"},
    {"sim_by_default_without_passes", "[sim]\nseed = 2\n", "sim.pass", 0, "needs at least one [[sim.pass]]"},
    {"too_many_passes", passes(17), "sim.pass", 4 + 16 * 3, "at most 16 passes"},
    {"pass_as_table", "[sim.pass]\nmode = \"teach\"\n", "sim.pass", 1,
     "expected an array of tables ([[sim.pass]]), got a table"},
    {"pass_without_mode", "[[sim.pass]]\nmode = \"teach\"\n\n[[sim.pass]]\noffset_pct = 5\n", "sim.pass[1]", 4,
     "missing mode"},
    {"pass_bad_mode", "[[sim.pass]]\nmode = \"fly\"\n", "sim.pass[0].mode", 2,
     "must be one of teach, repeat, hold, vo, map, got \"fly\""},
    {"pass_unknown_key", "[[sim.pass]]\nmode = \"teach\"\noffset = 5\n", "sim.pass[0].offset", 3,
     "a [[sim.pass]] has mode, offset_pct, reverse, length_m, file, first_ping, last_ping, candump, dvl_log, images, max_frames"},
    {"closed_loop_in_a_teach_pass", "[[sim.pass]]\nmode = \"teach\"\nclosed_loop = true\n", "sim.pass[0].closed_loop", 3,
     "a closed-loop pass is a simulated repeat"},
    {"closed_loop_without_a_teach", "[[sim.pass]]\nmode = \"repeat\"\nclosed_loop = true\n", "sim.pass[0].closed_loop", 3,
     "needs a simulated teach pass before it"},
    {"images_in_a_teach_pass", "[[sim.pass]]\nmode = \"teach\"\nimages = \"seq\"\n", "sim.pass[0].images", 3,
     "a stereo sequence is replayed in a pass with mode = \"vo\""},
    {"logs_with_the_simulated_rover", "[[sim.pass]]\nmode = \"vo\"\ncandump = \"dive.log\"\n", "sim.pass[0].images", 3,
     "not with the simulated rover"},
    {"last_ping_before_first", "[[sim.pass]]\nmode = \"teach\"\nfile = \"dive.xtf\"\nfirst_ping = 50\nlast_ping = 20\n", "sim.pass[0].last_ping", 5,
     "must be -1 or > first_ping (50), got 20"},
    {"downward_camera_on_sim", "[map]\nenabled = true\ndevice = \"/dev/video2\"\n\n[[sim.pass]]\nmode = \"map\"\n", "map.device", 3,
     "daemon.backend = \"sim\" flies the simulated downward camera"},
    {"max_frames_negative", "[[sim.pass]]\nmode = \"vo\"\nmax_frames = -1\n", "sim.pass[0].max_frames", 3, "must be in [0, 1000000], got -1"},
    {"pass_misspelt_key", "[[sim.pass]]\nmode = \"teach\"\nreverse_ = true\n", "sim.pass[0].reverse_", 3,
     "did you mean reverse?"},
    {"pass_offset_out_of_range", "[[sim.pass]]\nmode = \"repeat\"\noffset_pct = 120\n", "sim.pass[0].offset_pct", 3,
     "must be in [-100, 100], got 120"},
    {"pass_offset_nan", "[[sim.pass]]\nmode = \"repeat\"\noffset_pct = nan\n", "sim.pass[0].offset_pct", 3,
     "must be a finite number"},
    {"pass_reverse_not_bool", "[[sim.pass]]\nmode = \"repeat\"\nreverse = \"yes\"\n", "sim.pass[0].reverse", 3,
     "expected a boolean"},
    {"stall_beyond_the_mission",
     "[sim]\nstall = \"dvl\"\nstall_pass = 2\n\n[[sim.pass]]\nmode = \"teach\"\n\n[[sim.pass]]\nmode = \"repeat\"\n",
     "sim.stall_pass", 3, "must be < the number of [[sim.pass]] (2), got 2"},
    {"stall_default_pass_beyond_the_mission", "[sim]\nstall = \"sonar\"\n" + std::string(kOnePass), "sim.stall_pass", 2,
     "must be < the number of [[sim.pass]] (1), got 1"},
    {"speed_bad_word", "[sim]\nspeed = \"slow\"\n", "sim.speed", 2, "must be a number in [0, 1000] or one of \"fast\", \"recorded\", got \"slow\""},
    {"speed_negative", "[sim]\nspeed = -1\n", "sim.speed", 2, "must be in [0, 1000]"},
    {"speed_too_fast", "[sim]\nspeed = 1e4\n", "sim.speed", 2, "must be in [0, 1000]"},
    {"speed_nan", "[sim]\nspeed = nan\n", "sim.speed", 2, "must be a finite number"},
    {"sim_can_interface_bad_name", "[sim]\ncan_interface = \"vcan0:1\"\n", "sim.can_interface", 2, "must be a network interface name"},
    {"error_frames_on_a_real_interface", "[sim]\ncan_interface = \"vcan0\"\nfault = \"can_error_frames\"\nfault_pass = 0\n" + std::string(kOnePass),
     "sim.fault", 3, "user space cannot send them on a SocketCAN interface"},
    {"bad_stall", "[sim]\nstall = \"gps\"\n", "sim.stall", 2, "must be one of none, dvl, attitude, sonar, camera, got \"gps\""},
    // toml++ keeps a table's keys sorted by name, not by line: the error nearest the top is reported.
    {"first_error_by_line", "[daemon]\nnav_priority = 0\n[can]\nrx_queue = 3\n", "daemon.nav_priority", 2,
     "must be in [1, 99], got 0"},
};

INSTANTIATE_TEST_SUITE_P(Classes, QnavdConfigError, ::testing::ValuesIn(kBadConfigs),
                         [](const ::testing::TestParamInfo<BadConfig>& p) { return std::string(p.param.what); });

TEST(QnavdConfig, SixteenPassesAreAllowed) {
  const DaemonConfig c = expect_ok(passes(16));
  EXPECT_EQ(c.sim_mission.size(), 16u);
}

TEST(QnavdConfig, ErrorReadsFileLineKeyMessage) {
  const ConfigError err = expect_error("[daemon]\nio_priority = 0\n");
  EXPECT_EQ(err.to_string(), "qnavd.toml:2: daemon.io_priority: must be in [1, 99], got 0");
  const ConfigError syntax = expect_error("[daemon\n");
  EXPECT_EQ(syntax.to_string().rfind("qnavd.toml:1: ", 0), 0u) << syntax.to_string();
}

TEST(QnavdConfig, MissingFileGivesTheSystemsReason) {
  DaemonConfig c;
  ConfigError err;
  const std::string path = source_path("firmware/qnavd/config/no_such_file.toml");
  EXPECT_FALSE(load_config(path.c_str(), c, err));
  EXPECT_EQ(err.file, path);
  EXPECT_EQ(err.line, 0);
  EXPECT_EQ(err.to_string(), path + ": cannot open: " + std::strerror(ENOENT));
}

TEST(QnavdConfig, ADirectoryIsNotAConfigFile) {
  DaemonConfig c;
  ConfigError err;
  EXPECT_FALSE(load_config(QNAV_SOURCE_DIR, c, err));
  EXPECT_NE(err.message.find(std::strerror(EISDIR)), std::string::npos) << err.to_string();
}

TEST(QnavdConfig, AFailedParseLeavesTheDefaults) {
  DaemonConfig c = expect_ok(kEveryKey);
  ConfigError err;
  EXPECT_FALSE(parse_config("[daemon]\nroute_dir = \"/x\"\nio_cpu = 99\n", "qnavd.toml", c, err));
  const DaemonConfig defaults;
  for (const Field& f : fields()) EXPECT_EQ(f.get(c), f.get(defaults)) << f.name;
  EXPECT_TRUE(c.sim_mission.empty());
}

TEST(QnavdConfig, InlineAndDottedTablesAreTheSameKeys) {
  const DaemonConfig c = expect_ok(
      "daemon = { log = \"off\", io_cpu = 1 }\n"
      "route.id = 9\n"
      "sim.pass = [ { mode = \"teach\" }, { mode = \"repeat\", reverse = true } ]\n");
  EXPECT_EQ(c.log, LogFormat::kOff);
  EXPECT_EQ(c.io_cpu, 1);
  EXPECT_EQ(c.route_id, 9);
  ASSERT_EQ(c.sim_mission.size(), 2u);
  EXPECT_TRUE(c.sim_mission[1].reverse);
}

}  // namespace
}  // namespace qnav::daemon
