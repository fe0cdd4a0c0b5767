#include "firmware/tools/hil_player.hpp"

#define TOML_ASSERT(expr) static_cast<void>(0)  // as in firmware/qnavd/config.cpp: errors, never abort
#include <toml++/toml.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
#include <thread>

#include "drivers/sidescan/jsf_parser.hpp"
#include "drivers/dvl/wl_parser.hpp"
#include "drivers/route_store/route_file.hpp"
#include "drivers/route_store/route_open.hpp"
#include "firmware/pipeline/closed_loop.hpp"
#include "firmware/pipeline/dead_reckoner.hpp"
#include "firmware/tools/sim_dive.hpp"
#include "firmware/tools/text_file.hpp"
#include "hal/linux/posix_file_store.hpp"
#include "hal/core/candump.hpp"
#include "hal/linux/monotonic_clock.hpp"
#include "hal/linux/pty_device.hpp"
#include "hal/linux/socketcan_bus.hpp"
#include "hal/linux/tcp_server_port.hpp"
#include "nav/core/byte_order.hpp"

namespace qnav::tools {
namespace qc = drivers::qnavcan;

namespace {

constexpr std::size_t kMaxDiveBytes = std::size_t{512} << 20;

// Strict reading of one TOML table: every key must be known, of its type and within its range.
class TableReader {
 public:
  TableReader(const toml::table& t, std::string where, std::string& error) : t_(t), where_(std::move(where)), error_(error) {}

