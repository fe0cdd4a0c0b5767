// The HIL player's device ends against real kernel objects: PtyDevice (a pseudo-terminal behind a
// symlink, opened by TermiosSerialPort as the daemon opens its DVL) and TcpServerPort (the sonar
// topside's data port, read by TcpClientPort as the daemon reads its JSF stream).
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <string>

#include "hal/linux/pty_device.hpp"
#include "hal/linux/tcp_client_port.hpp"
#include "hal/linux/tcp_server_port.hpp"
#include "hal/linux/termios_serial.hpp"

using namespace qnav;
using namespace qnav::hal;

namespace {
std::string temp_dir() {
  char t[] = "/tmp/qnav_ports_XXXXXX";
  const char* d = mkdtemp(t);
  return d != nullptr ? d : "";
}
Span<const std::uint8_t> bytes(const char* s) { return Span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(s), std::strlen(s)); }
}  // namespace

TEST(PtyDevice, PlaysADeviceBehindASymlinkAndUnplugs) {
  const std::string dir = temp_dir();
  ASSERT_FALSE(dir.empty());
  const std::string link = dir + "/dvl0";
  PtyDevice dev;
  ASSERT_TRUE(dev.open(link.c_str()).is_ok());
  char target[128] = {};
  ASSERT_GT(readlink(link.c_str(), target, sizeof target - 1), 0);
  EXPECT_STREQ(target, dev.slave_path());

  TermiosSerialPort port;  // the daemon's side, opened through the link as a UART
  ASSERT_TRUE(port.open(link.c_str(), SerialConfig{}).is_ok());
  const char line[] = "wrz,0.100,0.000,0.000,y,1.30,0.000,1e-07;0;1e-07;0;1e-07;0;1e-07;0;1e-07,1,1,1.00,1*00\n";
  const Result<std::size_t> w = dev.write(bytes(line));
  ASSERT_TRUE(w.is_ok());
  EXPECT_EQ(w.value(), sizeof line - 1);
  std::uint8_t buf[256];
  std::size_t got = 0;
  for (int i = 0; i < 20 && got < sizeof line - 1; ++i) {
    const Result<SerialRead> r = port.read(Span<std::uint8_t>(buf + got, sizeof buf - got), 100);
    ASSERT_TRUE(r.is_ok());
    got += r.value().bytes;
  }
  ASSERT_EQ(got, sizeof line - 1);
  EXPECT_EQ(std::memcmp(buf, line, got), 0);
  // What the daemon writes is drained, not kept.
  ASSERT_TRUE(port.write(bytes("PD6\r\n")).is_ok());
  std::size_t drained = 0;
  for (int i = 0; i < 20 && drained < 5; ++i) {
    drained += dev.drain();
    usleep(5000);
  }
  EXPECT_EQ(drained, 5u);

  dev.unplug();  // the adapter is pulled: the link is gone and the daemon's side hangs up
  struct stat st {};
  EXPECT_NE(lstat(link.c_str(), &st), 0);
  bool hung_up = false;
  for (int i = 0; i < 5 && !hung_up; ++i) hung_up = !port.read(Span<std::uint8_t>(buf, sizeof buf), 50).is_ok();
  EXPECT_TRUE(hung_up);
  EXPECT_FALSE(dev.write(bytes(line)).is_ok());

  ASSERT_TRUE(dev.open(link.c_str()).is_ok());  // plugged back: a stale link is replaced by the new one
  ASSERT_TRUE(dev.open(link.c_str()).is_ok());
  dev.unplug();
  (void)rmdir(dir.c_str());
}

TEST(PtyDevice, NeverReplacesAFileThatIsNotASymlink) {
  const std::string dir = temp_dir();
  const std::string path = dir + "/precious";
  std::FILE* f = std::fopen(path.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fputs("a user's data\n", f);
  std::fclose(f);
  PtyDevice dev;
  const Status s = dev.open(path.c_str());
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(std::strstr(s.message(), "not a symlink"), nullptr) << s.message();
  EXPECT_NE(std::strstr(s.message(), path.c_str()), nullptr) << s.message();
  dev.unplug();
  struct stat st {};
  ASSERT_EQ(lstat(path.c_str(), &st), 0);  // still there, untouched
  EXPECT_TRUE(S_ISREG(st.st_mode));
  EXPECT_EQ(st.st_size, 14);
  (void)unlink(path.c_str());
  (void)rmdir(dir.c_str());
}

TEST(TcpServerPort, ServesOneClientAtATimeAndCountsDrops) {
  TcpServerPort srv;
  ASSERT_TRUE(srv.listen("127.0.0.1", 0).is_ok());
  const std::uint16_t port = srv.local_port();
  ASSERT_GT(port, 0);
  EXPECT_FALSE(srv.poll_accept());
  EXPECT_EQ(srv.write(bytes("x"), 10).code(), StatusCode::kNotReady);

  TcpClientPort a;
  ASSERT_TRUE(a.open("127.0.0.1", port, 1000).is_ok());
  bool up = false;
  for (int i = 0; i < 100 && !up; ++i, usleep(2000)) up = srv.poll_accept();
  ASSERT_TRUE(up);
  ASSERT_TRUE(srv.write(bytes("ping-1"), 100).is_ok());
  std::uint8_t buf[64];
  std::size_t got = 0;
  for (int i = 0; i < 20 && got < 6; ++i) {
    const Result<SerialRead> r = a.read(Span<std::uint8_t>(buf + got, sizeof buf - got), 100);
    ASSERT_TRUE(r.is_ok());
    got += r.value().bytes;
  }
  ASSERT_EQ(got, 6u);
  EXPECT_EQ(std::memcmp(buf, "ping-1", 6), 0);

  // The client goes away (a daemon stopped): writes fail, the drop is counted, and a new client
  // (the daemon restarted) is taken.
  a.close();
  Status s = Status::ok();
  for (int i = 0; i < 50 && s.is_ok(); ++i, usleep(2000)) s = srv.write(bytes("ping-2"), 100);
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_EQ(srv.drops(), 1u);
  EXPECT_FALSE(srv.connected());
  TcpClientPort b;
  ASSERT_TRUE(b.open("127.0.0.1", port, 1000).is_ok());
  up = false;
  for (int i = 0; i < 100 && !up; ++i, usleep(2000)) up = srv.poll_accept();
  ASSERT_TRUE(up);
  EXPECT_EQ(srv.connections(), 2u);
  EXPECT_TRUE(srv.write(bytes("ping-3"), 100).is_ok());
}

TEST(TcpServerPort, ErrorsNameTheAddress) {
  TcpServerPort a, b;
  EXPECT_EQ(a.listen("localhost", 1709).code(), StatusCode::kInvalidArgument);  // numeric only: no resolver
  ASSERT_TRUE(a.listen("127.0.0.1", 0).is_ok());
  const Status s = b.listen("127.0.0.1", a.local_port());
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(std::strstr(s.message(), "127.0.0.1"), nullptr) << s.message();
  EXPECT_NE(std::strstr(s.message(), "in use"), nullptr) << s.message();
}
