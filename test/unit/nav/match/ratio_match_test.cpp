#include "nav/match/ratio_match.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "nav/match/ransac.hpp"
#include "test/support/alloc_guard.hpp"

namespace qnav::match {
namespace {

using vision::OrientedDescriptor;

double gaussian(DeterministicRng& rng) {
  double u1 = rng.uniform();
  const double u2 = rng.uniform();
  if (u1 < 1e-300) u1 = 1e-300;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
}

void normalise(OrientedDescriptor& d) {
  double n = 0.0;
  for (float v : d.v) n += static_cast<double>(v) * static_cast<double>(v);
  const float s = static_cast<float>(1.0 / std::sqrt(n));
  for (float& v : d.v) v *= s;
  d.valid = true;
}

OrientedDescriptor random_descriptor(DeterministicRng& rng) {
  OrientedDescriptor d;
  for (float& v : d.v) v = static_cast<float>(rng.uniform());  // non-negative like gradient histograms
  normalise(d);
  return d;
}

OrientedDescriptor perturbed(const OrientedDescriptor& src, double sigma, DeterministicRng& rng) {
  OrientedDescriptor d = src;
  for (float& v : d.v) {
    const double g = gaussian(rng);
    v = static_cast<float>(static_cast<double>(v) + sigma * g);
  }
  normalise(d);
  return d;
}

struct Fixture {
  std::vector<std::byte> block;
  Arena arena;
  RatioMatcher matcher;
  std::vector<DescriptorMatch> out_storage;
  BoundedVector<DescriptorMatch> out;
  explicit Fixture(const RatioMatchConfig& c, std::size_t out_cap = 512)
      : block(RatioMatcher::arena_bytes(c)), arena(Span<std::byte>(block.data(), block.size())), out_storage(out_cap),
        out(Span<DescriptorMatch>(out_storage.data(), out_cap)) {
    EXPECT_TRUE(matcher.init(c, arena).is_ok());
  }
};

Span<const OrientedDescriptor> span_of(const std::vector<OrientedDescriptor>& v) {
  return Span<const OrientedDescriptor>(v.data(), v.size());
}

// 120 train descriptors; 80 queries are noisy copies of train[(7 i + 3) % 120], 20 are new.
struct Sets {
  std::vector<OrientedDescriptor> train, query;
  std::vector<int> truth;  // per query: train index or -1
};

Sets make_sets(double noise, std::uint64_t seed) {
  DeterministicRng rng(seed);
  Sets s;
  for (int j = 0; j < 120; ++j) s.train.push_back(random_descriptor(rng));
  for (int i = 0; i < 100; ++i) {
    if (i < 80) {
      const int t = (7 * i + 3) % 120;
      s.query.push_back(perturbed(s.train[t], noise, rng));
      s.truth.push_back(t);
    } else {
      s.query.push_back(random_descriptor(rng));
      s.truth.push_back(-1);
    }
  }
  return s;
}

TEST(RatioMatch, KeepsTrueMatchesAndRejectsQueriesWithoutOne) {
  const Sets s = make_sets(0.01, 1);
  RatioMatchConfig c;
  Fixture f(c);
  ASSERT_TRUE(f.matcher.match(span_of(s.query), span_of(s.train), f.out).is_ok());
  int correct = 0, wrong = 0;
  for (const DescriptorMatch& m : f.out) (s.truth[m.query] == m.train ? correct : wrong)++;
  const RatioMatchStats& st = f.matcher.last_stats();
  std::printf("[measured] ratio match 100 x 120 (80 true, noise 0.01/dim): %d correct, %d wrong, %u ratio-rejected, "
              "%llu of %d distances started\n",
              correct, wrong, st.ratio_rejected, static_cast<unsigned long long>(st.distances), 100 * 120);
  EXPECT_EQ(correct, 80);
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(st.ratio_rejected, 20u);
  EXPECT_EQ(st.queries, 100u);
  for (std::size_t k = 1; k < f.out.size(); ++k) EXPECT_LT(f.out[k - 1].query, f.out[k].query);
}

TEST(RatioMatch, EqualsTheBruteForceRatioTest) {
  // The early exit must not change any decision: compare with a plain full-distance evaluation.
  const Sets s = make_sets(0.03, 2);
  RatioMatchConfig c;
  c.max_ratio = 0.9f;
  Fixture f(c);
  ASSERT_TRUE(f.matcher.match(span_of(s.query), span_of(s.train), f.out).is_ok());
  std::vector<int> expect(s.query.size(), -1);
  for (std::size_t i = 0; i < s.query.size(); ++i) {
    float d1 = 1e30f, d2 = 1e30f;
    int t1 = -1;
    for (std::size_t j = 0; j < s.train.size(); ++j) {
      const float d = vision::descriptor_distance_sq(s.query[i], s.train[j]);
      if (d < d1) {
        d2 = d1;
        d1 = d;
        t1 = static_cast<int>(j);
      } else if (d < d2) {
        d2 = d;
      }
    }
    if (d1 < 0.81f * d2) expect[i] = t1;
  }
  std::vector<int> got(s.query.size(), -1);
  for (const DescriptorMatch& m : f.out) got[m.query] = m.train;
  EXPECT_EQ(got, expect);
  EXPECT_LT(f.matcher.last_stats().distances, 100u * 120u + 1u);
}

TEST(RatioMatch, AnAmbiguousQueryFailsTheRatioTest) {
  DeterministicRng rng(3);
  std::vector<OrientedDescriptor> train;
  for (int j = 0; j < 20; ++j) train.push_back(random_descriptor(rng));
  train[5] = perturbed(train[4], 0.002, rng);  // a repeated texture: two near-identical train descriptors
  std::vector<OrientedDescriptor> query = {perturbed(train[4], 0.01, rng), perturbed(train[9], 0.01, rng)};
  Fixture f(RatioMatchConfig{});
  ASSERT_TRUE(f.matcher.match(span_of(query), span_of(train), f.out).is_ok());
  ASSERT_EQ(f.out.size(), 1u);
  EXPECT_EQ(f.out[0].query, 1u);
  EXPECT_EQ(f.out[0].train, 9u);
  EXPECT_EQ(f.matcher.last_stats().ratio_rejected, 1u);
}

TEST(RatioMatch, MutualCheckDropsTheSecondQueryOfATrainDescriptor) {
  DeterministicRng rng(4);
  std::vector<OrientedDescriptor> train;
  for (int j = 0; j < 30; ++j) train.push_back(random_descriptor(rng));
  // Both queries' nearest is train[7]; q0 is the closer one.
  std::vector<OrientedDescriptor> query = {perturbed(train[7], 0.005, rng), perturbed(train[7], 0.02, rng)};
  RatioMatchConfig c;
  Fixture plain(c);
  ASSERT_TRUE(plain.matcher.match(span_of(query), span_of(train), plain.out).is_ok());
  EXPECT_EQ(plain.out.size(), 2u);
  c.mutual = true;
  Fixture mutual(c);
  ASSERT_TRUE(mutual.matcher.match(span_of(query), span_of(train), mutual.out).is_ok());
  ASSERT_EQ(mutual.out.size(), 1u);
  EXPECT_EQ(mutual.out[0].query, 0u);
  EXPECT_EQ(mutual.out[0].train, 7u);
  EXPECT_EQ(mutual.matcher.last_stats().mutual_rejected, 1u);
}

TEST(RatioMatch, APredictionRestrictsTheCandidatesAndResolvesRepeatedTexture) {
  // Train keypoints on a 12 x 10 grid of a 320 x 240 image; each has a twin descriptor far away
  // (repeated texture), so a search over the whole image is ambiguous; the prediction is the true
  // position moved by up to 4 px.
  DeterministicRng rng(5);
  std::vector<OrientedDescriptor> train;
  for (int gy = 0; gy < 10; ++gy)
    for (int gx = 0; gx < 12; ++gx) {
      OrientedDescriptor d = random_descriptor(rng);
      d.x = 12.0f + 26.0f * gx;
      d.y = 12.0f + 24.0f * gy;
      train.push_back(d);
    }
  const std::size_t half = train.size() / 2;
  for (std::size_t j = 0; j < half; ++j) {  // the far half repeats the near half's texture
    const float x = train[j + half].x, y = train[j + half].y;
    train[j + half] = perturbed(train[j], 0.004, rng);
    train[j + half].x = x;
    train[j + half].y = y;
  }
  std::vector<OrientedDescriptor> query;
  std::vector<Vec2d> predicted;
  for (std::size_t j = 0; j < half; ++j) {
    query.push_back(perturbed(train[j], 0.01, rng));
    const double ex = 8.0 * (rng.uniform() - 0.5), ey = 8.0 * (rng.uniform() - 0.5);
    predicted.emplace_back(static_cast<double>(train[j].x) + ex, static_cast<double>(train[j].y) + ey);
  }
  RatioMatchConfig c;
  c.search_radius_px = 40.0f;  // the true keypoint and its grid neighbours: a second nearest exists
  Fixture f(c);
  ASSERT_TRUE(f.matcher.match(span_of(query), span_of(train), f.out).is_ok());
  const std::uint32_t brute = f.matcher.last_stats().matched;
  ASSERT_TRUE(
      f.matcher.match_predicted(span_of(query), Span<const Vec2d>(predicted.data(), predicted.size()), span_of(train), f.out).is_ok());
  int correct = 0;
  for (const DescriptorMatch& m : f.out) correct += m.train == m.query;
  const RatioMatchStats& st = f.matcher.last_stats();
  std::printf("[measured] predicted matching (repeated texture, %zu queries): whole image %u matched, radius 40 px %d correct of %u, "
              "%llu distances (whole image %zu)\n",
              query.size(), brute, correct, st.matched, static_cast<unsigned long long>(st.distances), query.size() * train.size());
  EXPECT_EQ(brute, 0u);
  EXPECT_EQ(correct, static_cast<int>(half));
  EXPECT_EQ(st.matched, static_cast<std::uint32_t>(half));
  EXPECT_LE(st.distances, query.size() * 13);  // at most the 13 grid keypoints within 40 px
}

TEST(RatioMatch, CandidatesPerQueryAreCapped) {
  DeterministicRng rng(6);
  std::vector<OrientedDescriptor> train;
  for (int j = 0; j < 50; ++j) {
    OrientedDescriptor d = random_descriptor(rng);
    d.x = 100.0f + static_cast<float>(j % 5);
    d.y = 100.0f + static_cast<float>(j / 5);
    train.push_back(d);
  }
  std::vector<OrientedDescriptor> query = {perturbed(train[0], 0.01, rng), perturbed(train[1], 0.01, rng)};
  const std::vector<Vec2d> predicted = {Vec2d(102.0, 104.0), Vec2d(102.0, 104.0)};
  RatioMatchConfig c;
  c.max_candidates = 8;
  Fixture f(c);
  ASSERT_TRUE(f.matcher.match_predicted(span_of(query), Span<const Vec2d>(predicted.data(), 2), span_of(train), f.out).is_ok());
  EXPECT_EQ(f.matcher.last_stats().distances, 16u);
  EXPECT_EQ(f.matcher.counters().get(RatioMatchCounter::kCandidatesCapped), 2u);
}

TEST(RatioMatch, BoundsInvalidInputAndConfigurationAreReported) {
  const Sets s = make_sets(0.01, 7);
  RatioMatchConfig c;
  c.max_query = 50;
  c.max_train = 100;
  Fixture f(c, 10);
  std::vector<OrientedDescriptor> query = s.query;
  query[1].valid = false;
  Status st = f.matcher.match(span_of(query), span_of(s.train), f.out);
  EXPECT_EQ(st.code(), StatusCode::kCapacityExceeded);  // more than 10 matches
  EXPECT_EQ(f.out.size(), 10u);
  EXPECT_EQ(f.matcher.counters().get(RatioMatchCounter::kQueryIgnored), 50u);
  EXPECT_EQ(f.matcher.counters().get(RatioMatchCounter::kTrainIgnored), 20u);
  EXPECT_EQ(f.matcher.counters().get(RatioMatchCounter::kInvalidDescriptor), 1u);
  EXPECT_EQ(f.matcher.counters().get(RatioMatchCounter::kOutputFull), 1u);
  std::vector<Vec2d> predicted(3, Vec2d(1.0, 1.0));
  EXPECT_EQ(f.matcher.match_predicted(span_of(query), Span<const Vec2d>(predicted.data(), 3), span_of(s.train), f.out).code(),
            StatusCode::kInvalidArgument);

  RatioMatcher not_ready;
  EXPECT_EQ(not_ready.match(span_of(query), span_of(s.train), f.out).code(), StatusCode::kNotReady);
  RatioMatchConfig bad;
  bad.max_ratio = 1.5f;
  std::vector<std::byte> block(RatioMatcher::arena_bytes(RatioMatchConfig{}));
  Arena arena(Span<std::byte>(block.data(), block.size()));
  EXPECT_EQ(not_ready.init(bad, arena).code(), StatusCode::kInvalidArgument);
  std::vector<std::byte> tiny(64);
  Arena small(Span<std::byte>(tiny.data(), tiny.size()));
  EXPECT_EQ(not_ready.init(RatioMatchConfig{}, small).code(), StatusCode::kCapacityExceeded);
}

TEST(RatioMatch, MatchingAllocatesNothing) {
  Sets s = make_sets(0.01, 8);
  std::vector<Vec2d> predicted;
  for (std::size_t i = 0; i < s.query.size(); ++i) {
    s.query[i].x = static_cast<float>(i % 20) * 15.0f;
    s.query[i].y = static_cast<float>(i / 20) * 15.0f;
    predicted.emplace_back(s.query[i].x, s.query[i].y);
  }
  for (std::size_t j = 0; j < s.train.size(); ++j) {
    s.train[j].x = static_cast<float>(j % 20) * 15.0f;
    s.train[j].y = static_cast<float>(j / 20) * 15.0f;
  }
  RatioMatchConfig c;
  c.mutual = true;
  Fixture f(c);
  Status st;
  QNAV_EXPECT_NO_ALLOC(st = f.matcher.match(span_of(s.query), span_of(s.train), f.out));
  EXPECT_TRUE(st.is_ok());
  QNAV_EXPECT_NO_ALLOC(st = f.matcher.match_predicted(span_of(s.query), Span<const Vec2d>(predicted.data(), predicted.size()),
                                                      span_of(s.train), f.out));
  EXPECT_TRUE(st.is_ok());
}

}  // namespace
}  // namespace qnav::match
