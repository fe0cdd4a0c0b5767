// SocketCanBus against vcan0 when the machine has it (`ip link add dev vcan0 type vcan && ip link set
// vcan0 up`); otherwise the kernel-facing cases skip and only the error paths run.
#include "hal/linux/socketcan_bus.hpp"

#include <gtest/gtest.h>
#include <net/if.h>

#include "hal/linux/monotonic_clock.hpp"
#include "test/support/alloc_guard.hpp"

using namespace qnav;
using namespace qnav::hal;

TEST(SocketCan, MissingInterfaceIsAnError) {
  SocketCanBus bus;
  SocketCanConfig c;
  c.interface = "qnavnope0";
  const Status s = bus.open(c);
  EXPECT_FALSE(s.is_ok());  // kNotFound, or kIoError when the kernel has no CAN at all
  EXPECT_FALSE(bus.is_open());
  CanRxFrame f;
  EXPECT_EQ(bus.receive(f, 0), StatusCode::kNotReady);
}

TEST(SocketCan, Vcan0LoopbackWithFilterAndKernelTimestamp) {
  if (if_nametoindex("vcan0") == 0) GTEST_SKIP() << "no vcan0 on this machine (ip link add dev vcan0 type vcan)";
  SocketCanBus tx, rx;
  SocketCanConfig tc;
  tc.interface = "vcan0";
  ASSERT_TRUE(tx.open(tc).is_ok());
  SocketCanConfig rc;
  rc.interface = "vcan0";
  CanFilter f;
  f.id = 0x321;
  f.mask = kCanSffMask;
  ASSERT_TRUE(rc.filters.push_back(f).is_ok());
  ASSERT_TRUE(rx.open(rc).is_ok());
  CanFrame other;
  other.id = 0x322;
  other.len = 1;
  ASSERT_TRUE(tx.send(other).is_ok());
  CanFrame want;
  want.id = 0x321;
  want.len = 3;
  want.data[0] = 1;
  want.data[2] = 3;
  const std::int64_t t0 = monotonic_now_ns();
  ASSERT_TRUE(tx.send(want).is_ok());
  CanRxFrame got;
  Status s = Status::ok();
  QNAV_EXPECT_NO_ALLOC(s = rx.receive(got, 500));
  ASSERT_TRUE(s.is_ok()) << s.message();
  EXPECT_EQ(got.frame.id, 0x321u);
  EXPECT_EQ(got.frame.len, 3);
  EXPECT_EQ(got.frame.data[2], 3);
  EXPECT_GE(got.stamp.sample_ns, t0 - 1000000);  // kernel stamp, converted to monotonic
  EXPECT_LE(got.stamp.sample_ns, got.stamp.arrival_ns + 1000000);
  EXPECT_EQ(rx.receive(got, 20), StatusCode::kTimeout);  // 0x322 was filtered by the kernel
}
