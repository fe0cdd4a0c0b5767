// The HIL scenario player (qnav hil play) on this machine's kernel: a pseudo-terminal DVL and a TCP
// sonar port, read back here exactly as the daemon reads them (TermiosSerialPort through the link,
// TcpClientPort). CAN needs vcan (the bench, test/hil): not used here. Also the scenario file's
// strict reading: every error names the key and its line.
#include "firmware/tools/hil_player.hpp"

#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <thread>

#include "drivers/sidescan/jsf_parser.hpp"
#include "hal/linux/tcp_client_port.hpp"
#include "hal/linux/tcp_server_port.hpp"
#include "hal/linux/termios_serial.hpp"

using namespace qnav;

namespace {

std::string temp_dir() {
  char t[] = "/tmp/qnav_hil_play_XXXXXX";
  const char* d = mkdtemp(t);
  return d != nullptr ? d : "";
}
void write_file(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }
std::string read_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// A dive of n pings: two JSF sonar messages (port, starboard) per ping, one DVL line per ping.
std::string make_jsf(int n) {
  std::string out;
  float samples[16];
  for (int i = 0; i < 16; ++i) samples[i] = static_cast<float>(100 + i);
  std::vector<std::uint8_t> buf(sidescan::jsf_sonar_message_bytes(16));
  for (int p = 0; p < n; ++p) {
    for (std::uint8_t ch = 0; ch < 2; ++ch) {
      sidescan::JsfWriteSonar w;
      w.channel = ch;
      w.ping_number = static_cast<std::uint32_t>(1000 + p);
      w.stamp_ns = 1700000000ull * 1000000000ull + static_cast<std::uint64_t>(p) * 100000000ull;
      w.samples = Span<const float>(samples, 16);
      const Result<std::size_t> b = sidescan::encode_jsf_sonar_message(Span<std::uint8_t>(buf.data(), buf.size()), w);
      if (b.is_ok()) out.append(reinterpret_cast<const char*>(buf.data()), b.value());
    }
  }
  return out;
}

std::string load_error(const std::string& dir, const std::string& toml) {
  write_file(dir + "/s.toml", toml);
  tools::HilScenario sc;
  std::string err;
  return tools::load_hil_scenario((dir + "/s.toml").c_str(), sc, err) ? "" : err;
}

}  // namespace