  bool only(std::initializer_list<const char*> keys) {
    for (const auto& kv : t_) {
      bool known = false;
      for (const char* k : keys) known = known || kv.first.str() == k;
      if (!known) return fail(std::string(kv.first.str()), kv.second.source().begin.line, "unknown key");
    }
    return true;
  }
  bool number(const char* key, double& v, double lo, double hi) {
    const toml::node* n = t_.get(key);
    if (n == nullptr) return true;
    if (!n->is_number()) return fail(key, n->source().begin.line, "must be a number");
    const double x = n->is_integer() ? static_cast<double>(n->as_integer()->get()) : n->as_floating_point()->get();
    if (!(x >= lo && x <= hi)) return fail(key, n->source().begin.line, "out of range [" + fmt(lo) + ", " + fmt(hi) + "]");
    v = x;
    return true;
  }
  bool integer(const char* key, long long& v, long long lo, long long hi) {
    const toml::node* n = t_.get(key);
    if (n == nullptr) return true;
    if (!n->is_integer()) return fail(key, n->source().begin.line, "must be an integer");
    const long long x = n->as_integer()->get();
    if (x < lo || x > hi) return fail(key, n->source().begin.line, "out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    v = x;
    return true;
  }
  bool boolean(const char* key, bool& v) {
    const toml::node* n = t_.get(key);
    if (n == nullptr) return true;
    if (!n->is_boolean()) return fail(key, n->source().begin.line, "must be true or false");
    v = n->as_boolean()->get();
    return true;
  }
  bool text(const char* key, std::string& v, bool* present = nullptr) {
    const toml::node* n = t_.get(key);
    if (present != nullptr) *present = n != nullptr;
    if (n == nullptr) return true;
    if (!n->is_string()) return fail(key, n->source().begin.line, "must be a string");
    v = n->as_string()->get();
    return true;
  }
  bool fail(const std::string& key, std::uint32_t line, const std::string& what) {
    error_ = where_ + (key.empty() ? "" : "." + key) + " (line " + std::to_string(line) + "): " + what;
    return false;
  }

 private:
  static std::string fmt(double x) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", x);
    return b;
  }
  const toml::table& t_;
  std::string where_;
  std::string& error_;
};

std::string relative_to(const std::string& dir, const std::string& p) {
  if (p.empty() || p[0] == '/' || dir.empty()) return p;
  return dir + "/" + p;
}

bool parse_mode(const std::string& s, qc::Mode& m) {
  static const struct {
    const char* name;
    qc::Mode mode;
  } kModes[] = {{"idle", qc::Mode::kIdle}, {"teach", qc::Mode::kTeach}, {"repeat", qc::Mode::kRepeat},
                {"map", qc::Mode::kMap},   {"hold", qc::Mode::kHold},   {"vo", qc::Mode::kVo}};
  for (const auto& k : kModes) {
    if (s == k.name) {
      m = k.mode;
      return true;
    }
  }
  return false;
}

bool read_pass(const toml::table& t, int index, const std::string& dir, HilPass& p, std::string& error) {
  TableReader r(t, "pass[" + std::to_string(index) + "]", error);
  if (!r.only({"name", "jsf", "dvl", "candump", "mode", "route", "reverse", "lead_s", "pings", "idle_after", "after_s", "silence", "closed_loop",
               "seed", "pass_seed", "samples", "length_m", "speed_mps", "range_m", "offset_m", "start_s", "guidance_age_s", "teach_truth",
               "route_file", "truth_csv"}))
    return false;
  if (!r.boolean("closed_loop", p.closed_loop) || !r.integer("seed", p.seed, 0, 1000000000) || !r.integer("pass_seed", p.pass_seed, 0, 1000000000) ||
      !r.integer("samples", p.samples, 64, 16384) || !r.number("length_m", p.length_m, 10.0, 50000.0) ||
      !r.number("speed_mps", p.speed_mps, 0.1, 20.0) || !r.number("range_m", p.range_m, 1.0, 1000.0) ||
      !r.number("offset_m", p.offset_m, -1000.0, 1000.0) || !r.number("start_s", p.start_s, 0.0, 4e9) ||
      !r.number("guidance_age_s", p.guidance_age_s, 0.0, 600.0) || !r.text("teach_truth", p.teach_truth) ||
      !r.text("route_file", p.route_file) || !r.text("truth_csv", p.truth_csv))
    return false;
  std::string mode;
  long long route = 0, pings = 0;
  if (!r.text("name", p.name) || !r.text("jsf", p.jsf) || !r.text("dvl", p.dvl) || !r.text("candump", p.candump) ||
      !r.text("mode", mode, &p.send_mode) || !r.integer("route", route, 0, 65535) || !r.boolean("reverse", p.reverse) ||
      !r.number("lead_s", p.lead_s, 0.0, 600.0) || !r.integer("pings", pings, 0, 10000000) ||
      !r.boolean("idle_after", p.idle_after) || !r.number("after_s", p.after_s, 0.0, 600.0)) {
    return false;
  }
  if (p.send_mode && !parse_mode(mode, p.mode)) {
    return r.fail("mode", t.get("mode")->source().begin.line, "must be one of idle, teach, repeat, map, hold, vo; got \"" + mode + "\"");
  }
  if (p.name.empty()) p.name = "pass" + std::to_string(index);
  p.route = static_cast<std::uint16_t>(route);
  p.pings = static_cast<int>(pings);
  p.jsf = relative_to(dir, p.jsf), p.dvl = relative_to(dir, p.dvl), p.candump = relative_to(dir, p.candump);
  if (p.closed_loop) {
    if (!p.jsf.empty() || !p.dvl.empty() || !p.candump.empty())
      return r.fail("closed_loop", t.get("closed_loop")->source().begin.line, "a closed-loop pass flies live: no jsf, dvl or candump");
    if (p.teach_truth.empty() || p.route_file.empty())
      return r.fail("closed_loop", t.get("closed_loop")->source().begin.line, "needs teach_truth and route_file (the taught track)");
    p.teach_truth = relative_to(dir, p.teach_truth);
    if (!p.truth_csv.empty()) p.truth_csv = relative_to(dir, p.truth_csv);
  } else if (p.jsf.empty() && p.dvl.empty() && p.candump.empty()) {
    return r.fail("", t.source().begin.line, "plays nothing: give jsf, dvl or candump");
  }
  if (const toml::node* s = t.get("silence")) {
    const toml::array* a = s->as_array();
    if (a == nullptr || !a->is_array_of_tables()) return r.fail("silence", s->source().begin.line, "must be [[pass.silence]] tables");
    int k = 0;
    for (const toml::node& n : *a) {
      TableReader sr(*n.as_table(), "pass[" + std::to_string(index) + "].silence[" + std::to_string(k++) + "]", error);
      HilSilence q;
      std::string stream;
      if (!sr.only({"stream", "from_s", "to_s"}) || !sr.text("stream", stream) || !sr.number("from_s", q.from_s, 0.0, 1e6) ||
          !sr.number("to_s", q.to_s, 0.0, 1e6)) {
        return false;
      }
      if (stream == "sonar") {
        q.stream = HilStream::kSonar;
      } else if (stream == "dvl") {
        q.stream = HilStream::kDvl;
      } else if (stream == "ahrs") {
        q.stream = HilStream::kAhrs;
      } else {
        return sr.fail("stream", n.source().begin.line, "must be sonar, dvl or ahrs; got \"" + stream + "\"");
      }
      if (!(q.to_s > q.from_s)) return sr.fail("to_s", n.source().begin.line, "must be after from_s");
      p.silences.push_back(q);
    }
  }
  return true;
}

}  // namespace

std::size_t HilDive::pings() const {
  std::size_t n = 0;
  for (std::size_t k : {jsf_pings.size(), dvl_lines.size(), ahrs.size()}) {
    if (k > 0 && (n == 0 || k < n)) n = k;
  }
  return n;
}

bool load_hil_scenario(const char* path, HilScenario& out, std::string& error) {
  std::string text;
  if (Status s = read_text_file(path, std::size_t{1} << 20, text); !s) {
    error = s.message();
    return false;
  }
  toml::table root;
  try {
    root = toml::parse(text, std::string_view(path));
  } catch (const toml::parse_error& e) {
    error = std::string(path) + " (line " + std::to_string(e.source().begin.line) + "): " + std::string(e.description());
    return false;
  }
  std::string dir(path);
  const std::size_t slash = dir.rfind('/');
  dir = slash == std::string::npos ? std::string() : dir.substr(0, slash);
  HilScenario sc;
  TableReader r(root, std::string(path), error);
  if (!r.only({"rate_hz", "can", "sonar_listen", "dvl_pty", "played", "wait_connect_s", "pass"}) || !r.number("rate_hz", sc.rate_hz, 0.1, 1000.0) ||
      !r.text("can", sc.can_interface) || !r.text("sonar_listen", sc.sonar_listen) || !r.text("dvl_pty", sc.dvl_pty) ||
      !r.text("played", sc.played) || !r.number("wait_connect_s", sc.wait_connect_s, 0.0, 600.0)) {
    return false;
  }
  sc.played = relative_to(dir, sc.played);
  const toml::array* passes = root.get("pass") != nullptr ? root.get("pass")->as_array() : nullptr;
  if (passes == nullptr || passes->empty() || !passes->is_array_of_tables()) {
    error = std::string(path) + ": no [[pass]] tables (a scenario plays one or more passes)";
    return false;
  }
  int k = 0;
  for (const toml::node& n : *passes) {
    HilPass p;
    if (!read_pass(*n.as_table(), k++, dir, p, error)) {
      error = std::string(path) + ": " + error;
      return false;
    }
    if (p.send_mode && sc.can_interface.empty()) {
      error = std::string(path) + ": pass " + p.name + " sends a mode command but `can` (the interface) is not set";
      return false;
    }
    sc.passes.push_back(std::move(p));
  }
  out = std::move(sc);
  return true;
}

bool load_hil_dive(const HilPass& pass, HilDive& out, std::string& error) {
  HilDive d;
  std::string bytes;
  if (!pass.jsf.empty()) {
    if (Status s = read_binary_file(pass.jsf.c_str(), kMaxDiveBytes, bytes); !s) {
      error = s.message();
      return false;
    }
    // A ping is the run of messages up to the last sonar data message (80) with its ping number.
    const auto* b = reinterpret_cast<const std::uint8_t*>(bytes.data());
    std::size_t off = 0, start = 0;
    long long cur = -1;
    if (bytes.size() < sidescan::kJsfHeaderBytes) {
      error = pass.jsf + ": shorter than one JSF message header (16 bytes): nothing to play";
      return false;
    }
    while (off + sidescan::kJsfHeaderBytes <= bytes.size()) {
      if (load_le_u16(b + off) != sidescan::kJsfSync) {
        error = pass.jsf + ": no JSF sync word at byte " + std::to_string(off) + " (not a JSF file, or damaged)";
        return false;
      }
      const std::size_t size = load_le_u32(b + off + 12);
      const std::uint16_t type = load_le_u16(b + off + 4);
      const std::size_t next = off + sidescan::kJsfHeaderBytes + size;
      if (next > bytes.size()) break;  // a torn last message: not played
      if (type == 80 && size >= 12) {
        const long long ping = load_le_u32(b + off + sidescan::kJsfHeaderBytes + 8);
        if (cur >= 0 && ping != cur) {
          d.jsf_pings.emplace_back(bytes, start, off - start);
          start = off;
        }
        cur = ping;
      }
      off = next;
    }
    if (cur >= 0) d.jsf_pings.emplace_back(bytes, start, off - start);
    if (d.jsf_pings.empty()) {
      error = pass.jsf + ": no sonar data message (type 80): nothing to play";
      return false;
    }
  }
  if (!pass.dvl.empty()) {
    if (Status s = read_text_file(pass.dvl.c_str(), kMaxDiveBytes, bytes); !s) {
      error = s.message();
      return false;
    }
    for (std::size_t a = 0; a < bytes.size();) {
      std::size_t e = bytes.find('\n', a);
      e = e == std::string::npos ? bytes.size() : e + 1;
      if (e - a > 1) d.dvl_lines.emplace_back(bytes, a, e - a);
      a = e;
    }
    if (d.dvl_lines.empty()) {
      error = pass.dvl + ": empty: no DVL sentence to play";
      return false;
    }
  }
  if (!pass.candump.empty()) {
    if (Status s = read_text_file(pass.candump.c_str(), kMaxDiveBytes, bytes); !s) {
      error = s.message();
      return false;
    }
    int line_no = 0;
    for (std::size_t a = 0; a < bytes.size();) {
      std::size_t e = bytes.find('\n', a);
      e = e == std::string::npos ? bytes.size() : e;
      ++line_no;
      hal::CanLogRecord rec;
      if (e > a) {
        if (Status s = hal::parse_can_log_line(bytes.data() + a, e - a, rec); !s) {
          error = pass.candump + " line " + std::to_string(line_no) + ": " + s.message() + " (want candump -l lines)";
          return false;
        }
        d.ahrs.push_back(rec.frame);
      }
      a = e + 1;
    }
    if (d.ahrs.empty()) {
      error = pass.candump + ": no CAN frame to play";
      return false;
    }
  }
  out = std::move(d);
  return true;
}

namespace {

// The devices of a scenario and the sending of one stream's item.
class Vehicle {
 public:
  Vehicle(const HilScenario& sc, std::FILE* log, HilPlayStats& st) : sc_(sc), log_(log), st_(st) {}

