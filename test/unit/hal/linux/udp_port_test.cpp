// UdpPort against real loopback sockets (127.0.0.1 only): client and server roles, replies to the
// last sender, foreign senders, truncation, "port unreachable", and MAVLink frames through it.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <thread>
#include <vector>

#include "drivers/mavlink/messages.hpp"
#include "drivers/mavlink/parser.hpp"
#include "hal/linux/udp_port.hpp"

namespace qnav::hal {
namespace {

Span<const std::uint8_t> bytes_of(const char* s) {
  return Span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(s), std::strlen(s));
}

// Reads one datagram, waiting up to 2 s (the loopback delivers at once; the bound only stops a hang).
std::vector<std::uint8_t> read_one(UdpPort& p, std::size_t cap = 2048) {
  std::vector<std::uint8_t> buf(cap);
  auto r = p.read(Span<std::uint8_t>(buf.data(), buf.size()), 2000);
  EXPECT_TRUE(r.is_ok()) << r.status().message();
  buf.resize(r.is_ok() ? r.value().bytes : 0);
  return buf;
}

TEST(UdpEndpoint, ParsesHostPort) {
  char host[16];
  std::uint16_t port = 0;
  ASSERT_TRUE(parse_ipv4_endpoint("127.0.0.1:14550", host, port).is_ok());
  EXPECT_STREQ(host, "127.0.0.1");
  EXPECT_EQ(port, 14550);
  ASSERT_TRUE(parse_ipv4_endpoint("192.168.2.1:65535", host, port).is_ok());
  EXPECT_EQ(port, 65535);
  for (const char* bad : {"", "14550", ":14550", "127.0.0.1:", "127.0.0.1:0", "127.0.0.1:65536", "127.0.0.1:14a50",
                          "localhost:14550", "1.2.3.4.5:1", "127.0.0.1:1455000", "999.0.0.1:5"}) {
    EXPECT_EQ(parse_ipv4_endpoint(bad, host, port).code(), StatusCode::kInvalidArgument) << bad;
  }
  EXPECT_EQ(parse_ipv4_endpoint(nullptr, host, port).code(), StatusCode::kInvalidArgument);
}

TEST(UdpPort, ClientAndServerExchangeDatagramsAndTheServerRepliesToTheLastSender) {
  UdpPort server;
  ASSERT_TRUE(server.open_server(0, "127.0.0.1").is_ok());
  const std::uint16_t sport = server.local_port();
  ASSERT_NE(sport, 0);
  EXPECT_FALSE(server.has_peer());
  EXPECT_EQ(server.write(bytes_of("x")).status(), StatusCode::kNotReady);

  UdpPort a, b;
  ASSERT_TRUE(a.open_client("127.0.0.1", sport).is_ok());
  ASSERT_TRUE(b.open_client("127.0.0.1", sport).is_ok());
  ASSERT_TRUE(a.write(bytes_of("from a")).is_ok());
  auto got = read_one(server);
  EXPECT_EQ(std::string(got.begin(), got.end()), "from a");
  ASSERT_TRUE(server.write(bytes_of("to a")).is_ok());
  got = read_one(a);
  EXPECT_EQ(std::string(got.begin(), got.end()), "to a");

  ASSERT_TRUE(b.write(bytes_of("from b")).is_ok());
  got = read_one(server);
  EXPECT_EQ(std::string(got.begin(), got.end()), "from b");
  ASSERT_TRUE(server.write(bytes_of("to b")).is_ok());
  got = read_one(b);
  EXPECT_EQ(std::string(got.begin(), got.end()), "to b");

  EXPECT_EQ(server.udp_stats().datagrams_rx, 2u);
  EXPECT_EQ(server.udp_stats().datagrams_tx, 2u);
  EXPECT_EQ(a.stats().tx_bytes, 6u);
  EXPECT_EQ(a.stats().rx_bytes, 4u);
}

TEST(UdpPort, ReadTimesOutWithZeroBytes) {
  UdpPort server;
  ASSERT_TRUE(server.open_server(0, "127.0.0.1").is_ok());
  std::uint8_t buf[16];
  auto r = server.read(Span<std::uint8_t>(buf), 0);
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(r.value().bytes, 0u);
}

TEST(UdpPort, ClientHearsOnlyItsRemote) {
  UdpPort server;
  ASSERT_TRUE(server.open_server(0, "127.0.0.1").is_ok());
  UdpPort client;
  ASSERT_TRUE(client.open_client("127.0.0.1", server.local_port()).is_ok());
  UdpPort stranger;
  ASSERT_TRUE(stranger.open_client("127.0.0.1", client.local_port()).is_ok());
  ASSERT_TRUE(stranger.write(bytes_of("spoof")).is_ok());
  ASSERT_TRUE(client.write(bytes_of("hello")).is_ok());
  (void)read_one(server);
  ASSERT_TRUE(server.write(bytes_of("real")).is_ok());
  const auto got = read_one(client);
  EXPECT_EQ(std::string(got.begin(), got.end()), "real");  // the stranger's datagram never arrives
}

TEST(UdpPort, LongDatagramIsCutAndCounted) {
  UdpPort server, client;
  ASSERT_TRUE(server.open_server(0, "127.0.0.1").is_ok());
  ASSERT_TRUE(client.open_client("127.0.0.1", server.local_port()).is_ok());
  std::vector<std::uint8_t> big(100, 0x42);
  ASSERT_TRUE(client.write(Span<const std::uint8_t>(big.data(), big.size())).is_ok());
  const auto got = read_one(server, 10);
  EXPECT_EQ(got.size(), 10u);
  EXPECT_EQ(server.udp_stats().rx_truncated, 1u);
}

TEST(UdpPort, NothingListeningIsReportedAsRefusedAndThePortStaysUsable) {
  std::uint16_t dead_port = 0;
  {
    UdpPort probe;
    ASSERT_TRUE(probe.open_server(0, "127.0.0.1").is_ok());
    dead_port = probe.local_port();
  }
  UdpPort client;
  ASSERT_TRUE(client.open_client("127.0.0.1", dead_port).is_ok());
  bool refused = false;
  for (int i = 0; i < 200 && !refused; ++i) {  // the ICMP error arrives after the first send
    auto w = client.write(bytes_of("anyone?"));
    if (!w.is_ok()) {
      EXPECT_EQ(w.status().code(), StatusCode::kIoError);
      refused = true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_TRUE(refused);
  EXPECT_GE(client.udp_stats().tx_refused, 1u);
  // A listener appears on that port: the same client reaches it.
  UdpPort late;
  ASSERT_TRUE(late.open_server(dead_port, "127.0.0.1").is_ok());
  ASSERT_TRUE(client.write(bytes_of("now")).is_ok());
  const auto got = read_one(late);
  EXPECT_EQ(std::string(got.begin(), got.end()), "now");
}

TEST(UdpPort, BadArgumentsAreErrors) {
  UdpPort p;
  EXPECT_EQ(p.open_client("not-an-ip", 1).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(p.open_client("127.0.0.1", 0).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(p.open_server(0, "bad").code(), StatusCode::kInvalidArgument);
  std::uint8_t buf[4];
  EXPECT_EQ(p.read(Span<std::uint8_t>(buf), 0).status(), StatusCode::kNotReady);
  UdpPort a, b;
  ASSERT_TRUE(a.open_server(0, "127.0.0.1").is_ok());
  EXPECT_EQ(b.open_server(a.local_port(), "127.0.0.1").code(), StatusCode::kIoError);  // in use
}

TEST(UdpPort, MavlinkOdometryFramesArriveThroughTheParser) {
  using namespace qnav::drivers::mavlink;
  UdpPort autopilot, qnav;
  ASSERT_TRUE(autopilot.open_server(0, "127.0.0.1").is_ok());
  ASSERT_TRUE(qnav.open_client("127.0.0.1", autopilot.local_port()).is_ok());
  FrameEncoder enc(1, kMavCompIdVisualInertialOdometry);
  Parser parser;
  int received = 0;
  for (int i = 0; i < 200; ++i) {
    Odometry o;
    o.time_usec = 1000000ULL * static_cast<std::uint64_t>(i);
    o.x = 0.5f * static_cast<float>(i);
    o.quality = static_cast<std::int8_t>(i % 101);
    o.reset_counter = static_cast<std::uint8_t>(i / 50);
    std::uint8_t frame[kMaxFrameBytes];
    auto n = encode(enc, o, Span<std::uint8_t>(frame));
    ASSERT_TRUE(n.is_ok());
    ASSERT_TRUE(qnav.write(Span<const std::uint8_t>(frame, n.value())).is_ok());
    const auto dgram = read_one(autopilot);
    parser.feed(Span<const std::uint8_t>(dgram.data(), dgram.size()), [&](const Frame& f) {
      Odometry back;
      ASSERT_TRUE(decode(f, back));
      EXPECT_EQ(back.time_usec, o.time_usec);
      EXPECT_EQ(back.x, o.x);
      EXPECT_EQ(back.quality, o.quality);
      EXPECT_EQ(back.reset_counter, o.reset_counter);
      EXPECT_EQ(f.seq, static_cast<std::uint8_t>(i));
      ++received;
    });
  }
  EXPECT_EQ(received, 200);
  EXPECT_EQ(parser.counters().total(), 0u);
}

}  // namespace
}  // namespace qnav::hal
