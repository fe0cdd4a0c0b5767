// The publisher on an in-process CAN bus: DBC periods, rolling counters, TX-full retry, bad values.
#include "drivers/qnavcan/publisher.hpp"

#include <gtest/gtest.h>

#include <utility>
#include <vector>

#include "hal/sim/manual_clock.hpp"
#include "hal/sim/sim_can.hpp"
#include "test/support/alloc_guard.hpp"

using namespace qnav;
using namespace qnav::drivers::qnavcan;

TEST(QnavCanPublisher, SendsEachOutputAtItsDbcPeriodWithRollingCounters) {
  hal::ManualClock clock(0);
  hal::SimCanNetwork net(clock);
  hal::SimCanBus tx, rx;
  ASSERT_TRUE(tx.attach(net).is_ok());
  ASSERT_TRUE(rx.attach(net).is_ok());
  QnavCanPublisher pub(tx);
  pub.set(NavStatus{Mode::kRepeat, true, 90.0, 12, 0, 0});
  pub.set(Health{0, 3, 0, 25.0, false, false});
  int nav = 0, health = 0;
  std::uint8_t last_counter = 0;
  QNAV_EXPECT_NO_ALLOC(for (std::int64_t t = 0; t < 2000000000LL; t += 10000000LL) {  // 2 s in 10 ms steps
    clock.set_ns(t);
    pub.poll(t);
    hal::CanRxFrame f;
    while (rx.receive(f, 0).is_ok()) {
      if (f.frame.id == kIdNavStatus) {
        NavStatus m;
        ASSERT_TRUE(decode(f.frame, m).is_ok());
        if (nav > 0) {
          EXPECT_EQ(m.counter, static_cast<std::uint8_t>(last_counter + 1));
        }
        last_counter = m.counter;
        ++nav;
      } else if (f.frame.id == kIdHealth) {
        ++health;
      }
    }
  });
  EXPECT_EQ(nav, 20);    // 100 ms period over 2 s
  EXPECT_EQ(health, 2);  // 1000 ms period
  EXPECT_EQ(pub.counters().get(TxCounter::kSent), 22u);
}

namespace {
// A bus whose TX queue is full for the first `busy` sends, and for frames of `refuse_id` (0: none);
// it records what it sent.
class BusyBus final : public hal::CanBus {
 public:
  int busy = 2;
  int sent = 0;
  std::uint32_t refuse_id = 0;
  std::vector<hal::CanFrame> frames;
  Status send(const hal::CanFrame& f) noexcept override {
    if (busy > 0 || (refuse_id != 0 && f.id == refuse_id)) {
      busy -= busy > 0 ? 1 : 0;
      return Status(StatusCode::kCapacityExceeded, "full");
    }
    ++sent;
    frames.push_back(f);
    return Status::ok();
  }
  Status receive(hal::CanRxFrame&, int) noexcept override { return Status(StatusCode::kTimeout, "none"); }
  hal::CanBusStats stats() const noexcept override { return {}; }
};
}  // namespace

TEST(QnavCanPublisher, RetriesWhenTxIsFullAndDropsUnencodableValues) {
  BusyBus bus;
  QnavCanPublisher pub(bus);
  pub.set(Heartbeat{10, Mode::kIdle, 0, 1, 0});
  EXPECT_EQ(pub.poll(0), 0);
  EXPECT_EQ(pub.poll(1000000), 0);
  EXPECT_EQ(pub.poll(2000000), 1);
  EXPECT_EQ(pub.counters().get(TxCounter::kTxBusy), 2u);
  pub.set(VoStep{100.0, 0, 0, 0, 0});  // 100 m step: outside the DBC range
  EXPECT_EQ(pub.poll(3000000), 0);
  EXPECT_EQ(pub.counters().get(TxCounter::kEncodeError), 1u);
  EXPECT_EQ(pub.poll(4000000), 0);  // not retried
  EXPECT_EQ(pub.counters().get(TxCounter::kEncodeError), 1u);
}

