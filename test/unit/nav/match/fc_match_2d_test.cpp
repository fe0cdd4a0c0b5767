#include "nav/match/fc_match_2d.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "nav/core/arena.hpp"
#include "nav/match/ransac.hpp"
#include "test/support/alloc_guard.hpp"

namespace qnav::match {
namespace {

constexpr std::size_t kD = 64;

struct Sets {
  std::vector<Vec2d> pa, pb;
  std::vector<std::int8_t> da, db;
  std::vector<int> truth;  // truth[i] = index in B of A's point i, or -1
};

// A: n points; B: the same seabed seen from pose `rel` (b = rel.apply(a)), shuffled, plus clutter.
Sets make(int n, const Pose2& rel, double noise_m, int clutter, bool scramble_desc, std::uint64_t seed) {
  DeterministicRng rng(seed);
  Sets s;
  std::vector<std::int8_t> base(static_cast<std::size_t>(n) * kD);
  for (auto& v : base) v = static_cast<std::int8_t>(static_cast<int>(rng.below(200)) - 100);
  for (int i = 0; i < n; ++i) s.pa.push_back(Vec2d((rng.uniform() - 0.5) * 60, (rng.uniform() - 0.5) * 40));
  s.da = base;
  const int nb = n + clutter;
  std::vector<int> perm(static_cast<std::size_t>(nb));
  for (int i = 0; i < nb; ++i) perm[static_cast<std::size_t>(i)] = i;
  for (int i = nb - 1; i > 0; --i) std::swap(perm[static_cast<std::size_t>(i)], perm[rng.below(static_cast<std::uint32_t>(i + 1))]);
  s.pb.resize(static_cast<std::size_t>(nb));
  s.db.resize(static_cast<std::size_t>(nb) * kD);
  s.truth.assign(static_cast<std::size_t>(n), -1);
  for (int j = 0; j < nb; ++j) {
    const int src = perm[static_cast<std::size_t>(j)];
    if (src < n) {
      s.pb[static_cast<std::size_t>(j)] = rel.apply(s.pa[static_cast<std::size_t>(src)]) + Vec2d((rng.uniform() - 0.5) * noise_m, (rng.uniform() - 0.5) * noise_m);
      for (std::size_t k = 0; k < kD; ++k) {
        int v = scramble_desc ? static_cast<int>(rng.below(200)) - 100 : base[static_cast<std::size_t>(src) * kD + k] + static_cast<int>(rng.below(21)) - 10;
        s.db[static_cast<std::size_t>(j) * kD + k] = static_cast<std::int8_t>(v);
      }
      s.truth[static_cast<std::size_t>(src)] = j;
    } else {
      s.pb[static_cast<std::size_t>(j)] = Vec2d((rng.uniform() - 0.5) * 60, (rng.uniform() - 0.5) * 40);
      for (std::size_t k = 0; k < kD; ++k) s.db[static_cast<std::size_t>(j) * kD + k] = static_cast<std::int8_t>(static_cast<int>(rng.below(200)) - 100);
    }
  }
  return s;
}

TEST(Zncc, IdenticalIsOneNegatedIsMinusOneFlatIsZero) {
  std::int8_t a[kD], b[kD], f[kD];
  for (std::size_t i = 0; i < kD; ++i) {
    a[i] = static_cast<std::int8_t>((i * 37) % 101 - 50);
    b[i] = static_cast<std::int8_t>(-a[i]);
    f[i] = 5;
  }
  EXPECT_NEAR(zncc_i8(a, a, kD), 1.0f, 1e-6f);
  EXPECT_NEAR(zncc_i8(a, b, kD), -1.0f, 1e-6f);
  EXPECT_EQ(zncc_i8(a, f, kD), 0.0f);
}

struct Fixture {
  ArenaStorage arena{FcMatcher2d::arena_bytes(FcMatch2dConfig{})};
  FcMatcher2d m;
  std::vector<Match2d> store = std::vector<Match2d>(128);
  Fixture() { EXPECT_TRUE(m.init(FcMatch2dConfig{}, arena).is_ok()); }
  BoundedVector<Match2d> run(const Sets& s, double dtheta) {
    BoundedVector<Match2d> out(Span<Match2d>(store.data(), store.size()));
    KeypointSet2d a{Span<const Vec2d>(s.pa.data(), s.pa.size()), Span<const std::int8_t>(s.da.data(), s.da.size()), kD};
    KeypointSet2d b{Span<const Vec2d>(s.pb.data(), s.pb.size()), Span<const std::int8_t>(s.db.data(), s.db.size()), kD};
    EXPECT_TRUE(m.match(a, b, dtheta, out).is_ok());
    return out;
  }
};

TEST(FcMatch2d, MatchesARotatedTranslatedSetWithClutter) {
  const Pose2 rel{8.0, -3.0, 0.4};
  Sets s = make(40, rel, 0.5, 30, false, 5);
  Fixture f;
  BoundedVector<Match2d> out = f.run(s, 0.4);
  int correct = 0;
  for (const Match2d& m : out) correct += s.truth[m.a] == m.b;
  EXPECT_GE(correct, 34);
  EXPECT_LE(static_cast<int>(out.size()) - correct, 3);
}

TEST(FcMatch2d, ReversePassHalfTurnMatches) {
  const Pose2 rel{-20.0, 5.0, 3.1};
  Sets s = make(40, rel, 0.5, 10, false, 6);
  Fixture f;
  BoundedVector<Match2d> out = f.run(s, 3.1);
  int correct = 0;
  for (const Match2d& m : out) correct += s.truth[m.a] == m.b;
  EXPECT_GE(correct, 34);
}

TEST(FcMatch2d, GeometryRejectsAWrongHeadingAndUnrelatedDescriptorsGiveFewMatches) {
  const Pose2 rel{8.0, -3.0, 0.4};
  Sets s = make(40, rel, 0.5, 10, false, 8);
  Fixture f;
  BoundedVector<Match2d> wrong = f.run(s, 0.4 + 1.2);  // directions not preserved under this rotation
  int correct = 0;
  for (const Match2d& m : wrong) correct += s.truth[m.a] == m.b;
  EXPECT_LT(correct, 10);
  Sets u = make(40, rel, 0.5, 10, true, 9);
  BoundedVector<Match2d> none = f.run(u, 0.4);
  EXPECT_LT(none.size(), 8u);
}

TEST(FcMatch2d, NoHeapInMatch) {
  Sets s = make(40, Pose2{1, 1, 0.1}, 0.5, 10, false, 10);
  Fixture f;
  BoundedVector<Match2d> out(Span<Match2d>(f.store.data(), f.store.size()));
  KeypointSet2d a{Span<const Vec2d>(s.pa.data(), s.pa.size()), Span<const std::int8_t>(s.da.data(), s.da.size()), kD};
  KeypointSet2d b{Span<const Vec2d>(s.pb.data(), s.pb.size()), Span<const std::int8_t>(s.db.data(), s.db.size()), kD};
  QNAV_EXPECT_NO_ALLOC(EXPECT_TRUE(f.m.match(a, b, 0.1, out).is_ok()));
  EXPECT_GT(out.size(), 20u);
}

TEST(FcMatch2d, InconsistentInputIsAnErrorAndCounted) {
  Sets s = make(10, Pose2{}, 0.1, 0, false, 1);
  Fixture f;
  BoundedVector<Match2d> out(Span<Match2d>(f.store.data(), f.store.size()));
  KeypointSet2d a{Span<const Vec2d>(s.pa.data(), s.pa.size()), Span<const std::int8_t>(s.da.data(), 10), kD};
  KeypointSet2d b{Span<const Vec2d>(s.pb.data(), s.pb.size()), Span<const std::int8_t>(s.db.data(), s.db.size()), kD};
  EXPECT_EQ(f.m.match(a, b, 0.0, out), StatusCode::kInvalidArgument);
  EXPECT_EQ(f.m.match(b, b, std::nan(""), out), StatusCode::kInvalidArgument);
  EXPECT_EQ(f.m.counters().get(FcMatchCounter::kBadInput), 2u);
}

// The appearance of each match is the ZNCC of its two descriptors: the matcher's dot products (on
// int16 copies, a fixed-length loop for 64 bytes, a generic one otherwise) are the same integer sums.
TEST(FcMatch2d, AppearanceIsTheDescriptorZnccFor64AndShorterDescriptors) {
  Sets s = make(40, Pose2{8.0, -3.0, 0.4}, 0.5, 30, false, 5);
  Fixture f;
  BoundedVector<Match2d> out = f.run(s, 0.4);
  ASSERT_GT(out.size(), 30u);
  for (const Match2d& m : out)
    EXPECT_NEAR(m.appearance, zncc_i8(s.da.data() + m.a * kD, s.db.data() + m.b * kD, kD), 1e-5f);
  // The first 24 bytes of every descriptor (not a multiple of the vector width).
  constexpr std::size_t kShort = 24;
  std::vector<std::int8_t> sa, sb;
  for (std::size_t i = 0; i < s.pa.size(); ++i) sa.insert(sa.end(), s.da.begin() + static_cast<long>(i * kD), s.da.begin() + static_cast<long>(i * kD + kShort));
  for (std::size_t j = 0; j < s.pb.size(); ++j) sb.insert(sb.end(), s.db.begin() + static_cast<long>(j * kD), s.db.begin() + static_cast<long>(j * kD + kShort));
  KeypointSet2d a{Span<const Vec2d>(s.pa.data(), s.pa.size()), Span<const std::int8_t>(sa.data(), sa.size()), kShort};
  KeypointSet2d b{Span<const Vec2d>(s.pb.data(), s.pb.size()), Span<const std::int8_t>(sb.data(), sb.size()), kShort};
  BoundedVector<Match2d> short_out(Span<Match2d>(f.store.data(), f.store.size()));
  ASSERT_TRUE(f.m.match(a, b, 0.4, short_out).is_ok());
  ASSERT_GT(short_out.size(), 20u);
  for (const Match2d& m : short_out)
    EXPECT_NEAR(m.appearance, zncc_i8(sa.data() + m.a * kShort, sb.data() + m.b * kShort, kShort), 1e-5f);
}

TEST(FcMatch2d, DescriptorsLongerThanConfiguredAreRefusedAndCounted) {
  Sets s = make(10, Pose2{}, 0.1, 0, false, 1);
  Fixture f;
  BoundedVector<Match2d> out(Span<Match2d>(f.store.data(), f.store.size()));
  // The same bytes read as 5 descriptors of 128 bytes: longer than max_descriptor_bytes (64).
  KeypointSet2d a{Span<const Vec2d>(s.pa.data(), 5), Span<const std::int8_t>(s.da.data(), s.da.size()), 2 * kD};
  EXPECT_EQ(f.m.match(a, a, 0.0, out), StatusCode::kInvalidArgument);
  EXPECT_EQ(f.m.counters().get(FcMatchCounter::kBadInput), 1u);
  FcMatch2dConfig c;
  c.max_descriptor_bytes = 0;
  ArenaStorage arena(FcMatcher2d::arena_bytes(FcMatch2dConfig{}));
  FcMatcher2d m;
  EXPECT_EQ(m.init(c, arena), StatusCode::kInvalidArgument);
}

// The matcher as first written (every candidate pair scored, int8 dot products), kept here as the
// reference: the matcher's prefiltered scoring and int16 dot products must give the same matches
// with the same scores, bit for bit.
std::vector<Match2d> reference_match(const Sets& s, double dtheta, const FcMatch2dConfig& c) {
  struct Cand {
    std::uint16_t a, b;
    float appearance, score;
  };
  const std::size_t na = s.pa.size(), nb = s.pb.size(), d = kD, k = c.max_candidates_per_point;
  auto stats = [](const std::int8_t* p, float* st) {
    std::int32_t s1 = 0, s2 = 0;
    for (std::size_t q = 0; q < kD; ++q) {
      s1 += p[q];
      s2 += static_cast<std::int32_t>(p[q]) * p[q];
    }
    const double var = static_cast<double>(s2) - static_cast<double>(s1) * s1 / static_cast<double>(kD);
    st[0] = static_cast<float>(s1);
    st[1] = var > 1e-9 ? static_cast<float>(1.0 / std::sqrt(var)) : 0.0f;
  };
  std::vector<float> sta(2 * na), stb(2 * nb);
  for (std::size_t i = 0; i < na; ++i) stats(s.da.data() + i * d, sta.data() + 2 * i);
  for (std::size_t j = 0; j < nb; ++j) stats(s.db.data() + j * d, stb.data() + 2 * j);
  const float inv_d = 1.0f / static_cast<float>(d);
  std::vector<Cand> cand;
  std::vector<std::uint32_t> first(na + 1);
  for (std::size_t i = 0; i < na; ++i) {
    first[i] = static_cast<std::uint32_t>(cand.size());
    std::vector<Cand> list;
    for (std::size_t j = 0; j < nb; ++j) {
      if (sta[2 * i + 1] == 0.0f || stb[2 * j + 1] == 0.0f) continue;
      std::int32_t dot = 0;
      for (std::size_t q = 0; q < d; ++q) dot += static_cast<std::int32_t>(s.da[i * d + q]) * s.db[j * d + q];
      const float z = (static_cast<float>(dot) - sta[2 * i] * stb[2 * j] * inv_d) * sta[2 * i + 1] * stb[2 * j + 1];
      if (!(z >= c.min_appearance)) continue;
      if (list.size() == k && z <= list.back().appearance) continue;
      if (list.size() < k) list.push_back(Cand{});
      std::size_t pos = list.size() - 1;
      while (pos > 0 && list[pos - 1].appearance < z) {
        list[pos] = list[pos - 1];
        --pos;
      }
      list[pos] = Cand{static_cast<std::uint16_t>(i), static_cast<std::uint16_t>(j), z, 0.0f};
    }
    cand.insert(cand.end(), list.begin(), list.end());
  }
  first[na] = static_cast<std::uint32_t>(cand.size());
  const Mat2d r = Pose2{0.0, 0.0, dtheta}.rotation();
  const double inv2sd = 1.0 / (2.0 * c.sigma_dist_m * c.sigma_dist_m);
  for (std::size_t i = 0; i < na; ++i) {
    for (std::uint32_t q = first[i]; q < first[i + 1]; ++q) {
      double acc = 0.0;
      for (std::size_t i2 = 0; i2 < na; ++i2) {
        if (i2 == i || first[i2] == first[i2 + 1]) continue;
        const Vec2d va = r * (s.pa[i2] - s.pa[i]);
        const double la = va.norm();
        if (la < 1e-9) continue;
        const double sphi = c.sigma_dir_rad + c.sigma_dist_m / la;
        const double inv2sp = 1.0 / (2.0 * sphi * sphi);
        const double gate2 = 2.0 * 13.8 * (c.sigma_dist_m * c.sigma_dist_m + la * la * sphi * sphi);
        const Vec2d pb = s.pb[cand[q].b];
        double best = 0.0;
        for (std::uint32_t c2 = first[i2]; c2 < first[i2 + 1]; ++c2) {
          if (cand[c2].b == cand[q].b) continue;
          const Vec2d vb = s.pb[cand[c2].b] - pb;
          if ((vb - va).squaredNorm() > gate2) continue;
          const double lb = vb.norm();
          const double dd = la - lb;
          const double ed = dd * dd * inv2sd;
          if (ed > 4.5 || lb < 1e-9) continue;
          const double cosphi = va.dot(vb) / (la * lb);
          if (cosphi <= 0.0) continue;
          const double e = ed + 2.0 * (1.0 - cosphi) * inv2sp;
          if (e > 6.9) continue;
          const double f = std::exp(-e);
          if (f > best) best = f;
        }
        acc += best;
      }
      cand[q].score = static_cast<float>(acc) * ((1.0f - c.appearance_weight) + c.appearance_weight * std::max(0.0f, cand[q].appearance));
    }
  }
  std::vector<std::uint32_t> order(cand.size());
  for (std::size_t o = 0; o < order.size(); ++o) order[o] = static_cast<std::uint32_t>(o);
  std::sort(order.begin(), order.end(), [&](std::uint32_t x, std::uint32_t y) {
    if (cand[x].score != cand[y].score) return cand[x].score > cand[y].score;
    return x < y;
  });
  std::vector<std::uint8_t> ua(na), ub(nb);
  std::vector<Match2d> out;
  for (std::uint32_t o : order) {
    const Cand& cc = cand[o];
    if (cc.score < c.min_support) break;
    if (ua[cc.a] || ub[cc.b]) continue;
    out.push_back(Match2d{cc.a, cc.b, cc.score, cc.appearance});
    ua[cc.a] = ub[cc.b] = 1;
  }
  return out;
}

// 128 x 160 keypoints spread over a 100 m tile, 3 candidates each (the route's configuration), at
// several rotations, noise levels and one unrelated pair: the same matches and scores as the reference.
TEST(FcMatch2d, SameMatchesAndScoresAsTheAllPairsReference) {
  FcMatch2dConfig c;
  c.max_points = 160;
  c.max_candidates_per_point = 3;
  c.min_appearance = 0.35f;
  c.sigma_dir_rad = 0.02;
  ArenaStorage arena(FcMatcher2d::arena_bytes(c));
  FcMatcher2d m;
  ASSERT_TRUE(m.init(c, arena).is_ok());
  std::vector<Match2d> store(160);
  int compared = 0;
  for (int run = 0; run < 6; ++run) {
    const Pose2 rel{10.0 * run - 20.0, 4.0 - 3.0 * run, 0.5 * run - 1.2};
    Sets s = make(128, rel, 0.3 + 0.4 * run, 32, run == 5, 100 + static_cast<std::uint64_t>(run));
    for (auto& p : s.pa) p *= 1.6;  // 96 x 64 m (the same rotation between the sets, 1.6 x the shift)
    for (auto& p : s.pb) p *= 1.6;
    const std::vector<Match2d> want = reference_match(s, rel.heading_rad, c);
    BoundedVector<Match2d> got(Span<Match2d>(store.data(), store.size()));
    KeypointSet2d a{Span<const Vec2d>(s.pa.data(), s.pa.size()), Span<const std::int8_t>(s.da.data(), s.da.size()), kD};
    KeypointSet2d b{Span<const Vec2d>(s.pb.data(), s.pb.size()), Span<const std::int8_t>(s.db.data(), s.db.size()), kD};
    ASSERT_TRUE(m.match(a, b, rel.heading_rad, got).is_ok());
    ASSERT_EQ(got.size(), want.size()) << "run " << run;
    for (std::size_t q = 0; q < want.size(); ++q) {
      EXPECT_EQ(got[q].a, want[q].a);
      EXPECT_EQ(got[q].b, want[q].b);
      EXPECT_EQ(got[q].score, want[q].score);  // bit for bit
      EXPECT_EQ(got[q].appearance, want[q].appearance);
    }
    compared += static_cast<int>(want.size());
  }
  EXPECT_GT(compared, 300);  // the related runs match most of their 128 keypoints
}

// Odd and ragged counts and flat descriptors: 37 x 63 keypoints (without SIMD the dot products are
// taken two rows of A by four of B at a time: an unpaired last row of A, three rows of B left over),
// flat rows of A first in a pair, second in a pair and last, flat rows of B inside a block of four and
// in the remainder: the same matches, scores and appearances as the reference, bit for bit.
TEST(FcMatch2d, SameAsTheReferenceForRaggedCountsAndFlatDescriptors) {
  FcMatch2dConfig c;
  c.max_points = 64;
  c.max_candidates_per_point = 3;
  c.min_appearance = 0.3f;
  ArenaStorage arena(FcMatcher2d::arena_bytes(c));
  FcMatcher2d m;
  ASSERT_TRUE(m.init(c, arena).is_ok());
  std::vector<Match2d> store(64), store2(64);
  FcMatch2dConfig c2 = c;
  c2.force_scalar_kernels = true;
  ArenaStorage arena2(FcMatcher2d::arena_bytes(c2));
  FcMatcher2d m2;
  ASSERT_TRUE(m2.init(c2, arena2).is_ok());
  for (int run = 0; run < 3; ++run) {
    const Pose2 rel{6.0 - 4.0 * run, 2.0 + run, 0.3 * run - 0.2};
    Sets s = make(37, rel, 0.4, 26, false, 300 + static_cast<std::uint64_t>(run));
    ASSERT_EQ(s.pb.size(), 63u);
    for (std::size_t i : {std::size_t{0}, std::size_t{5}, std::size_t{36}}) std::fill_n(s.da.begin() + static_cast<long>(i * kD), kD, std::int8_t{7});
    for (std::size_t j : {std::size_t{2}, std::size_t{61}}) std::fill_n(s.db.begin() + static_cast<long>(j * kD), kD, std::int8_t{-3});
    const std::vector<Match2d> want = reference_match(s, rel.heading_rad, c);
    BoundedVector<Match2d> got(Span<Match2d>(store.data(), store.size()));
    KeypointSet2d a{Span<const Vec2d>(s.pa.data(), s.pa.size()), Span<const std::int8_t>(s.da.data(), s.da.size()), kD};
    KeypointSet2d b{Span<const Vec2d>(s.pb.data(), s.pb.size()), Span<const std::int8_t>(s.db.data(), s.db.size()), kD};
    ASSERT_TRUE(m.match(a, b, rel.heading_rad, got).is_ok());
    ASSERT_EQ(got.size(), want.size()) << "run " << run;
    BoundedVector<Match2d> scalar(Span<Match2d>(store2.data(), store2.size()));  // the no-SIMD kernels
    ASSERT_TRUE(m2.match(a, b, rel.heading_rad, scalar).is_ok());
    ASSERT_EQ(scalar.size(), want.size()) << "run " << run;
    for (std::size_t q = 0; q < want.size(); ++q) {
      EXPECT_EQ(scalar[q].a, want[q].a);
      EXPECT_EQ(scalar[q].b, want[q].b);
      EXPECT_EQ(scalar[q].score, want[q].score);
      EXPECT_EQ(scalar[q].appearance, want[q].appearance);
    }
    EXPECT_GT(want.size(), 25u);  // the 34 unflattened true pairs, mostly matched
    for (std::size_t q = 0; q < want.size(); ++q) {
      EXPECT_EQ(got[q].a, want[q].a);
      EXPECT_EQ(got[q].b, want[q].b);
      EXPECT_EQ(got[q].score, want[q].score);
      EXPECT_EQ(got[q].appearance, want[q].appearance);
      EXPECT_NE(got[q].a, 0);  // flat descriptors have no candidates
      EXPECT_NE(got[q].a, 5);
      EXPECT_NE(got[q].a, 36);
      EXPECT_NE(got[q].b, 2);
      EXPECT_NE(got[q].b, 61);
    }
  }
}

// The no-SIMD path (LEON3's; forced here on any build) prunes pairs by a bound on their last terms.
// Held to the all-pairs reference bit for bit where the bound is tight and where it is loose: near
// ties (rows of B repeated, so equal z compete for a list's last place), exact and negated copies,
// descriptors with a large offset and little variance (a large |x| / sqrt(n var), the bound's rounding
// margin), extreme bytes (-128, 127), one to eight candidates per point and floors from -1 (every
// pair a candidate) to 0.9 (almost none); on SIMD builds the default path too.
TEST(FcMatch2d, PrunedScalarKernelsSameAsTheReference) {
  std::vector<Match2d> store(96);
  int compared = 0;
  for (int run = 0; run < 8; ++run) {
    FcMatch2dConfig c;
    c.max_points = 96;
    c.max_candidates_per_point = run % 4 == 0 ? 1 : (run % 4 == 1 ? 3 : (run % 4 == 2 ? 8 : 4));
    const float floors[] = {0.35f, -1.0f, 0.0f, 0.9f, 0.5f, 0.2f, -0.3f, 0.35f};
    c.min_appearance = floors[run];
    c.sigma_dir_rad = 0.02;
    const Pose2 rel{5.0 * run - 15.0, 3.0 - 2.0 * run, 0.4 * run - 1.0};
    Sets s = make(61, rel, 0.3 + 0.1 * run, 24, false, 700 + static_cast<std::uint64_t>(run));
    DeterministicRng rng(900 + static_cast<std::uint64_t>(run));
    const std::size_t nb = s.pb.size();
    auto row_b = [&](std::size_t j) { return s.db.begin() + static_cast<long>(j * kD); };
    auto row_a = [&](std::size_t i) { return s.da.begin() + static_cast<long>(i * kD); };
    std::copy_n(row_b(3), kD, row_b(4));  // repeated rows: ties for a list's places
    std::copy_n(row_b(3), kD, row_b(nb - 1));
    std::copy_n(row_b(10), kD, row_b(11));
    for (std::size_t q = 0; q < kD; ++q) {
      row_b(20)[static_cast<long>(q)] = static_cast<std::int8_t>(-std::max(-127, static_cast<int>(row_a(7)[static_cast<long>(q)])));  // negated
      row_b(21)[static_cast<long>(q)] = row_a(8)[static_cast<long>(q)];  // exact copy
      row_a(9)[static_cast<long>(q)] = static_cast<std::int8_t>(100 + static_cast<int>(rng.below(5)));  // offset, little variance
      row_b(22)[static_cast<long>(q)] = static_cast<std::int8_t>(98 + static_cast<int>(rng.below(7)));
      row_a(10)[static_cast<long>(q)] = static_cast<std::int8_t>(q % 2 == 0 ? -128 : 127);  // extremes
      row_b(23)[static_cast<long>(q)] = static_cast<std::int8_t>(q % 3 == 0 ? -128 : 127);
      row_a(11)[static_cast<long>(q)] = static_cast<std::int8_t>(q < 52 ? -20 : 120);  // all variance in the last terms
      row_b(24)[static_cast<long>(q)] = static_cast<std::int8_t>(q < 52 ? 3 : -90 + static_cast<int>(q));
    }
    const std::vector<Match2d> want = reference_match(s, rel.heading_rad, c);
    KeypointSet2d a{Span<const Vec2d>(s.pa.data(), s.pa.size()), Span<const std::int8_t>(s.da.data(), s.da.size()), kD};
    KeypointSet2d b{Span<const Vec2d>(s.pb.data(), s.pb.size()), Span<const std::int8_t>(s.db.data(), s.db.size()), kD};
    for (bool force : {true, false}) {
      c.force_scalar_kernels = force;
      ArenaStorage arena(FcMatcher2d::arena_bytes(c));
      FcMatcher2d m;
      ASSERT_TRUE(m.init(c, arena).is_ok());
      BoundedVector<Match2d> got(Span<Match2d>(store.data(), store.size()));
      ASSERT_TRUE(m.match(a, b, rel.heading_rad, got).is_ok());
      ASSERT_EQ(got.size(), want.size()) << "run " << run << " forced " << force;
      for (std::size_t q = 0; q < want.size(); ++q) {
        EXPECT_EQ(got[q].a, want[q].a) << "run " << run;
        EXPECT_EQ(got[q].b, want[q].b) << "run " << run;
        EXPECT_EQ(got[q].score, want[q].score) << "run " << run;
        EXPECT_EQ(got[q].appearance, want[q].appearance) << "run " << run;
      }
    }
    compared += static_cast<int>(want.size());
  }
  EXPECT_GT(compared, 150);  // the runs with a floor below 0.9 match most of their 61 keypoints
}

}  // namespace
}  // namespace qnav::match
