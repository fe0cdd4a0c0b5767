// MavlinkLink over an in-process serial pipe (every target): frames both ways with their values and
// arrival times, signed links, a full port counted as tx_short, and no heap in poll() / send().
#include <gtest/gtest.h>

#include <vector>

#include "drivers/mavlink/link.hpp"
#include "hal/sim/manual_clock.hpp"
#include "hal/sim/sim_serial.hpp"
#include "test/support/alloc_guard.hpp"

namespace qnav::drivers::mavlink {
namespace {

TEST(MavlinkLink, FramesCrossThePipeWithTheirValues) {
  hal::ManualClock clock(5000);
  hal::SimSerialPipe pipe(clock);
  Link qnav(pipe.a(), 1, kMavCompIdVisualInertialOdometry);
  Link autopilot(pipe.b(), 1, 1);

  Odometry o;
  o.time_usec = 42;
  o.x = 3.5f;
  o.quality = -1;
  o.reset_counter = 4;
  ASSERT_TRUE(qnav.send(o).is_ok());
  Heartbeat hb;
  hb.type = kMavTypeOnboardController;
  ASSERT_TRUE(qnav.send(hb).is_ok());
  std::vector<std::uint32_t> ids;
  auto n = autopilot.poll(0, [&](const Frame& f, std::int64_t arrival_ns) {
    ids.push_back(f.msgid);
    EXPECT_EQ(arrival_ns, 5000);
    EXPECT_EQ(f.sysid, 1);
    EXPECT_EQ(f.compid, kMavCompIdVisualInertialOdometry);
    Odometry back;
    if (decode(f, back)) {
      EXPECT_EQ(back.time_usec, 42u);
      EXPECT_EQ(back.x, 3.5f);
      EXPECT_EQ(back.quality, -1);
      EXPECT_EQ(back.reset_counter, 4);
      EXPECT_EQ(back.frame_id, kMavFrameLocalFrd);
      EXPECT_EQ(back.child_frame_id, kMavFrameBodyFrd);
    }
  });
  ASSERT_TRUE(n.is_ok());
  EXPECT_EQ(n.value(), 2);
  EXPECT_EQ(ids, (std::vector<std::uint32_t>{Odometry::kId, Heartbeat::kId}));
  EXPECT_EQ(qnav.stats().frames_tx, 2u);
  EXPECT_EQ(autopilot.stats().frames_rx, 2u);

  // The other way: a COMMAND_LONG and its ACK.
  CommandLong c;
  c.command = 31010;
  c.target_system = 1;
  c.target_component = kMavCompIdVisualInertialOdometry;
  ASSERT_TRUE(autopilot.send(c).is_ok());
  int acks = 0;
  ASSERT_TRUE(qnav.poll(0, [&](const Frame& f, std::int64_t) {
                    CommandLong got;
                    if (!decode(f, got)) return;
                    CommandAck ack;
                    ack.command = got.command;
                    ack.target_system = f.sysid;
                    ack.target_component = f.compid;
                    EXPECT_TRUE(qnav.send(ack).is_ok());
                  }).is_ok());
  ASSERT_TRUE(autopilot.poll(0, [&](const Frame& f, std::int64_t) {
                        CommandAck ack;
                        if (decode(f, ack) && ack.command == 31010) ++acks;
                      }).is_ok());
  EXPECT_EQ(acks, 1);
}

TEST(MavlinkLink, SignedLinkVerifiesAndAnUnkeyedReceiverRefuses) {
  hal::ManualClock clock;
  hal::SimSerialPipe pipe(clock);
  SigningKey key;
  for (std::size_t i = 0; i < sizeof(key.secret); ++i) key.secret[i] = static_cast<std::uint8_t>(3 * i);
  key.link_id = 1;
  Link gcs(pipe.a(), 255, 190);
  gcs.set_signing_key(key, true);
  Link qnav(pipe.b(), 1, 197);
  qnav.set_signing_key(key, false);
  CommandLong c;
  c.command = 31010;
  ASSERT_TRUE(gcs.send(c, 1000).is_ok());
  ASSERT_TRUE(gcs.send(c, 1000).is_ok());  // a replayed timestamp
  ASSERT_TRUE(gcs.send(c, 1001).is_ok());
  int verified = 0;
  ASSERT_TRUE(qnav.poll(0, [&](const Frame& f, std::int64_t) { verified += f.signature_verified ? 1 : 0; }).is_ok());
  EXPECT_EQ(verified, 2);
  EXPECT_EQ(qnav.parser().counters().get(ParserCounter::kReplay), 1u);

  hal::SimSerialPipe pipe2(clock);
  Link gcs2(pipe2.a(), 255, 190);
  gcs2.set_signing_key(key, true);
  Link unkeyed(pipe2.b(), 1, 197);
  ASSERT_TRUE(gcs2.send(c, 5).is_ok());
  int got = 0;
  ASSERT_TRUE(unkeyed.poll(0, [&](const Frame&, std::int64_t) { ++got; }).is_ok());
  EXPECT_EQ(got, 0);
  EXPECT_EQ(unkeyed.parser().counters().get(ParserCounter::kSignedRefused), 1u);
}

TEST(MavlinkLink, AFullPortIsCountedAndTheFramesThatFitArriveWhole) {
  hal::ManualClock clock;
  hal::SimSerialPipe pipe(clock);
  Link qnav(pipe.a(), 1, 197);
  Link autopilot(pipe.b(), 1, 1);
  Odometry o;
  o.x = 1.0f;
  o.pose_covariance[20] = 2.0f;  // a long frame (no truncation of the covariances)
  int sent = 0;
  Status last;
  for (int i = 0; i < 100; ++i) {
    last = qnav.send(o);
    if (!last.is_ok()) break;
    ++sent;
  }
  EXPECT_EQ(last.code(), StatusCode::kCapacityExceeded);
  EXPECT_EQ(qnav.counters().get(LinkCounter::kTxShort), 1u);
  EXPECT_GT(sent, 0);
  int got = 0;
  // The cut frame's head reaches the receiver; a later frame follows it, so the cut one is rejected.
  ASSERT_TRUE(autopilot.poll(0, [&](const Frame&, std::int64_t) { ++got; }).is_ok());
  ASSERT_TRUE(qnav.send(o).is_ok());
  ASSERT_TRUE(autopilot.poll(0, [&](const Frame&, std::int64_t) { ++got; }).is_ok());
  EXPECT_EQ(got, sent + 1);
  EXPECT_GE(autopilot.parser().counters().total(), 1u);
}

TEST(MavlinkLink, PollAndSendAllocateNothing) {
  hal::ManualClock clock;
  hal::SimSerialPipe pipe(clock);
  Link qnav(pipe.a(), 1, 197);
  Link autopilot(pipe.b(), 1, 1);
  int got = 0;
  QNAV_EXPECT_NO_ALLOC({
    for (int i = 0; i < 50; ++i) {
      Odometry o;
      o.time_usec = static_cast<std::uint64_t>(i);
      qnav.send(o).ignore();
      autopilot.poll(0, [&](const Frame&, std::int64_t) { ++got; }).status().ignore();
    }
  });
  EXPECT_EQ(got, 50);
}

}  // namespace
}  // namespace qnav::drivers::mavlink