TEST(QnavCanPublisher, SendsRouteStatusEvery100msRightAfterRouteGuidance) {
  hal::ManualClock clock(0);
  hal::SimCanNetwork net(clock);
  hal::SimCanBus tx, rx;
  ASSERT_TRUE(tx.attach(net).is_ok());
  ASSERT_TRUE(rx.attach(net).is_ok());
  QnavCanPublisher pub(tx);
  pub.set(RouteGuidance{1.5, 0.1, 20.0, 7});
  // A sigma too large for the signal is sent saturated ("unknown"), not dropped as unencodable.
  pub.set(RouteStatus{GuidanceState::kHoldCourse, SideOfRoute::kUnknown, 1e6, 7, 41, 99});
  int status = 0, guidance = 0;
  std::uint8_t last_counter = 0;
  std::uint32_t previous_id = 0;
  QNAV_EXPECT_NO_ALLOC(for (std::int64_t t = 0; t < 2000000000LL; t += 10000000LL) {  // 2 s in 10 ms steps
    clock.set_ns(t);
    pub.poll(t);
    hal::CanRxFrame f;
    while (rx.receive(f, 0).is_ok()) {
      if (f.frame.id == kIdRouteStatus) {
        RouteStatus m;
        ASSERT_TRUE(decode(f.frame, m).is_ok());
        EXPECT_EQ(previous_id, kIdRouteGuidance) << "ROUTE_STATUS follows its ROUTE_GUIDANCE";
        EXPECT_EQ(f.stamp.sample_ns, static_cast<std::int64_t>(status) * 100000000LL);
        EXPECT_EQ(m.status, GuidanceState::kHoldCourse);
        EXPECT_EQ(m.side, SideOfRoute::kUnknown);
        EXPECT_DOUBLE_EQ(m.cross_track_sigma_m, kCrossTrackSigmaMaxM);
        EXPECT_EQ(m.estimate_node, 7);
        EXPECT_EQ(m.tile_seq, 41);
        if (status > 0) {
          EXPECT_EQ(m.counter, static_cast<std::uint8_t>(last_counter + 1));
        } else {
          EXPECT_EQ(m.counter, 0) << "the publisher fills the counter, not the caller";
        }
        last_counter = m.counter;
        ++status;
      } else if (f.frame.id == kIdRouteGuidance) {
        ++guidance;
      }
      previous_id = f.frame.id;
    }
  });
  EXPECT_EQ(status, 20);  // 100 ms period over 2 s
  EXPECT_EQ(guidance, 20);
  EXPECT_EQ(pub.counters().get(TxCounter::kSent), 40u);
  EXPECT_EQ(pub.counters().get(TxCounter::kEncodeError), 0u);
}

TEST(QnavCanPublisher, DropsAFaultWordWithAReservedBit) {
  BusyBus bus;
  bus.busy = 0;
  QnavCanPublisher pub(bus);
  pub.set(Health{static_cast<std::uint16_t>(1u << 12), 0, 0, 0, false, false});
  EXPECT_EQ(pub.poll(0), 0);
  EXPECT_EQ(pub.counters().get(TxCounter::kEncodeError), 1u);
  pub.set(Health{fault::kSoftware, 0, 0, 0, false, false});
  EXPECT_EQ(pub.poll(1000000), 1);
  EXPECT_EQ(bus.sent, 1);
}