  bool open(std::string& error) {
    if (!sc_.can_interface.empty()) {
      hal::SocketCanConfig c;
      c.interface = sc_.can_interface.c_str();
      c.error_mask = 0;
      // The player only sends unless a pass flies in closed loop (then it reads qnavd's guidance).
      c.receive = false;
      for (const HilPass& p : sc_.passes) c.receive = c.receive || p.closed_loop;
      if (Status s = can_.open(c); !s) return fail(error, "CAN " + sc_.can_interface + ": " + s.message());
    }
    if (!sc_.dvl_pty.empty()) {
      if (Status s = dvl_.open(sc_.dvl_pty.c_str()); !s) return fail(error, std::string("DVL: ") + s.message());
      std::fprintf(log_, "hil play: DVL on %s -> %s\n", sc_.dvl_pty.c_str(), dvl_.slave_path());
    }
    if (!sc_.sonar_listen.empty()) {
      const std::size_t colon = sc_.sonar_listen.rfind(':');
      const long port = colon == std::string::npos ? -1 : std::strtol(sc_.sonar_listen.c_str() + colon + 1, nullptr, 10);
      if (port <= 0 || port > 65535) return fail(error, "sonar_listen: want IPv4:port, got \"" + sc_.sonar_listen + "\"");
      const std::string host = sc_.sonar_listen.substr(0, colon);
      if (Status s = sonar_.listen(host.c_str(), static_cast<std::uint16_t>(port)); !s) return fail(error, std::string("sonar: ") + s.message());
      std::fprintf(log_, "hil play: sonar data port %s listening\n", sc_.sonar_listen.c_str());
    }
    return true;
  }
  void wait_for_sonar_client() {
    if (sc_.sonar_listen.empty()) return;
    const std::int64_t until = hal::monotonic_now_ns() + static_cast<std::int64_t>(sc_.wait_connect_s * 1e9);
    while (!sonar_.poll_accept() && hal::monotonic_now_ns() < until) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    std::fprintf(log_, "hil play: sonar client %s\n", sonar_.connected() ? "connected" : "not connected (pings are counted as unsent)");
  }
  void mode(qc::Mode m, std::uint16_t route, bool reverse) {
    qc::ModeCmd cmd;
    cmd.mode = m, cmd.route_id = route, cmd.reverse = reverse, cmd.counter = mode_counter_++;
    hal::CanFrame f;
    if (qc::encode(cmd, f) && send(f)) ++st_.mode_sent;
  }
  void ahrs(hal::CanFrame f) {
    qc::AttitudeIn a;
    if (f.id == qc::kIdAttitudeIn && !f.extended && qc::decode(f, a)) {
      a.counter = ahrs_counter_++;  // a live AHRS counts on: a replayed log must not repeat counters
      (void)qc::encode(a, f);
    }
    if (send(f)) ++st_.ahrs_sent;
  }
  void dvl(const std::string& line) {
    const Result<std::size_t> n = dvl_.write(Span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(line.data()), line.size()));
    if (n.is_ok() && n.value() == line.size()) ++st_.dvl_sent;
    (void)dvl_.drain();  // what the daemon writes to the DVL (nothing is expected)
  }
  void sonar(const std::string& ping) {
    (void)sonar_.poll_accept();
    if (sonar_.connected() &&
        sonar_.write(Span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(ping.data()), ping.size()), 200)) {
      ++st_.sonar_sent;
    } else {
      ++st_.sonar_unsent;
    }
  }
  bool receive(hal::CanRxFrame& rx) { return can_.is_open() && can_.receive(rx, 0).is_ok(); }
  void finish() {
    st_.sonar_connections = sonar_.connections();
    st_.sonar_drops = sonar_.drops();
  }

