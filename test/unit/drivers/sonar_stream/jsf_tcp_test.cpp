// The JSF stream driver on a real TCP connection over loopback (127.0.0.1, an ephemeral port): the
// test plays the sonar's data port.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <vector>

#include "drivers/sonar_stream/jsf_stream_driver.hpp"
#include "hal/linux/tcp_client_port.hpp"
#include "jsf_stream.hpp"

using namespace qnav;
using namespace qnav::drivers::sonar_stream;

namespace {
void count(void* ctx, const sonar::SonarPing&, const hal::SampleStamp&) { ++*static_cast<int*>(ctx); }
}  // namespace

TEST(JsfStreamTcp, PingsOverLoopback) {
  const int srv = socket(AF_INET, SOCK_STREAM, 0);
  ASSERT_GE(srv, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  ASSERT_EQ(bind(srv, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  ASSERT_EQ(listen(srv, 1), 0);
  socklen_t len = sizeof a;
  ASSERT_EQ(getsockname(srv, reinterpret_cast<sockaddr*>(&a), &len), 0);
  hal::TcpClientPort port;
  ASSERT_TRUE(port.open("127.0.0.1", ntohs(a.sin_port), 1000).is_ok());
  pollfd p{srv, POLLIN, 0};
  ASSERT_EQ(poll(&p, 1, 1000), 1);
  const int peer = accept(srv, nullptr, nullptr);
  ASSERT_GE(peer, 0);
  const std::vector<std::uint8_t> stream = qnav_test::jsf_stream(20, 2000, true);
  ASSERT_EQ(send(peer, stream.data(), stream.size(), 0), static_cast<ssize_t>(stream.size()));
  JsfStreamDriver drv;
  ASSERT_TRUE(drv.init(JsfStreamConfig{}).is_ok());
  int pings = 0;
  for (int i = 0; i < 50 && pings < 20; ++i) {
    auto r = drv.poll(port, 100, &count, &pings);
    ASSERT_TRUE(r.is_ok()) << r.status().message();
  }
  EXPECT_EQ(pings, 20);
  EXPECT_EQ(drv.bytes(), stream.size());
  close(peer);  // the sonar goes away: the next poll reports it
  Result<int> r = 0;
  for (int i = 0; i < 10 && r.is_ok(); ++i) r = drv.poll(port, 100, &count, &pings);
  EXPECT_EQ(r.status(), StatusCode::kIoError);
  close(srv);
  hal::TcpClientPort bad;
  EXPECT_EQ(bad.open("not-an-ip", 1037, 10), StatusCode::kInvalidArgument);
}

// The daemon's way to connect: begin_connect() returns at once, poll_connect() finishes the
// connection without waiting; a port nobody listens on is refused, never a hang.
TEST(JsfStreamTcp, ConnectWithoutWaiting) {
  const int srv = socket(AF_INET, SOCK_STREAM, 0);
  ASSERT_GE(srv, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(srv, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  ASSERT_EQ(listen(srv, 1), 0);
  socklen_t len = sizeof a;
  ASSERT_EQ(getsockname(srv, reinterpret_cast<sockaddr*>(&a), &len), 0);
  hal::TcpClientPort port;
  Status s = port.begin_connect("127.0.0.1", ntohs(a.sin_port));
  ASSERT_TRUE(s.is_ok() || s == StatusCode::kNotReady) << s.message();
  for (int i = 0; i < 100 && s == StatusCode::kNotReady; ++i) {
    usleep(10000);
    s = port.poll_connect();
  }
  EXPECT_TRUE(s.is_ok()) << s.message();
  EXPECT_TRUE(port.is_open());
  EXPECT_FALSE(port.connecting());
  port.close();
  // The listener gone: the port is closed, the connection is refused (at once or at the next poll).
  close(srv);
  s = port.begin_connect("127.0.0.1", ntohs(a.sin_port));
  for (int i = 0; i < 100 && s == StatusCode::kNotReady; ++i) {
    usleep(10000);
    s = port.poll_connect();
  }
  EXPECT_EQ(s, StatusCode::kIoError) << s.message();
  EXPECT_FALSE(port.is_open());
  EXPECT_FALSE(port.connecting());
}
