// TermiosSerialPort against a real pseudo-terminal (posix_openpt): the slave side is opened by the
// backend exactly as a UART would be; the test plays the device on the master side.
#include "hal/linux/termios_serial.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <stdlib.h>
#include <termios.h>
#include <unistd.h>

#include <cstring>

#include "hal/linux/monotonic_clock.hpp"
#include "test/support/pty.hpp"
#include "test/support/alloc_guard.hpp"

using namespace qnav;
using namespace qnav::hal;


TEST(TermiosSerial, ReadsAndWritesThroughAPseudoTerminal) {
  test::PseudoTerminal pty;
  ASSERT_TRUE(pty.ok());
  TermiosSerialPort port;
  SerialConfig cfg;
  cfg.baud = 115200;
  ASSERT_TRUE(port.open(pty.slave_path(), cfg).is_ok());
  const char sentence[] = "wrz,0.120,-0.400,2.000,y,1.30,1.855,1e-07;0;1.4;0;1.2;0;0.2;0;1e+09,7,14,123.00,1*50\n";
  ASSERT_EQ(write(pty.master_fd(), sentence, sizeof sentence - 1), static_cast<ssize_t>(sizeof sentence - 1));
  std::uint8_t buf[256];
  std::size_t got = 0;
  const std::int64_t t0 = monotonic_now_ns();
  std::int64_t arrival = 0;
  for (int i = 0; i < 50 && got < sizeof sentence - 1; ++i) {
    auto r = port.read(Span<std::uint8_t>(buf + got, sizeof buf - got), 100);
    ASSERT_TRUE(r.is_ok());
    got += r.value().bytes;
    if (r.value().bytes) arrival = r.value().arrival_ns;
  }
  ASSERT_EQ(got, sizeof sentence - 1);
  EXPECT_EQ(std::memcmp(buf, sentence, got), 0);  // raw mode: no CR/LF translation, no echo
  EXPECT_GE(arrival, t0);
  EXPECT_LT(arrival - t0, 2000000000LL);
  const std::uint8_t cmd[] = {'w', 'c', 'v', '\r', '\n'};
  auto w = port.write(Span<const std::uint8_t>(cmd, sizeof cmd));
  ASSERT_TRUE(w.is_ok());
  EXPECT_EQ(w.value(), sizeof cmd);
  pollfd p{pty.master_fd(), POLLIN, 0};
  ASSERT_EQ(poll(&p, 1, 1000), 1);
  char back[16] = {};
  ASSERT_EQ(read(pty.master_fd(), back, sizeof back), static_cast<ssize_t>(sizeof cmd));
  EXPECT_EQ(std::memcmp(back, cmd, sizeof cmd), 0);
  EXPECT_EQ(port.stats().rx_bytes, sizeof sentence - 1);
}

TEST(TermiosSerial, TimeoutReturnsZeroBytesWithoutHeap) {
  test::PseudoTerminal pty;
  ASSERT_TRUE(pty.ok());
  TermiosSerialPort port;
  ASSERT_TRUE(port.open(pty.slave_path(), SerialConfig{}).is_ok());
  std::uint8_t buf[8];
  const std::int64_t t0 = monotonic_now_ns();
  Result<SerialRead> r = SerialRead{};
  QNAV_EXPECT_NO_ALLOC(r = port.read(Span<std::uint8_t>(buf, sizeof buf), 30));
  const std::int64_t dt = monotonic_now_ns() - t0;
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(r.value().bytes, 0u);
  EXPECT_GE(dt, 25000000LL);  // it did wait (poll timeout), not spin
}

TEST(TermiosSerial, OpenErrorsAreValues) {
  TermiosSerialPort port;
  EXPECT_EQ(port.open("/dev/does-not-exist-qnav", SerialConfig{}), StatusCode::kNotFound);
  EXPECT_EQ(port.open("/dev/null", SerialConfig{}), StatusCode::kIoError);  // not a tty
  SerialConfig bad;
  bad.baud = 123;
  EXPECT_EQ(port.open("/dev/null", bad), StatusCode::kUnsupported);
  std::uint8_t b[4];
  EXPECT_EQ(port.read(Span<std::uint8_t>(b, 4), 0).status(), StatusCode::kNotReady);
}

TEST(TermiosSerial, BuildsFramingBits) {
  SerialConfig cfg;
  cfg.baud = 9600;
  cfg.parity = Parity::kOdd;
  cfg.stop_bits = 2;
  cfg.data_bits = 7;
  cfg.hw_flow_control = true;
  termios t{};
  ASSERT_TRUE(build_termios(cfg, t).is_ok());
  EXPECT_TRUE(t.c_cflag & PARENB);
  EXPECT_TRUE(t.c_cflag & PARODD);
  EXPECT_TRUE(t.c_cflag & CSTOPB);
  EXPECT_TRUE(t.c_cflag & CRTSCTS);
  EXPECT_TRUE(t.c_cflag & CLOCAL);
  EXPECT_EQ(t.c_cflag & CSIZE, static_cast<tcflag_t>(CS7));
  EXPECT_EQ(cfgetispeed(&t), static_cast<speed_t>(B9600));
  EXPECT_FALSE(t.c_lflag & ICANON);  // raw
  EXPECT_FALSE(t.c_lflag & ECHO);
  EXPECT_EQ(t.c_cc[VMIN], 0);
}

TEST(TermiosSerial, PtyTakesTheRequestedSpeed) {
  test::PseudoTerminal pty;
  ASSERT_TRUE(pty.ok());
  TermiosSerialPort port;
  SerialConfig cfg;
  cfg.baud = 9600;
  ASSERT_TRUE(port.open(pty.slave_path(), cfg).is_ok());
  termios t{};
  ASSERT_EQ(tcgetattr(port.fd(), &t), 0);
  EXPECT_EQ(cfgetispeed(&t), static_cast<speed_t>(B9600));
  EXPECT_FALSE(t.c_lflag & ICANON);
}