 private:
  bool send(const hal::CanFrame& f) {
    if (can_.is_open() && can_.send(f)) return true;
    ++st_.can_errors;
    return false;
  }
  static bool fail(std::string& error, const std::string& what) {
    error = what;
    return false;
  }
  const HilScenario& sc_;
  std::FILE* log_;
  HilPlayStats& st_;
  hal::SocketCanBus can_;
  hal::PtyDevice dvl_;
  hal::TcpServerPort sonar_;
  std::uint8_t mode_counter_ = 1, ahrs_counter_ = 0;
};

bool silenced(const HilPass& p, HilStream s, double t_s) {
  for (const HilSilence& q : p.silences) {
    if (q.stream == s && t_s >= q.from_s && t_s < q.to_s) return true;
  }
  return false;
}

void sleep_until_ns(std::int64_t t_ns) {
  const std::int64_t d = t_ns - hal::monotonic_now_ns();
  if (d > 0) std::this_thread::sleep_for(std::chrono::nanoseconds(d));
}

// Hovering: the AHRS frame repeated at the ping rate for `seconds`, nothing else.
void hover(Vehicle& v, const hal::CanFrame* frame, double rate_hz, double seconds) {
  const std::int64_t t0 = hal::monotonic_now_ns(), period = static_cast<std::int64_t>(1e9 / rate_hz);
  for (std::int64_t k = 0; static_cast<double>(k * period) < seconds * 1e9; ++k) {
    sleep_until_ns(t0 + k * period);
    if (frame != nullptr) v.ahrs(*frame);
  }
  sleep_until_ns(t0 + static_cast<std::int64_t>(seconds * 1e9));
}