TEST(HilPlayer, ScenarioErrorsNameTheKeyAndLine) {
  const std::string d = temp_dir();
  write_file(d + "/a.txt", "this is a text file, not a recorded dive\n");
  EXPECT_NE(load_error(d, "rate_hz = 10\n").find("no [[pass]]"), std::string::npos);
  std::string e = load_error(d, "rate_hz = 10\nsonar_listn = \"127.0.0.1:1709\"\n[[pass]]\ndvl = \"a.txt\"\n");
  EXPECT_NE(e.find("sonar_listn (line 2): unknown key"), std::string::npos) << e;
  e = load_error(d, "rate_hz = 0\n[[pass]]\ndvl = \"a.txt\"\n");
  EXPECT_NE(e.find("rate_hz (line 1): out of range [0.1, 1000]"), std::string::npos) << e;
  e = load_error(d, "can = \"vcan0\"\n[[pass]]\ndvl = \"a.txt\"\nmode = \"teech\"\n");
  EXPECT_NE(e.find("pass[0].mode (line 4): must be one of idle, teach"), std::string::npos) << e;
  e = load_error(d, "[[pass]]\ndvl = \"a.txt\"\nmode = \"teach\"\n");
  EXPECT_NE(e.find("sends a mode command but `can`"), std::string::npos) << e;
  e = load_error(d, "[[pass]]\ndvl = \"a.txt\"\n[[pass.silence]]\nstream = \"gps\"\nfrom_s = 1\nto_s = 2\n");
  EXPECT_NE(e.find("pass[0].silence[0].stream"), std::string::npos) << e;
  e = load_error(d, "[[pass]]\ndvl = \"a.txt\"\n[[pass.silence]]\nstream = \"dvl\"\nfrom_s = 3\nto_s = 2\n");
  EXPECT_NE(e.find("to_s"), std::string::npos) << e;
  e = load_error(d, "[[pass]]\nname = \"empty\"\n");
  EXPECT_NE(e.find("plays nothing"), std::string::npos) << e;
  e = load_error(d, "[[pass]\n");
  EXPECT_NE(e.find("(line 1)"), std::string::npos) << e;
  // A closed-loop pass flies live: no recorded dive, and it needs its taught track.
  e = load_error(d, "[[pass]]\nclosed_loop = true\ndvl = \"a.txt\"\n");
  EXPECT_NE(e.find("pass[0].closed_loop (line 2): a closed-loop pass flies live"), std::string::npos) << e;
  e = load_error(d, "[[pass]]\nclosed_loop = true\nteach_truth = \"t.csv\"\n");
  EXPECT_NE(e.find("needs teach_truth and route_file"), std::string::npos) << e;
  e = load_error(d, "[[pass]]\nclosed_loop = true\nspeed_mps = 0\n");
  EXPECT_NE(e.find("speed_mps (line 3): out of range"), std::string::npos) << e;
  EXPECT_EQ(load_error(d, "[[pass]]\nclosed_loop = true\nteach_truth = \"t.csv\"\nroute_file = \"/tmp/r.qroute\"\n"), "");

  // The dive's files are checked before anything is played.
  tools::HilPass p;
  tools::HilDive dive;
  p.jsf = d + "/a.txt";
  EXPECT_FALSE(tools::load_hil_dive(p, dive, e));
  EXPECT_NE(e.find("no JSF sync word at byte 0"), std::string::npos) << e;
  p.jsf.clear();
  p.candump = d + "/a.txt";
  EXPECT_FALSE(tools::load_hil_dive(p, dive, e));
  EXPECT_NE(e.find("line 1"), std::string::npos) << e;
}

