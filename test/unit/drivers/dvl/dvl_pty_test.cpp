// The DVL driver on the real termios backend: a pseudo-terminal plays the DVL, writing the vendor's
// recorded sentences; the driver opens the slave side like a UART.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <stdlib.h>
#include <unistd.h>

#include <cstring>
#include <string>

#include "drivers/dvl/dvl_driver.hpp"
#include "hal/linux/monotonic_clock.hpp"
#include "test/support/pty.hpp"
#include "hal/linux/termios_serial.hpp"
#include "recorded.hpp"

using namespace qnav;
using namespace qnav::drivers::dvl;


TEST(DvlPty, WaterLinkedSentencesThroughATerminal) {
  test::PseudoTerminal pty;
  ASSERT_TRUE(pty.ok());
  hal::TermiosSerialPort port;
  ASSERT_TRUE(port.open(pty.slave_path(), hal::SerialConfig{}).is_ok());
  DvlSerialDriver drv(port, DvlProtocol::kWaterLinked);
  std::string s;
  for (const char* w : qnav_test::kWlWru) s += std::string(w) + "\r\n";
  s += std::string(qnav_test::kWlWrz) + "\r\n";
  const std::int64_t t0 = hal::monotonic_now_ns();
  ASSERT_EQ(write(pty.master_fd(), s.data(), s.size()), static_cast<ssize_t>(s.size()));
  int got = 0;
  for (int i = 0; i < 20 && got == 0; ++i) {
    auto r = drv.poll(100);
    ASSERT_TRUE(r.is_ok()) << r.status().message();
    got += r.value();
  }
  ASSERT_EQ(got, 1);
  DvlVelocity v;
  ASSERT_TRUE(drv.pop(v));
  EXPECT_DOUBLE_EQ(v.vx_mps, 0.12);
  EXPECT_GE(v.stamp.arrival_ns, t0);
  EXPECT_EQ(drv.lines(), 5u);
  // Command out through the terminal.
  ASSERT_TRUE(drv.send_command("wcr").is_ok());
  pollfd p{pty.master_fd(), POLLIN, 0};
  ASSERT_EQ(poll(&p, 1, 1000), 1);
  char back[16] = {};
  const ssize_t n = read(pty.master_fd(), back, sizeof back);
  ASSERT_EQ(n, 7);
  EXPECT_EQ(std::string(back, 4), "wcr*");
}

TEST(DvlPty, Pd6ThroughATerminal) {
  test::PseudoTerminal pty;
  ASSERT_TRUE(pty.ok());
  hal::TermiosSerialPort port;
  hal::SerialConfig c;
  c.baud = 9600;
  ASSERT_TRUE(port.open(pty.slave_path(), c).is_ok());
  DvlSerialDriver drv(port, DvlProtocol::kPd6);
  const std::string s = qnav_test::kPd6Ensemble;
  ASSERT_EQ(write(pty.master_fd(), s.data(), s.size()), static_cast<ssize_t>(s.size()));
  int got = 0;
  for (int i = 0; i < 20 && got == 0; ++i) got += drv.poll(100).value_or(0);
  ASSERT_EQ(got, 1);
  DvlVelocity v;
  ASSERT_TRUE(drv.pop(v));
  EXPECT_TRUE(v.bottom_lock);
  EXPECT_DOUBLE_EQ(v.vz_mps, 2.0);
}

// Fault injection on a real terminal (issue #19): line noise between sentences is counted and the
// good sentences still arrive; a device that goes away is an error from poll() at once (the daemon
// counts it as device_errors and reopens), never a hang or a crash.
TEST(DvlPty, LineNoiseIsCountedAndAVanishedDeviceIsAnError) {
  test::PseudoTerminal pty;
  ASSERT_TRUE(pty.ok());
  hal::TermiosSerialPort port;
  ASSERT_TRUE(port.open(pty.slave_path(), hal::SerialConfig{}).is_ok());
  DvlSerialDriver drv(port, DvlProtocol::kWaterLinked);
  std::string s;
  std::uint32_t seed = 7;
  for (int k = 0; k < 5; ++k) {
    for (int i = 0; i < 40; ++i) {  // a burst of noise ending its own line
      seed = seed * 1103515245u + 12345u;
      s += static_cast<char>(0x21 + (seed >> 16) % 0x5E);
    }
    s += "\r\n" + std::string(qnav_test::kWlWrz) + "\r\n";
  }
  ASSERT_EQ(write(pty.master_fd(), s.data(), s.size()), static_cast<ssize_t>(s.size()));
  int got = 0;
  for (int i = 0; i < 20 && got < 1; ++i) {
    auto r = drv.poll(100);
    ASSERT_TRUE(r.is_ok()) << r.status().message();
    got += r.value();
  }
  EXPECT_EQ(got, 1) << "the same recorded sentence five times: the first is used, the rest are stale";
  EXPECT_EQ(drv.counter(DvlCounter::kStale), 4u);
  EXPECT_EQ(drv.counter(DvlCounter::kChecksum) + drv.counter(DvlCounter::kFormat), 5u) << "each noise line rejected";
  pty.close_master();
  const std::int64_t t0 = hal::monotonic_now_ns();
  Result<int> r = drv.poll(500);
  for (int i = 0; i < 5 && r.is_ok(); ++i) r = drv.poll(100);
  EXPECT_FALSE(r.is_ok()) << "a vanished device must be an error";
  EXPECT_EQ(r.status().code(), StatusCode::kIoError) << r.status().message();
  EXPECT_LT(hal::monotonic_now_ns() - t0, 2000000000) << "reported at once, not after a hang";
}