// The AHRS frame of a compass heading (rad; qnav's QNAV_ATTITUDE_IN).
hal::CanFrame attitude_frame(double heading_rad) {
  const qc::AttitudeIn a = qc::attitude_from_heading(heading_rad);
  hal::CanFrame f;
  (void)qc::encode(a, f);
  return f;
}

// The teach dive's navigation as the autopilot logged it (every 10 m, qnavd's teach frame: the dive's
// dead reckoning less its first ping's position), from `qnav sonar simulate --truth-csv`.
bool read_teach_log(const std::string& path, std::vector<Pose2>& log, std::vector<double>& dist, std::string& error) {
  std::string text;
  if (Status s = read_text_file(path.c_str(), kMaxDiveBytes, text); !s) {
    error = path + ": " + s.message();
    return false;
  }
  std::size_t a = text.find('\n');
  Pose2 first{}, prev{}, last{};
  bool have = false;
  double d = 0.0, since = 0.0;
  while (a != std::string::npos && a + 1 < text.size()) {
    const std::size_t e = text.find('\n', a + 1);
    const std::string line = text.substr(a + 1, e == std::string::npos ? std::string::npos : e - a - 1);
    a = e;
    double v[9];
    if (std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &v[6], &v[7], &v[8]) != 9) continue;
    const Pose2 nav{v[6], v[7], v[8]};
    if (!have) first = prev = nav;
    const double step = (nav.translation() - prev.translation()).norm();
    d += step, since += step;
    prev = nav;
    last = Pose2{nav.x_m - first.x_m, nav.y_m - first.y_m, nav.heading_rad};
    if (!have || since >= 10.0) {
      log.push_back(last);
      dist.push_back(d);
      since = 0.0;
    }
    have = true;
  }
  if (log.size() < 2) {
    error = path + ": fewer than two navigation rows (want the CSV of qnav sonar simulate --truth-csv)";
    return false;
  }
  log.push_back(last);
  dist.push_back(d);
  return true;
}