TEST(HilPlayer, PlaysADiveThroughAPtyAndTcpWithASilence) {
  const std::string d = temp_dir();
  ASSERT_FALSE(d.empty());
  constexpr int kPings = 30;
  const std::string jsf = make_jsf(kPings);
  std::string dvl;
  for (int i = 0; i < kPings; ++i) dvl += "wrz,line," + std::to_string(i) + "\n";
  write_file(d + "/dive.jsf", jsf);
  write_file(d + "/dive_dvl.txt", dvl);
  std::uint16_t port = 0;
  {
    hal::TcpServerPort probe;  // a free port for the scenario
    ASSERT_TRUE(probe.listen("127.0.0.1", 0).is_ok());
    port = probe.local_port();
  }
  // 200 pings/s; the DVL silent from 0.05 s to 0.1 s of the pass (pings 10..19).
  write_file(d + "/s.toml", "rate_hz = 200\nsonar_listen = \"127.0.0.1:" + std::to_string(port) + "\"\ndvl_pty = \"" + d +
                                "/dvl0\"\nplayed = \"out/played.csv\"\nwait_connect_s = 10\n[[pass]]\nname = \"dive\"\njsf = \"dive.jsf\"\n"
                                "dvl = \"dive_dvl.txt\"\nlead_s = 0\nafter_s = 0.05\n[[pass.silence]]\nstream = \"dvl\"\nfrom_s = 0.05\nto_s = 0.1\n");
  tools::HilScenario sc;
  std::string err;
  ASSERT_TRUE(tools::load_hil_scenario((d + "/s.toml").c_str(), sc, err)) << err;
  ASSERT_EQ(mkdir((d + "/out").c_str(), 0755), 0);

  tools::HilPlayStats st;
  bool played_ok = false;
  std::FILE* log = std::tmpfile();
  std::thread player([&] { played_ok = tools::play_hil_scenario(sc, log, st, err); });
  // The daemon's side: the DVL through the link, then the sonar connection (the player waits for it).
  hal::TermiosSerialPort dvl_port;
  bool open = false;
  Status why = Status::ok();
  for (int i = 0; i < 500 && !open; ++i, usleep(2000)) open = (why = dvl_port.open((d + "/dvl0").c_str(), hal::SerialConfig{})).is_ok();
  if (!open) player.join();  // it ends on its own (wait_connect_s) and says why in err
  ASSERT_TRUE(open) << why.message() << " / player: " << err;
  hal::TcpClientPort sonar;
  open = false;
  for (int i = 0; i < 500 && !open; ++i, usleep(2000)) open = sonar.open("127.0.0.1", port, 200).is_ok();
  ASSERT_TRUE(open);
  std::string got_jsf, got_dvl;
  std::uint8_t buf[65536];
  for (int idle = 0; idle < 30;) {  // until 0.3 s pass with nothing on either line (the player has ended)
    const Result<hal::SerialRead> a = sonar.read(Span<std::uint8_t>(buf, sizeof buf), 5);
    if (a.is_ok() && a.value().bytes > 0) got_jsf.append(reinterpret_cast<const char*>(buf), a.value().bytes);
    const Result<hal::SerialRead> b = dvl_port.read(Span<std::uint8_t>(buf, sizeof buf), 5);
    if (b.is_ok() && b.value().bytes > 0) got_dvl.append(reinterpret_cast<const char*>(buf), b.value().bytes);
    const bool any = (a.is_ok() && a.value().bytes > 0) || (b.is_ok() && b.value().bytes > 0);
    idle = any ? 0 : idle + 1;
  }
  player.join();
  std::fclose(log);
  ASSERT_TRUE(played_ok) << err;

  EXPECT_EQ(got_jsf, jsf);  // every ping, byte for byte, in order
  std::string want_dvl;
  for (int i = 0; i < kPings; ++i)
    if (i < 10 || i >= 20) want_dvl += "wrz,line," + std::to_string(i) + "\n";
  EXPECT_EQ(got_dvl, want_dvl);
  EXPECT_EQ(st.pings, static_cast<unsigned>(kPings));
  EXPECT_EQ(st.sonar_sent, static_cast<unsigned>(kPings));
  EXPECT_EQ(st.sonar_unsent, 0u);
  EXPECT_EQ(st.dvl_sent, 20u);
  EXPECT_EQ(st.silenced, 10u);
  EXPECT_EQ(st.sonar_connections, 1u);
  // played.csv: a line per ping with its wall-clock time, in order, and which streams went out.
  std::istringstream csv(read_file(d + "/out/played.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "pass,ping,realtime_s,sonar,dvl,ahrs");
  int n = 0;
  double prev = 0.0;
  while (std::getline(csv, line)) {
    unsigned pass = 9, ping = 9;
    double t = 0.0;
    int s = -1, v = -1, a = -1;
    ASSERT_EQ(std::sscanf(line.c_str(), "%u,%u,%lf,%d,%d,%d", &pass, &ping, &t, &s, &v, &a), 6) << line;
    EXPECT_EQ(pass, 0u);
    EXPECT_EQ(ping, static_cast<unsigned>(n));
    EXPECT_EQ(v, (n >= 10 && n < 20) ? 0 : 1) << line;
    EXPECT_EQ(s, 1);
    EXPECT_EQ(a, 0);  // no candump in this pass
    EXPECT_GT(t, 1.7e9);
    if (n > 0) {
      EXPECT_GE(t, prev);
    }
    prev = t;
    ++n;
  }
  EXPECT_EQ(n, kPings);
  struct stat stt {};
  EXPECT_NE(lstat((d + "/dvl0").c_str(), &stt), 0);  // the player unplugged its DVL when it ended
}
