// LogRing: a producer's fprintf never blocks, whatever the reader of the log does. Against a real
// pipe nobody reads: lines are accepted until the ring is full, then dropped whole and counted; the
// drain writes only what the pipe takes; once the pipe is read, every accepted line comes out whole
// and in order.
#include "hal/linux/log_ring.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <string>

#include "test/support/alloc_guard.hpp"

namespace qnav::hal {
namespace {

TEST(LogRing, AFullPipeDropsWholeLinesAndNeverBlocks) {
  int p[2];
  ASSERT_EQ(::pipe(p), 0);
  ASSERT_GE(::fcntl(p[1], F_SETPIPE_SZ, 4096), 4096);  // the smallest pipe the kernel gives
  LogRing ring;
  ASSERT_TRUE(ring.open(16384, 512));
  FILE* f = ring.stream();
  const int kLines = 2000;  // ~120 kB: far more than the ring and the pipe hold
  std::uint64_t allocs = 0;
  {
    test::AllocationGuard guard;
    for (int i = 0; i < kLines; ++i) {
      std::fprintf(f, "{\"event\":\"tile\",\"seq\":%05d,\"pad\":\"xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx\"}\n", i);
      if (i % 50 == 0) ring.drain(p[1]);  // the drain stops where the pipe is full, never waits
    }
    allocs = guard.allocations();
  }
  if (test::malloc_counted()) {
    EXPECT_EQ(allocs, 0u);
  }
  EXPECT_GT(ring.dropped_lines(), 0u);
  EXPECT_LT(ring.dropped_lines(), static_cast<std::uint64_t>(kLines));
  // Read everything the pipe holds, draining the rest as room appears.
  ASSERT_EQ(::fcntl(p[0], F_SETFL, O_NONBLOCK), 0);
  std::string out;
  char buf[4096];
  for (int round = 0; round < 1000 && (ring.pending() > 0 || round == 0); ++round) {
    ring.drain(p[1]);
    ssize_t n;
    while ((n = ::read(p[0], buf, sizeof buf)) > 0) out.append(buf, static_cast<std::size_t>(n));
  }
  EXPECT_EQ(ring.pending(), 0u);
  // Every line whole, in increasing order, and accepted + dropped = written.
  std::size_t lines = 0;
  int last = -1;
  std::size_t at = 0;
  while (at < out.size()) {
    const std::size_t nl = out.find('\n', at);
    ASSERT_NE(nl, std::string::npos) << "a partial line at the end";
    const std::string line = out.substr(at, nl - at);
    ASSERT_EQ(line.rfind("{\"event\":\"tile\",\"seq\":", 0), 0u) << line;
    ASSERT_EQ(line.back(), '}') << line;
    const int seq = std::stoi(line.substr(22, 5));
    EXPECT_GT(seq, last);
    last = seq;
    ++lines;
    at = nl + 1;
  }
  EXPECT_EQ(lines + ring.dropped_lines(), static_cast<std::size_t>(kLines));
  ::close(p[0]);
  ::close(p[1]);
}

}  // namespace
}  // namespace qnav::hal