// One closed-loop pass, live (HilPass::closed_loop): see hil_player.hpp.
bool fly_closed_loop(Vehicle& v, const HilScenario& sc, const HilPass& p, std::size_t pass_index, std::FILE* played, std::FILE* log,
                     HilPlayStats& st, std::string& error) {
  std::vector<Pose2> teach;
  std::vector<double> dist;
  if (!read_teach_log(p.teach_truth, teach, dist, error)) return false;
  drivers::route_store::RouteFileReader reader(hal::host_file_store());
  std::vector<route::NodeMeta> meta;
  const drivers::route_store::RepeatOpenReport rr = drivers::route_store::open_route_for_repeat(reader, p.route_file.c_str(), meta, 100000);
  if (rr.outcome != drivers::route_store::RepeatOpen::kOk && rr.outcome != drivers::route_store::RepeatOpen::kGoodPrefix) {
    error = p.route_file + ": " + rr.why.message();
    return false;
  }
  std::vector<Pose2> track;
  std::vector<std::uint32_t> node_at;
  pipeline::taught_track_from_log(teach, dist, meta, track, node_at);
  std::vector<Vec2d> truth_poly = {Vec2d(0.0, 0.0), Vec2d(p.length_m, 0.0)};  // the survey line, north
  if (p.reverse) std::swap(truth_poly[0], truth_poly[1]);
  pipeline::ClosedLoopScenario scn = pipeline::follow_scenario(static_cast<std::uint64_t>(p.seed), p.reverse, p.offset_m, pipeline::FollowDrift{});
  const double dt = 1.0 / sc.rate_hz, max_travel = scn.max_travel_factor * p.length_m;
  pipeline::ClosedLoopVehicle veh;
  pipeline::RouteAutopilot ap;
  if (Status s = pipeline::start_closed_loop(Span<const Pose2>(track.data(), track.size()), Span<const std::uint32_t>(node_at.data(), node_at.size()),
                                             truth_poly, scn, pipeline::Guide::kQnav, p.guidance_age_s, p.speed_mps, 0, veh, ap);
      !s) {
    error = std::string("closed loop: ") + s.message();
    return false;
  }
  sidescan::Seabed bed;
  sidescan::SideScanSimulator sim;
  if (Status s = bed.init(sim_dive_seabed(p.length_m, static_cast<std::uint64_t>(p.seed))); !s || !(s = sim.init(sim_dive_sonar(p.samples, p.range_m, static_cast<std::uint64_t>(p.pass_seed)), &bed))) {
    error = std::string("closed loop: the simulated dive: ") + s.message();
    return false;
  }
  std::FILE* truth = p.truth_csv.empty() ? nullptr : std::fopen(p.truth_csv.c_str(), "w");
  if (truth != nullptr) std::fprintf(truth, "ping,time_s,along_m,north_m,east_m,heading_rad,nav_north_m,nav_east_m,nav_heading_rad\n");
  std::fprintf(log, "hil play: pass %zu %s: closed loop on the guidance read from %s: %zu nodes, taught track of %zu poses\n", pass_index,
               p.name.c_str(), sc.can_interface.c_str(), meta.size(), track.size());
  std::fflush(log);
  hal::CanRxFrame rx;
  while (v.receive(rx)) {
  }  // what queued before this pass (the teach's frames)
  const float altitude = static_cast<float>(sidescan::TrajectoryConfig{}.altitude_m);
  std::vector<float> port(static_cast<std::size_t>(p.samples)), stbd(static_cast<std::size_t>(p.samples));
  std::vector<std::uint8_t> buf;
  std::string ping;
  Pose2 prev = veh.dr_pose();
  const std::int64_t period = static_cast<std::int64_t>(1e9 / sc.rate_hz), t0 = hal::monotonic_now_ns();
  const std::uint64_t stamp0 = static_cast<std::uint64_t>(p.start_s * 1e9);
  std::uint32_t k = 0;
  for (; pipeline::closed_loop_step(veh, ap, dt, max_travel); ++k) {
    sleep_until_ns(t0 + static_cast<std::int64_t>(k) * period);
    const Pose2 dr = veh.dr_pose(), tr = veh.truth();
    const std::uint64_t stamp = stamp0 + static_cast<std::uint64_t>(k) * static_cast<std::uint64_t>(period);
    const double wall = static_cast<double>(hal::realtime_now_ns()) * 1e-9;
    v.ahrs(attitude_frame(dr.heading_rad));
    double fwd = 0.0, stb = 0.0;
    if (k > 0) pipeline::body_velocity_between(prev, dr, dt, fwd, stb);
    prev = dr;
    char line[240];
    const long long t_us = static_cast<long long>(stamp / 1000);
    const std::size_t n = drivers::dvl::wl_velocity_report(fwd, stb, 0.0, 10.0, t_us, t_us, line, sizeof line);
    v.dvl(std::string(line, n));
    (void)sim.ping(tr, altitude, k, Span<float>(port.data(), port.size()), Span<float>(stbd.data(), stbd.size()));
    ping.clear();
    if (append_sim_dive_jsf(ping, k, stamp, p.range_m, altitude, dr, port, stbd, buf)) v.sonar(ping);
    while (v.receive(rx)) (void)ap.on_frame(rx.frame, veh.t_ns());  // decode errors are counted by the autopilot
    double along = 0.0, cross = 0.0, hdg = 0.0;
    pipeline::polyline_offsets(truth_poly, tr.translation(), along, cross, hdg);
    if (truth != nullptr)
      std::fprintf(truth, "%u,%.3f,%.3f,%.3f,%.3f,%.5f,%.3f,%.3f,%.5f\n", k, static_cast<double>(stamp) * 1e-9, p.reverse ? p.length_m - along : along,
                   tr.x_m, tr.y_m, tr.heading_rad, dr.x_m, dr.y_m, dr.heading_rad);
    ++st.pings;
    if (played != nullptr) std::fprintf(played, "%zu,%u,%.6f,1,1,1\n", pass_index, k, wall);
  }
  if (truth != nullptr) std::fclose(truth);
  double along = 0.0, cross = 0.0, hdg = 0.0;
  pipeline::polyline_offsets(truth_poly, veh.truth().translation(), along, cross, hdg);
  std::fprintf(log, "hil play: pass %zu %s: closed loop flew %u pings, %.0f m; %s %.2f m from the route's end (cross-track %+.2f m); %u fixes steered, %u decode errors\n",
               pass_index, p.name.c_str(), k, veh.travelled_m(), ap.command().mode == pipeline::AutopilotMode::kStopped ? "stopped" : "NOT stopped",
               (veh.truth().translation() - truth_poly.back()).norm(), cross, ap.counters().get(pipeline::AutopilotCounter::kSteerFixes),
               ap.counters().get(pipeline::AutopilotCounter::kDecodeErrors));
  return true;
}

}  // namespace

