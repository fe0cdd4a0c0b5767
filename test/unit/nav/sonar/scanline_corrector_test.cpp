// ScanlineCorrector: slant->ground geometry, bottom detection, TVG/EGN flattening, bad input.
#include "nav/sonar/scanline_corrector.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "test/support/alloc_guard.hpp"

namespace qnav::sonar {
namespace {

struct Fixture {
  ArenaStorage arena{1 << 20};
  ScanlineCorrector corr;
  explicit Fixture(const ScanlineCorrectorConfig& c) { EXPECT_TRUE(corr.init(c, arena).is_ok()); }
};

// A synthetic ping over a flat seabed at altitude h: water column = low noise, seabed = a level
// that follows the TVG model's inverse, so after TVG it is flat.
void flat_ping(std::vector<float>& port, std::vector<float>& stbd, int n, float range_m, float h, float k) {
  port.assign(static_cast<std::size_t>(n), 0.0f);
  stbd.assign(static_cast<std::size_t>(n), 0.0f);
  const float dr = range_m / static_cast<float>(n);
  for (int i = 0; i < n; ++i) {
    const float r = (static_cast<float>(i) + 0.5f) * dr;
    const float v = r < h ? 0.01f : 100.0f * std::pow(r, -k);
    port[static_cast<std::size_t>(i)] = v;
    stbd[static_cast<std::size_t>(i)] = v;
  }
}

TEST(ScanlineCorrector, RejectsBadConfig) {
  ArenaStorage arena(1 << 16);
  ScanlineCorrector c;
  ScanlineCorrectorConfig cfg;
  cfg.ground_bin_m = 0.0f;
  EXPECT_EQ(c.init(cfg, arena), StatusCode::kInvalidArgument);
  cfg = ScanlineCorrectorConfig{};
  cfg.max_samples_per_side = 1 << 20;
  EXPECT_EQ(c.init(cfg, arena), StatusCode::kInvalidArgument);
  cfg = ScanlineCorrectorConfig{};
  ArenaStorage tiny(64);
  EXPECT_EQ(c.init(cfg, tiny), StatusCode::kCapacityExceeded);
  EXPECT_GE(ScanlineCorrector::arena_bytes(cfg), sizeof(float) * 4096u);
}

TEST(ScanlineCorrector, DetectsBottomOfFlatSeabed) {
  ScanlineCorrectorConfig cfg;
  Fixture f(cfg);
  std::vector<float> port, stbd;
  const float h = 7.3f;
  flat_ping(port, stbd, 1024, 50.0f, h, 1.0f);
  SonarPing p;
  p.port = Span<const float>(port.data(), port.size());
  p.stbd = Span<const float>(stbd.data(), stbd.size());
  p.slant_range_m = 50.0f;
  const Result<float> b = f.corr.detect_bottom_m(p);
  ASSERT_TRUE(b.is_ok()) << b.status().message();
  // One sample is 4.9 cm; the box-smoothing compensation is good to about a sample.
  EXPECT_NEAR(b.value(), h, 0.1f);
}

TEST(ScanlineCorrector, BottomDetectionIgnoresASaturatedTransmitPulse) {
  // Real Iver2 pings start with 8 saturated samples (32767): they must not count as the seabed nor
  // raise the water-column noise estimate.
  ScanlineCorrectorConfig cfg;
  Fixture f(cfg);
  std::vector<float> port, stbd;
  const float h = 5.8f;
  flat_ping(port, stbd, 1024, 30.0f, h, 1.0f);
  for (int i = 0; i < 8; ++i) port[static_cast<std::size_t>(i)] = stbd[static_cast<std::size_t>(i)] = 32767.0f;
  SonarPing p;
  p.port = Span<const float>(port.data(), port.size());
  p.stbd = Span<const float>(stbd.data(), stbd.size());
  p.slant_range_m = 30.0f;
  const Result<float> b = f.corr.detect_bottom_m(p);
  ASSERT_TRUE(b.is_ok()) << b.status().message();
  EXPECT_NEAR(b.value(), h, 0.1f);
}

TEST(ScanlineCorrector, GroundRangeGeometryPlacesAStepAtItsGroundRange) {
  // A bright patch at ground range 20..21 m on starboard must land in bins 200..209 (0.1 m bins).
  ScanlineCorrectorConfig cfg;
  cfg.tvg_enabled = false;
  cfg.egn_enabled = false;
  Fixture f(cfg);
  const int n = 2000;
  const float range = 40.0f, h = 10.0f, dr = range / n;
  std::vector<float> port(n, 1.0f), stbd(n, 1.0f);
  for (int i = 0; i < n; ++i) {
    const float r = (static_cast<float>(i) + 0.5f) * dr;
    const float g = r > h ? std::sqrt(r * r - h * h) : -1.0f;
    if (g >= 20.0f && g < 21.0f) stbd[static_cast<std::size_t>(i)] = 5.0f;
  }
  SonarPing p;
  p.port = Span<const float>(port.data(), port.size());
  p.stbd = Span<const float>(stbd.data(), stbd.size());
  p.slant_range_m = range;
  p.altitude_m = h;
  CorrectedScanline out;
  ASSERT_TRUE(f.corr.correct(p, out).is_ok());
  ASSERT_EQ(out.stbd.size(), 512u);
  for (int b = 190; b < 220; ++b) {
    const float v = out.stbd[static_cast<std::size_t>(b)];
    if (b >= 201 && b <= 208) {
      EXPECT_NEAR(v, 5.0f, 0.05f) << "bin " << b;
    }
    if (b <= 198 || b >= 211) {
      EXPECT_NEAR(v, 1.0f, 0.05f) << "bin " << b;
    }
  }
  EXPECT_FALSE(out.altitude_detected);
  EXPECT_FLOAT_EQ(out.altitude_m, h);
  // Beyond the last sample (ground range sqrt(40^2 - 10^2) = 38.73 m) bins are invalid.
  EXPECT_EQ(out.stbd_valid[386], 1);
  EXPECT_EQ(out.stbd_valid[388], 0);
  EXPECT_EQ(out.stbd[500], 0.0f);
}

TEST(ScanlineCorrector, TvgAndEgnFlattenAUniformSeabed) {
  ScanlineCorrectorConfig cfg;
  cfg.spreading_db = 10.0f;  // the synthetic ping falls as r^-1
  Fixture f(cfg);
  std::vector<float> port, stbd;
  flat_ping(port, stbd, 1024, 50.0f, 8.0f, 1.0f);
  SonarPing p;
  p.port = Span<const float>(port.data(), port.size());
  p.stbd = Span<const float>(stbd.data(), stbd.size());
  p.slant_range_m = 50.0f;
  p.altitude_m = 8.0f;
  CorrectedScanline out;
  for (int k = 0; k < 3; ++k) ASSERT_TRUE(f.corr.correct(p, out).is_ok());
  int valid = 0;
  for (std::size_t b = 0; b < out.port.size(); ++b) {
    if (!out.port_valid[b]) continue;
    ++valid;
    EXPECT_NEAR(out.port[b], 1.0f, 1e-3f) << b;
  }
  EXPECT_GT(valid, 400);
}

TEST(ScanlineCorrector, EgnStartsWithThePlainMeanThenRuns) {
  // Pings of level 1 and 3 alternately: the second ping is divided by their mean 2 (plain mean
  // during warm-up), not by a running mean still stuck near the first value.
  ScanlineCorrectorConfig cfg;
  cfg.tvg_enabled = false;
  cfg.egn_alpha = 0.02f;
  Fixture f(cfg);
  std::vector<float> lo(512, 1.0f), hi(512, 3.0f);
  SonarPing p;
  p.slant_range_m = 50.0f;
  p.altitude_m = 8.0f;
  CorrectedScanline out;
  p.port = p.stbd = Span<const float>(lo.data(), lo.size());
  ASSERT_TRUE(f.corr.correct(p, out).is_ok());
  EXPECT_NEAR(out.port[300], 1.0f, 1e-5f);
  p.port = p.stbd = Span<const float>(hi.data(), hi.size());
  ASSERT_TRUE(f.corr.correct(p, out).is_ok());
  EXPECT_NEAR(out.port[300], 1.5f, 1e-5f);
  // After 1/alpha = 50 pings the mean runs exponentially: one more ping at 3 moves it by alpha.
  for (int k = 2; k < 100; ++k) {
    p.port = p.stbd = Span<const float>(k % 2 ? hi.data() : lo.data(), 512);
    ASSERT_TRUE(f.corr.correct(p, out).is_ok());
  }
  EXPECT_NEAR(out.port[300], 3.0f / 2.0f, 0.05f);
}

TEST(ScanlineCorrector, NadirGapBinsAreInvalid) {
  ScanlineCorrectorConfig cfg;
  cfg.nadir_gap_m = 1.5f;
  Fixture f(cfg);
  std::vector<float> port, stbd;
  flat_ping(port, stbd, 1024, 50.0f, 8.0f, 1.0f);
  SonarPing p;
  p.port = Span<const float>(port.data(), port.size());
  p.stbd = Span<const float>(stbd.data(), stbd.size());
  p.slant_range_m = 50.0f;
  p.altitude_m = 8.0f;
  CorrectedScanline out;
  ASSERT_TRUE(f.corr.correct(p, out).is_ok());
  for (int b = 0; b < 15; ++b) EXPECT_EQ(out.port_valid[static_cast<std::size_t>(b)], 0) << b;
  EXPECT_EQ(out.port_valid[15], 1);
}

TEST(ScanlineCorrector, BadInputIsRejectedAndCounted) {
  ScanlineCorrectorConfig cfg;
  Fixture f(cfg);
  std::vector<float> port, stbd;
  flat_ping(port, stbd, 256, 50.0f, 8.0f, 1.0f);
  SonarPing p;
  p.port = Span<const float>(port.data(), port.size());
  p.stbd = Span<const float>(stbd.data(), stbd.size());
  p.slant_range_m = std::nanf("");
  CorrectedScanline out;
  EXPECT_EQ(f.corr.correct(p, out), StatusCode::kInvalidArgument);
  EXPECT_EQ(f.corr.counters().get(CorrectorCounter::kBadRange), 1u);
  p.slant_range_m = 50.0f;
  port[10] = std::nanf("");
  EXPECT_EQ(f.corr.correct(p, out), StatusCode::kInvalidArgument);
  EXPECT_EQ(f.corr.counters().get(CorrectorCounter::kNonFiniteSample), 1u);
  port[10] = 0.0f;
  p.stbd = Span<const float>(stbd.data(), 100);
  EXPECT_EQ(f.corr.correct(p, out), StatusCode::kInvalidArgument);
  EXPECT_EQ(f.corr.counters().get(CorrectorCounter::kBadSampleCount), 1u);
  // Pure noise: no bottom to find.
  std::vector<float> flat(256, 1.0f);
  p.port = Span<const float>(flat.data(), flat.size());
  p.stbd = Span<const float>(flat.data(), flat.size());
  EXPECT_EQ(f.corr.correct(p, out), StatusCode::kNotFound);
  EXPECT_EQ(f.corr.counters().get(CorrectorCounter::kNoBottom), 1u);
  // Altitude beyond the range.
  p.altitude_m = 60.0f;
  EXPECT_EQ(f.corr.correct(p, out), StatusCode::kInvalidArgument);
  EXPECT_EQ(f.corr.counters().get(CorrectorCounter::kBadAltitude), 1u);
}

// Regression (issue #19): one flipped bit turned a 30 m slant range into 8.8e-38 m; the blanking
// index min_altitude / (range / n) overflowed int and bottom detection read far out of bounds. Every
// range no longer than the blanking distance is refused and counted, with or without an altitude.
TEST(ScanlineCorrector, TinySlantRangeIsRejectedNotIndexed) {
  ScanlineCorrectorConfig cfg;
  Fixture f(cfg);
  std::vector<float> port, stbd;
  flat_ping(port, stbd, 256, 30.0f, 8.0f, 1.0f);
  SonarPing p;
  p.port = Span<const float>(port.data(), port.size());
  p.stbd = Span<const float>(stbd.data(), stbd.size());
  CorrectedScanline out;
  std::uint64_t expected = 0;
  for (float r : {8.8e-38f, 1e-30f, 1e-6f, cfg.min_altitude_m}) {
    p.slant_range_m = r;
    p.altitude_m = 0.0f;  // detect the bottom
    EXPECT_EQ(f.corr.correct(p, out), StatusCode::kInvalidArgument) << r;
    EXPECT_EQ(f.corr.detect_bottom_m(p).status(), StatusCode::kInvalidArgument) << r;
    expected += 2;
    EXPECT_EQ(f.corr.counters().get(CorrectorCounter::kBadRange), expected) << r;
  }
  // Just above the blanking distance the ping is checked normally (no bottom in 0.6 m of water).
  p.slant_range_m = cfg.min_altitude_m * 1.2f;
  EXPECT_EQ(f.corr.correct(p, out), StatusCode::kNotFound);
  p.slant_range_m = 30.0f;
  EXPECT_TRUE(f.corr.correct(p, out).is_ok());
}

TEST(ScanlineCorrector, CorrectMakesNoHeapAllocation) {
  ScanlineCorrectorConfig cfg;
  Fixture f(cfg);
  std::vector<float> port, stbd;
  flat_ping(port, stbd, 1024, 50.0f, 8.0f, 1.0f);
  SonarPing p;
  p.port = Span<const float>(port.data(), port.size());
  p.stbd = Span<const float>(stbd.data(), stbd.size());
  p.slant_range_m = 50.0f;
  CorrectedScanline out;
  Status s;
  QNAV_EXPECT_NO_ALLOC(for (int k = 0; k < 20; ++k) s = f.corr.correct(p, out));
  EXPECT_TRUE(s.is_ok());
  EXPECT_TRUE(out.altitude_detected);
}

// The sample check works on the float bits: every value that is not finite and >= 0 is refused,
// on either side and at any index; -0, the largest float and the smallest subnormal pass.
TEST(ScanlineCorrector, SampleCheckRefusesEveryNonFiniteOrNegativeValueAndOnlyThose) {
  ScanlineCorrectorConfig cfg;
  Fixture f(cfg);
  std::vector<float> port, stbd;
  flat_ping(port, stbd, 256, 50.0f, 8.0f, 1.0f);
  SonarPing p;
  p.port = Span<const float>(port.data(), port.size());
  p.stbd = Span<const float>(stbd.data(), stbd.size());
  p.slant_range_m = 50.0f;
  p.altitude_m = 8.0f;
  CorrectedScanline out;
  const float bad[] = {std::nanf(""), -std::nanf(""), INFINITY, -INFINITY, -1e-30f, -1.0f, -std::numeric_limits<float>::denorm_min()};
  const float good[] = {-0.0f, 0.0f, std::numeric_limits<float>::max(), std::numeric_limits<float>::denorm_min(), 1.0f};
  std::uint32_t refused = 0;
  for (std::size_t at : {std::size_t{0}, std::size_t{77}, std::size_t{255}}) {
    for (std::vector<float>* side : {&port, &stbd}) {
      const float keep = (*side)[at];
      for (float v : bad) {
        (*side)[at] = v;
        EXPECT_EQ(f.corr.correct(p, out), StatusCode::kInvalidArgument) << v << " at " << at;
        ++refused;
      }
      for (float v : good) {
        (*side)[at] = v;
        EXPECT_TRUE(f.corr.correct(p, out).is_ok()) << v << " at " << at;
      }
      (*side)[at] = keep;
    }
  }
  EXPECT_EQ(f.corr.counters().get(CorrectorCounter::kNonFiniteSample), refused);
}

}  // namespace
}  // namespace qnav::sonar
