// ClockedCanNode: frames between the two linked ends keep the mission time they were sent at however
// late the "kernel" delivers them, in_flight() counts what is on its way (the sim backend's lockstep),
// frames nobody linked sent are stamped when read, and lost frames are given up and counted.
#include "hal/sim/clocked_can_link.hpp"

#include <gtest/gtest.h>

#include <deque>

#include "hal/sim/manual_clock.hpp"

namespace qnav::hal {
namespace {

// A socket on a shared "interface" whose deliveries the test releases by hand (the kernel's round trip).
struct FakeWire;
class FakeSocket final : public CanBus {
 public:
  FakeSocket(FakeWire& w, int id) : wire_(w), id_(id) {}
  Status send(const CanFrame& f) noexcept override;
  Status receive(CanRxFrame& out, int) noexcept override {
    if (rx_.empty()) return Status(StatusCode::kTimeout, "no frame");
    out = CanRxFrame{};
    out.frame = rx_.front();
    out.stamp.sample_ns = out.stamp.arrival_ns = 123;  // a kernel time: the node must replace it
    rx_.pop_front();
    return Status::ok();
  }
  CanBusStats stats() const noexcept override { return {}; }
  std::deque<CanFrame> rx_;
  FakeWire& wire_;
  int id_;
};
struct FakeWire {
  std::deque<std::pair<int, CanFrame>> pending;  // (receiver, frame) not delivered yet
  FakeSocket* sockets[2] = {nullptr, nullptr};
  void deliver_all() {
    for (auto& p : pending) sockets[p.first]->rx_.push_back(p.second);
    pending.clear();
  }
};
Status FakeSocket::send(const CanFrame& f) noexcept {
  wire_.pending.emplace_back(1 - id_, f);
  return Status::ok();
}

CanFrame frame(std::uint32_t id, std::uint8_t b0) {
  CanFrame f;
  f.id = id;
  f.len = 2;
  f.data[0] = b0;
  f.data[1] = 7;
  return f;
}

struct Link {
  FakeWire wire;
  FakeSocket a{wire, 0}, b{wire, 1};
  ManualClock mission{1000}, wall{0};
  ClockedCanNode na{a, mission, wall}, nb{b, mission, wall};
  Link() {
    wire.sockets[0] = &a;
    wire.sockets[1] = &b;
    na.link(nb);
  }
};

TEST(ClockedCanNode, AFrameKeepsTheMissionTimeItWasSentAtHoweverLateItArrives) {
  Link l;
  ASSERT_TRUE(l.na.send(frame(0x100, 1)));
  l.mission.set_ns(2000);
  ASSERT_TRUE(l.na.send(frame(0x100, 2)));
  EXPECT_EQ(l.nb.in_flight(), 2u);  // the lockstep waits
  EXPECT_EQ(l.na.in_flight(), 0u);
  l.mission.set_ns(9000);  // the round trip completes after the clock moved on
  l.wire.deliver_all();
  CanRxFrame rx;
  ASSERT_TRUE(l.nb.receive(rx, 0));
  EXPECT_EQ(rx.frame.data[0], 1);
  EXPECT_EQ(rx.stamp.sample_ns, 1000);
  EXPECT_EQ(rx.stamp.arrival_ns, 1000);
  ASSERT_TRUE(l.nb.receive(rx, 0));
  EXPECT_EQ(rx.stamp.sample_ns, 2000);
  EXPECT_EQ(l.nb.in_flight(), 0u);
  EXPECT_EQ(l.nb.lost(), 0u);
  EXPECT_FALSE(l.nb.receive(rx, 0));
}

TEST(ClockedCanNode, BothDirectionsAreLinked) {
  Link l;
  ASSERT_TRUE(l.nb.send(frame(0x200, 5)));
  EXPECT_EQ(l.na.in_flight(), 1u);
  l.mission.set_ns(5000);
  l.wire.deliver_all();
  CanRxFrame rx;
  ASSERT_TRUE(l.na.receive(rx, 0));
  EXPECT_EQ(rx.frame.id, 0x200u);
  EXPECT_EQ(rx.stamp.sample_ns, 1000);
}

TEST(ClockedCanNode, AForeignFrameIsStampedWhenReadAndLeavesTheCountAlone) {
  Link l;
  ASSERT_TRUE(l.na.send(frame(0x100, 1)));
  l.b.rx_.push_back(frame(0x110, 9));  // a person's cansend, before the vehicle's frame arrives
  l.mission.set_ns(4000);
  CanRxFrame rx;
  ASSERT_TRUE(l.nb.receive(rx, 0));
  EXPECT_EQ(rx.frame.id, 0x110u);
  EXPECT_EQ(rx.stamp.sample_ns, 4000);
  EXPECT_EQ(l.nb.foreign(), 1u);
  EXPECT_EQ(l.nb.in_flight(), 1u);  // the vehicle's frame is still expected
  l.wire.deliver_all();
  ASSERT_TRUE(l.nb.receive(rx, 0));
  EXPECT_EQ(rx.stamp.sample_ns, 1000);
  EXPECT_EQ(l.nb.in_flight(), 0u);
}

TEST(ClockedCanNode, LostFramesAreGivenUpAndCounted) {
  Link l;
  ASSERT_TRUE(l.na.send(frame(0x100, 1)));
  ASSERT_TRUE(l.na.send(frame(0x100, 2)));
  ASSERT_TRUE(l.na.send(frame(0x100, 3)));
  l.wire.pending.erase(l.wire.pending.begin());  // the kernel dropped the first
  l.wire.deliver_all();
  CanRxFrame rx;
  ASSERT_TRUE(l.nb.receive(rx, 0));  // the second overtook it: the first is lost
  EXPECT_EQ(rx.frame.data[0], 2);
  EXPECT_EQ(l.nb.lost(), 1u);
  EXPECT_EQ(l.nb.in_flight(), 1u);
  l.b.rx_.clear();  // and the third never comes: given up after kLostAfterNs of wall time
  l.wall.advance_ns(ClockedCanNode::kLostAfterNs);
  EXPECT_EQ(l.nb.in_flight(), 1u);
  l.wall.advance_ns(1);
  EXPECT_EQ(l.nb.in_flight(), 0u);
  EXPECT_EQ(l.nb.lost(), 2u);
}

TEST(ClockedCanNode, SendRefusesBeyondTheFramesInFlightItCanTrack) {
  Link l;
  for (std::size_t i = 0; i < ClockedCanNode::kMaxInFlight; ++i) ASSERT_TRUE(l.na.send(frame(0x100, static_cast<std::uint8_t>(i))));
  const Status s = l.na.send(frame(0x100, 0));
  EXPECT_EQ(s.code(), StatusCode::kCapacityExceeded);
  EXPECT_EQ(l.wire.pending.size(), ClockedCanNode::kMaxInFlight);  // the refused frame was not sent
}

}  // namespace
}  // namespace qnav::hal
