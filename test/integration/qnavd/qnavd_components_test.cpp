// The nav thread's components on their own (firmware/qnavd/components): what each port does, without
// the daemon's threads around them.
#include <gtest/gtest.h>

#include <vector>

#include "firmware/qnavd/components/nav_source.hpp"
#include "firmware/qnavd/deployment.hpp"
#include "nav/core/spsc_ring.hpp"

namespace qnav::daemon {
namespace {

constexpr std::int64_t kS = 1000000000;

// A map fix: the position kept where a node was created is where the estimate jumps back to when the
// map recognises the revisit; the drift around the loop is gone, reset_counter says so.
TEST(NavSource, ARevisitInTheMapMovesTheEstimateBackToWhereTheNodeWasCreated) {
  DaemonConfig cfg;
  cfg.mavlink_enabled = true;
  cfg.mavlink_udp_listen_port = 14555;
  cfg.map_enabled = true;
  cfg.backend = Backend::kSim;
  ASSERT_TRUE(map_runs(cfg));
  NavClock clock;
  NavContext ctx{&cfg, nullptr, &clock};
  std::vector<MavBytes> rx_items(4), tx_items(64);
  SpscRing<MavBytes> rx, tx;
  ASSERT_TRUE(rx.init(Span<MavBytes>(rx_items.data(), rx_items.size())));
  ASSERT_TRUE(tx.init(Span<MavBytes>(tx_items.data(), tx_items.size())));
  NavSource source(ctx);
  ASSERT_TRUE(source.init(&rx, &tx, nullptr));
  pipeline::DeadReckoner dr;
  // North at 1 m/s: node 3 created at t = 10 s (10 m north), the loop flown, back at t = 50 s where the
  // dead reckoning says 50 m north (the drift: the vehicle is really back at the node).
  std::int64_t flown_s = -1;
  const auto fly_to = [&](std::int64_t t_s) {  // the dead reckoning is causal: fed up to each frame's time
    for (++flown_s; flown_s <= t_s; ++flown_s) {
      dr.on_heading(flown_s * kS, 0.0);
      dr.on_velocity(flown_s * kS, 1.0, 0.0);
    }
    flown_s = t_s;
    clock.now_ns = t_s * kS;
  };
  fly_to(0);
  topo::ObserveResult first;  // the map's first node, where the estimate starts (its origin)
  first.kind = topo::ObserveKind::kCreated;
  first.node = 0;
  source.map_step(first, dr);
  EXPECT_NEAR(source.estimate().north_m(), 0.0, 1e-9);
  topo::ObserveResult created = first;
  created.node = 3;
  fly_to(10);
  source.map_step(created, dr);
  const std::uint32_t fixes_before = source.estimate().fixes();
  const std::uint8_t reset_before = source.estimate().reset_counter();
  EXPECT_NEAR(source.estimate().north_m(), 10.0, 1e-9);
  // The same node seen again in the next frame (not a revisit): nothing moves.
  topo::ObserveResult again = created;
  again.kind = topo::ObserveKind::kMatched;
  again.revisit = false;
  fly_to(11);
  source.map_step(again, dr);
  EXPECT_NEAR(source.estimate().north_m(), 11.0, 1e-9);
  EXPECT_EQ(source.estimate().fixes(), fixes_before);
  // The revisit: back to 10 m north, a fix, reset_counter changed; dead reckoning goes on from there.
  topo::ObserveResult revisit = again;
  revisit.revisit = true;
  fly_to(50);
  source.map_step(revisit, dr);
  EXPECT_NEAR(source.estimate().north_m(), 10.0, 1e-9);
  EXPECT_NEAR(source.estimate().east_m(), 0.0, 1e-9);
  EXPECT_EQ(source.estimate().fixes(), fixes_before + 1);
  EXPECT_NE(source.estimate().reset_counter(), reset_before);
  // A new map forgets the kept positions: the same node id recognised again moves nothing.
  source.map_start();
  source.map_step(revisit, dr);
  EXPECT_NEAR(source.estimate().north_m(), 10.0, 1e-9);
  EXPECT_EQ(source.estimate().fixes(), fixes_before + 1);
}

// The table lists the kept positions as a static buffer when the map and MAVLink both run, and not
// otherwise.
TEST(NavSource, TheMapFixesAreATableEntryOnlyWhenTheMapAndMavlinkRun) {
  DaemonConfig cfg;
  cfg.backend = Backend::kSim;
  cfg.map_enabled = true;
  EXPECT_EQ(make_deployment(cfg).buffer("map_fixes"), nullptr);
  cfg.mavlink_enabled = true;
  const Deployment d = make_deployment(cfg);
  ASSERT_NE(d.buffer("map_fixes"), nullptr);
  EXPECT_GE(d.buffer("map_fixes")->bytes, cfg.map_max_nodes * sizeof(KeptPosition));
}

}  // namespace
}  // namespace qnav::daemon
