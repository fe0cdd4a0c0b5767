// StereoCamera on PGM file sequences (the replay source), with a simulated trigger and strobe.
#include "drivers/camera/stereo_camera.hpp"

#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

#include "hal/sim/manual_clock.hpp"
#include "hal/sim/pgm_sequence_camera.hpp"
#include "hal/sim/sim_gpio.hpp"
#include "test/support/alloc_guard.hpp"

using namespace qnav;
using namespace qnav::drivers::camera;

namespace {
struct TempDir {
  std::string path;
  TempDir() {
    char t[] = "/tmp/qnav_cam_XXXXXX";
    if (mkdtemp(t)) path = t;
  }
  ~TempDir() {
    if (!path.empty()) {
      const std::string cmd = "rm -rf '" + path + "'";
      if (std::system(cmd.c_str()) != 0) {
      }
    }
  }
};
// Writes a w x h PGM whose pixel (x, y) = (value_of(x) + y) & 0xFF.
void write_pgm(const std::string& file, int w, int h, int base, int split_at = -1, int right_base = 0) {
  FILE* f = std::fopen(file.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  std::fprintf(f, "P5\n# qnav test\n%d %d\n255\n", w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) std::fputc(((split_at >= 0 && x >= split_at ? right_base : base) + y) & 0xFF, f);
  std::fclose(f);
}
}  // namespace

TEST(PgmSequence, HeaderAndPatternRules) {
  int w = 0, h = 0;
  std::size_t off = 0;
  const char hdr[] = "P5 # c\n 12 7\n255\n";
  ASSERT_TRUE(hal::parse_pgm_header(reinterpret_cast<const std::uint8_t*>(hdr), sizeof hdr - 1, w, h, off).is_ok());
  EXPECT_EQ(w, 12);
  EXPECT_EQ(h, 7);
  EXPECT_EQ(off, sizeof hdr - 1);
  const char p2[] = "P2\n1 1\n255\n";
  EXPECT_EQ(hal::parse_pgm_header(reinterpret_cast<const std::uint8_t*>(p2), sizeof p2 - 1, w, h, off), StatusCode::kCorrupt);
  const char deep[] = "P5\n1 1\n65535\n";
  EXPECT_EQ(hal::parse_pgm_header(reinterpret_cast<const std::uint8_t*>(deep), sizeof deep - 1, w, h, off), StatusCode::kUnsupported);
  char out[64];
  ASSERT_TRUE(hal::expand_sequence_pattern("run/l_%06d.pgm", 42, out, sizeof out));
  EXPECT_STREQ(out, "run/l_000042.pgm");
  ASSERT_TRUE(hal::expand_sequence_pattern("%d%%", 7, out, sizeof out));
  EXPECT_STREQ(out, "7%");
  EXPECT_FALSE(hal::expand_sequence_pattern("%s", 1, out, sizeof out));
  EXPECT_FALSE(hal::expand_sequence_pattern("%d_%d", 1, out, sizeof out));
  EXPECT_FALSE(hal::expand_sequence_pattern("none", 1, out, sizeof out));
}

TEST(StereoCamera, TwoSequencesWithJitterTriggerAndStrobe) {
  TempDir dir;
  ASSERT_FALSE(dir.path.empty());
  const int n = 8;
  for (int i = 0; i < n; ++i) {
    write_pgm(dir.path + "/l_" + std::to_string(i) + ".pgm", 16, 8, 10 * i);
    write_pgm(dir.path + "/r_" + std::to_string(i) + ".pgm", 16, 8, 10 * i + 5);
  }
  // Right camera stamps: +0.3 ms, but its frame 4 arrives 30 ms late (out of tolerance).
  std::vector<std::int64_t> ls(n), rs(n);
  for (int i = 0; i < n; ++i) {
    ls[static_cast<std::size_t>(i)] = 1000000000LL + i * 50000000LL;
    rs[static_cast<std::size_t>(i)] = ls[static_cast<std::size_t>(i)] + (i == 4 ? 30000000 : 300000);
  }
  const std::string lp = dir.path + "/l_%d.pgm", rp = dir.path + "/r_%d.pgm";
  hal::PgmSequenceCamera left, right;
  hal::PgmSequenceConfig lc;
  lc.pattern = lp.c_str();
  lc.count = n;
  lc.stamps = Span<const std::int64_t>(ls.data(), ls.size());
  hal::PgmSequenceConfig rc = lc;
  rc.pattern = rp.c_str();
  rc.stamps = Span<const std::int64_t>(rs.data(), rs.size());
  ASSERT_TRUE(left.open(lc).is_ok());
  ASSERT_TRUE(right.open(rc).is_ok());
  hal::ManualClock clock(0);
  hal::SimGpioLine trigger(clock, hal::GpioEdge::kRising);
  hal::SimGpioLine strobe(clock, hal::GpioEdge::kRising);
  StereoCamera cam;
  StereoConfig cfg;
  cfg.pair_tolerance_ns = 2000000;
  ASSERT_TRUE(cam.open(left, right, cfg, &trigger, &strobe).is_ok());
  int pairs = 0;
  for (int i = 0; i < n; ++i) {
    strobe.inject_level(true, ls[static_cast<std::size_t>(i)] - 100000);
    strobe.inject_level(false, ls[static_cast<std::size_t>(i)]);
    StereoFrame f;
    Result<bool> r = false;
    QNAV_EXPECT_NO_ALLOC(r = cam.step(f));
    ASSERT_TRUE(r.is_ok()) << r.status().message();
    if (!r.value()) continue;
    ++pairs;
    EXPECT_EQ(f.pair.left.sequence, f.pair.right.sequence);
    EXPECT_EQ(f.pair.skew_ns, 300000);
    EXPECT_EQ(f.left(3, 2), (10 * static_cast<int>(f.pair.left.sequence) + 2) & 0xFF);
    EXPECT_EQ(f.right(3, 2), (10 * static_cast<int>(f.pair.right.sequence) + 5 + 2) & 0xFF);
    EXPECT_TRUE(f.has_exposure);
    EXPECT_EQ(f.exposure_ns, f.pair.left.stamp.sample_ns - 100000);
  }
  EXPECT_EQ(pairs, n - 1);
  EXPECT_EQ(trigger.set_calls(), 2u * n);  // one pulse per step
  EXPECT_GE(cam.pairer().counters().get(PairCounter::kUnmatched), 1u);
  StereoFrame f;
  EXPECT_EQ(cam.step(f).status(), StatusCode::kEmpty);
}

TEST(StereoCamera, SideBySideSplitsOneFrame) {
  TempDir dir;
  ASSERT_FALSE(dir.path.empty());
  write_pgm(dir.path + "/sbs_0.pgm", 20, 4, 10, 10, 200);
  write_pgm(dir.path + "/sbs_1.pgm", 20, 4, 11, 10, 201);
  const std::string pat = dir.path + "/sbs_%d.pgm";
  hal::PgmSequenceCamera both;
  hal::PgmSequenceConfig c;
  c.pattern = pat.c_str();
  c.count = 2;
  ASSERT_TRUE(both.open(c).is_ok());
  StereoCamera cam;
  ASSERT_TRUE(cam.open_side_by_side(both, StereoConfig{}).is_ok());
  StereoFrame f;
  ASSERT_TRUE(cam.step(f).value());
  EXPECT_EQ(f.left.width(), 10);
  EXPECT_EQ(f.right.width(), 10);
  EXPECT_EQ(f.left(9, 1), 11);
  EXPECT_EQ(f.right(0, 1), 201);
  EXPECT_EQ(f.pair.skew_ns, 0);
  ASSERT_TRUE(cam.step(f).value());
  EXPECT_EQ(f.right(9, 3), 204);
}

TEST(StereoCamera, MissingFileIsCountedAndTheSequenceContinues) {
  TempDir dir;
  ASSERT_FALSE(dir.path.empty());
  write_pgm(dir.path + "/a_0.pgm", 8, 8, 1);
  write_pgm(dir.path + "/a_2.pgm", 8, 8, 3);
  const std::string pat = dir.path + "/a_%d.pgm";
  hal::PgmSequenceCamera seq;
  hal::PgmSequenceConfig c;
  c.pattern = pat.c_str();
  c.count = 3;
  ASSERT_TRUE(seq.open(c).is_ok());
  std::uint8_t px[64];
  auto v = ImageView<std::uint8_t>::make(px, 8, 8).value();
  EXPECT_TRUE(seq.capture(v, 0).is_ok());
  EXPECT_EQ(seq.capture(v, 0).status(), StatusCode::kNotFound);
  auto r = seq.capture(v, 0);
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(r.value().sequence, 2u);
  EXPECT_EQ(seq.stats().corrupt, 1u);
  EXPECT_EQ(seq.capture(v, 0).status(), StatusCode::kEmpty);
}