bool play_hil_scenario(const HilScenario& sc, std::FILE* log, HilPlayStats& st, std::string& error) {
  std::vector<HilDive> dives(sc.passes.size());
  for (std::size_t i = 0; i < sc.passes.size(); ++i) {
    if (!load_hil_dive(sc.passes[i], dives[i], error)) return false;
  }
  std::FILE* played = nullptr;
  if (!sc.played.empty()) {
    played = std::fopen(sc.played.c_str(), "w");
    if (played == nullptr) {
      error = sc.played + ": " + std::strerror(errno);
      return false;
    }
    std::fprintf(played, "pass,ping,realtime_s,sonar,dvl,ahrs\n");
  }
  Vehicle v(sc, log, st);
  bool ok = v.open(error);
  if (ok) v.wait_for_sonar_client();
  const std::int64_t period = static_cast<std::int64_t>(1e9 / sc.rate_hz);
  for (std::size_t i = 0; ok && i < sc.passes.size(); ++i) {
    const HilPass& p = sc.passes[i];
    const HilDive& d = dives[i];
    if (p.closed_loop) {
      const hal::CanFrame hover_frame = attitude_frame(p.reverse ? kPi : 0.0);
      hover(v, &hover_frame, sc.rate_hz, p.lead_s);
      if (p.send_mode) v.mode(p.mode, p.route, p.reverse);
      hover(v, &hover_frame, sc.rate_hz, 1.0 / sc.rate_hz);
      ok = fly_closed_loop(v, sc, p, i, played, log, st, error);
      if (p.idle_after && !sc.can_interface.empty()) v.mode(qc::Mode::kIdle, p.route, false);
      hover(v, &hover_frame, sc.rate_hz, p.after_s);
      continue;
    }
    std::size_t n = d.pings();
    if (p.pings > 0 && static_cast<std::size_t>(p.pings) < n) n = static_cast<std::size_t>(p.pings);
    std::fprintf(log, "hil play: pass %zu %s: %zu pings at %.1f Hz (%.1f s)%s\n", i, p.name.c_str(), n, sc.rate_hz,
                 static_cast<double>(n) / sc.rate_hz, p.send_mode ? ", mode command first" : "");
    std::fflush(log);
    // The autopilot commands the mode once the vehicle is on station: after lead_s of hovering (the
    // daemon refuses a mode without a recent heading), one ping period before the first ping.
    hover(v, d.ahrs.empty() ? nullptr : &d.ahrs.front(), sc.rate_hz, p.lead_s);
    if (p.send_mode) v.mode(p.mode, p.route, p.reverse);
    hover(v, d.ahrs.empty() ? nullptr : &d.ahrs.front(), sc.rate_hz, 1.0 / sc.rate_hz);
    const std::int64_t t0 = hal::monotonic_now_ns();
    for (std::size_t k = 0; k < n; ++k) {
      sleep_until_ns(t0 + static_cast<std::int64_t>(k) * period);
      const double t_s = static_cast<double>(k) / sc.rate_hz;
      const bool s_on = k < d.jsf_pings.size() && !silenced(p, HilStream::kSonar, t_s);
      const bool d_on = k < d.dvl_lines.size() && !silenced(p, HilStream::kDvl, t_s);
      const bool a_on = k < d.ahrs.size() && !silenced(p, HilStream::kAhrs, t_s);
      st.silenced += (k < d.jsf_pings.size() && !s_on) + (k < d.dvl_lines.size() && !d_on) + (k < d.ahrs.size() && !a_on);
      const double wall = static_cast<double>(hal::realtime_now_ns()) * 1e-9;
      if (a_on) v.ahrs(d.ahrs[k]);
      if (d_on) v.dvl(d.dvl_lines[k]);
      if (s_on) v.sonar(d.jsf_pings[k]);
      ++st.pings;
      if (played != nullptr) std::fprintf(played, "%zu,%zu,%.6f,%d,%d,%d\n", i, k, wall, s_on, d_on, a_on);
    }
    if (p.idle_after && !sc.can_interface.empty()) v.mode(qc::Mode::kIdle, p.route, false);
    hover(v, d.ahrs.empty() ? nullptr : &d.ahrs[n > 0 ? n - 1 : 0], sc.rate_hz, p.after_s);
  }
  v.finish();
  if (played != nullptr) std::fclose(played);
  return ok;
}

}  // namespace qnav::tools