// MAP_POSE and MAP_STATUS are per-frame events: each set() goes out once at the next poll, MAP_POSE
// right before MAP_STATUS with the same counter, and is never repeated; the periodic outputs keep
// their periods around them.
TEST(QnavCanPublisher, SendsMapPoseThenMapStatusOncePerSet) {
  hal::ManualClock clock(0);
  hal::SimCanNetwork net(clock);
  hal::SimCanBus tx, rx;
  ASSERT_TRUE(tx.attach(net).is_ok());
  ASSERT_TRUE(rx.attach(net).is_ok());
  QnavCanPublisher pub(tx);
  pub.set(Heartbeat{1, Mode::kMap, 0, 1, 0});
  int poses = 0, statuses = 0;
  std::uint32_t last_id = 0;
  for (int frame = 0; frame < 5; ++frame) {
    MapStatus s;
    s.frame_seq = static_cast<std::uint16_t>(frame);
    s.registered = true;
    pub.set(MapPose{0.5 * frame, 0, 0, 0});
    pub.set(s);
    for (int k = 0; k < 3; ++k) {  // three polls per frame: the event goes out at the first only
      const std::int64_t t = (3 * frame + k) * 10000000LL;
      clock.set_ns(t);
      pub.poll(t);
      hal::CanRxFrame f;
      while (rx.receive(f, 0).is_ok()) {
        if (f.frame.id == kIdMapPose) {
          MapPose p;
          ASSERT_TRUE(decode(f.frame, p).is_ok());
          EXPECT_EQ(k, 0);
          EXPECT_NEAR(p.x, 0.5 * frame, 0.005);
          EXPECT_EQ(p.counter, static_cast<std::uint8_t>(frame));
          ++poses;
        } else if (f.frame.id == kIdMapStatus) {
          MapStatus m;
          ASSERT_TRUE(decode(f.frame, m).is_ok());
          EXPECT_EQ(k, 0);
          EXPECT_EQ(last_id, kIdMapPose) << "MAP_STATUS right after MAP_POSE";
          EXPECT_EQ(m.frame_seq, frame);
          EXPECT_EQ(m.counter, static_cast<std::uint8_t>(frame));
          ++statuses;
        }
        last_id = f.frame.id;
      }
    }
  }
  EXPECT_EQ(poses, 5);
  EXPECT_EQ(statuses, 5);
}

// A map frame's MAP_STATUS that could not go out before the next frame replaced it: the next pair
// still carries one Counter in both frames (the lost status shows as a jump), never a pose paired with
// another frame's status (found in review: with a counter per message they drifted apart for good).
TEST(QnavCanPublisher, MapPoseAndMapStatusOfOneFrameShareTheirCounter) {
  BusyBus bus;
  bus.busy = 0;
  QnavCanPublisher pub(bus);
  MapStatus st;
  st.frame_seq = 0;
  pub.set(MapPose{1.0, 0, 0, 0});
  pub.set(st);
  bus.refuse_id = kIdMapStatus;  // frame 0's status stays behind a full TX queue
  pub.poll(0);
  bus.refuse_id = 0;
  st.frame_seq = 1;
  pub.set(MapPose{2.0, 0, 0, 0});  // frame 1 replaces both before the next poll
  pub.set(st);
  pub.poll(10000000);
  std::vector<std::pair<std::uint32_t, std::uint8_t>> pairs;  // (id, counter) of the map frames sent
  for (const hal::CanFrame& f : bus.frames) {
    if (f.id == kIdMapPose) {
      MapPose p;
      ASSERT_TRUE(decode(f, p).is_ok());
      pairs.emplace_back(f.id, p.counter);
    } else if (f.id == kIdMapStatus) {
      MapStatus m;
      ASSERT_TRUE(decode(f, m).is_ok());
      EXPECT_EQ(m.frame_seq, 1);
      pairs.emplace_back(f.id, m.counter);
    }
  }
  ASSERT_EQ(pairs.size(), 3u);  // pose 0, then pose 1 and status 1
  EXPECT_EQ(pairs[0].first, kIdMapPose);
  EXPECT_EQ(pairs[1].first, kIdMapPose);
  EXPECT_EQ(pairs[2].first, kIdMapStatus);
  EXPECT_EQ(pairs[1].second, pairs[2].second);                             // one frame, one Counter
  EXPECT_EQ(pairs[1].second, static_cast<std::uint8_t>(pairs[0].second + 1));  // the next pair's
}
