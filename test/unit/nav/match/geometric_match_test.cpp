#include "nav/match/geometric_match.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "test/support/alloc_guard.hpp"

namespace qnav::match {
namespace {

// A scene of 3D points seen from two camera poses: prev = R cur + T. Each set also holds points the other
// does not see (non-overlap) and noise of sigma_m per axis. truth[i] = index in cur of prev[i] or -1.
struct Scene {
  std::vector<Landmark3> prev, cur;
  std::vector<int> truth;
  MotionPrior prior;
};

Scene make_scene(std::size_t shared, std::size_t extra, double noise_m, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(-0.45, 0.45), uz(0.6, 1.2), us(0.0, 1.0);
  std::normal_distribution<double> nn(0.0, noise_m);
  Scene s;
  s.prior.R_prev_cur = rotation_from_rpy(0.02, -0.04, 0.08);
  s.prior.t_prev_cur_m = Vec3d(0.03, -0.01, 0.2);
  s.prior.translation_sigma_m = 0.02;
  const Pose3 truth{s.prior.R_prev_cur, s.prior.t_prev_cur_m};
  auto lm = [&](const Vec3d& p) {
    Landmark3 l;
    l.position_m = p + Vec3d(nn(rng), nn(rng), nn(rng));
    l.sigma_m = noise_m;
    l.score = us(rng);
    return l;
  };
  std::vector<std::pair<Landmark3, int>> prev;
  std::vector<Landmark3> cur;
  for (std::size_t i = 0; i < shared; ++i) {
    const Vec3d c(ux(rng), ux(rng), uz(rng));
    cur.push_back(lm(c));
    prev.push_back({lm(truth.apply(c)), static_cast<int>(i)});
  }
  for (std::size_t i = 0; i < extra; ++i) {
    cur.push_back(lm(Vec3d(ux(rng), ux(rng), uz(rng))));
    prev.push_back({lm(Vec3d(ux(rng), ux(rng), uz(rng))), -1});
  }
  // Decreasing score order, as the detector delivers them; cur indices are remapped.
  std::vector<int> order(cur.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return cur[a].score > cur[b].score; });
  std::vector<int> new_index(cur.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    s.cur.push_back(cur[order[k]]);
    new_index[order[k]] = static_cast<int>(k);
  }
  std::sort(prev.begin(), prev.end(), [](const auto& a, const auto& b) { return a.first.score > b.first.score; });
  for (const auto& p : prev) {
    s.prev.push_back(p.first);
    s.truth.push_back(p.second < 0 ? -1 : new_index[p.second]);
  }
  return s;
}

struct Quality {
  std::size_t correct = 0, wrong = 0;
};
Quality grade(const Scene& s, Span<const Match> m) {
  Quality q;
  for (const Match& x : m) (s.truth[x.prev] == x.cur ? q.correct : q.wrong)++;
  return q;
}

template <typename T>
Span<const T> sp(const std::vector<T>& v) {
  return Span<const T>(v.data(), v.size());
}

GeometricMatcher make(MatchScoreKind kind, bool fast) {
  GeometricMatchConfig c;
  c.score = kind;
  c.fast = fast;
  c.attitude_sigma_rad = deg_to_rad(0.1);
  Result<GeometricMatcher> m = GeometricMatcher::create(c);
  EXPECT_TRUE(m.is_ok());
  return std::move(m.value());
}

TEST(GeometricMatch, FcMatchingFindsTheTrueCorrespondences) {
  const Scene s = make_scene(120, 60, 0.002, 1);
  GeometricMatcher m = make(MatchScoreKind::kContinuous, false);
  Result<Span<const Match>> r = m.match(sp(s.prev), sp(s.cur), s.prior);
  ASSERT_TRUE(r.is_ok());
  const Quality q = grade(s, r.value());
  EXPECT_GE(q.correct, 100u) << "of 120 shared";
  EXPECT_LE(q.wrong, 1u);
}

TEST(GeometricMatch, FbMatchingFindsTheTrueCorrespondences) {
  const Scene s = make_scene(120, 60, 0.002, 2);
  GeometricMatcher m = make(MatchScoreKind::kBinary, false);
  Result<Span<const Match>> r = m.match(sp(s.prev), sp(s.cur), s.prior);
  ASSERT_TRUE(r.is_ok());
  const Quality q = grade(s, r.value());
  EXPECT_GE(q.correct, 95u);
  EXPECT_LE(q.wrong, 2u);
}

TEST(GeometricMatch, FastMatchingStopsEarlyWithFewerEvaluations) {
  const Scene s = make_scene(200, 100, 0.002, 3);
  GeometricMatcher full = make(MatchScoreKind::kContinuous, false);
  GeometricMatcher fast = make(MatchScoreKind::kContinuous, true);
  Result<Span<const Match>> rf = full.match(sp(s.prev), sp(s.cur), s.prior);
  Result<Span<const Match>> rq = fast.match(sp(s.prev), sp(s.cur), s.prior);
  ASSERT_TRUE(rf.is_ok() && rq.is_ok());
  const Quality qf = grade(s, rf.value()), qq = grade(s, rq.value());
  EXPECT_GE(qq.correct, fast.config().min_matches);
  EXPECT_LE(qq.wrong, 1u);
  EXPECT_LT(fast.stats().prev_used, s.prev.size());
  EXPECT_LT(fast.stats().pair_evaluations * 5, full.stats().pair_evaluations);
  EXPECT_GT(qf.correct, qq.correct);
}

TEST(GeometricMatch, ToleratesOdometryErrorWithinItsSigma) {
  Scene s = make_scene(100, 40, 0.002, 4);
  s.prior.t_prev_cur_m *= 1.2;  // 20% wheel slip, 4 cm
  s.prior.translation_sigma_m = 0.03;
  GeometricMatcher m = make(MatchScoreKind::kContinuous, false);
  Result<Span<const Match>> r = m.match(sp(s.prev), sp(s.cur), s.prior);
  ASSERT_TRUE(r.is_ok());
  const Quality q = grade(s, r.value());
  EXPECT_GE(q.correct, 80u);
  EXPECT_LE(q.wrong, 1u);
}

TEST(GeometricMatch, ConsistencyPassRejectsAWrongAttitude) {
  // With R off by 5 degrees the vectors between landmarks no longer agree: few consistent matches.
  Scene s = make_scene(100, 40, 0.002, 5);
  GeometricMatcher m = make(MatchScoreKind::kContinuous, false);
  MotionPrior wrong = s.prior;
  wrong.R_prev_cur = wrong.R_prev_cur * rotation_from_rpy(0.0, deg_to_rad(5.0), 0.0);
  wrong.translation_sigma_m = 0.05;
  Result<Span<const Match>> r = m.match(sp(s.prev), sp(s.cur), wrong);
  ASSERT_TRUE(r.is_ok());
  EXPECT_LT(r.value().size(), 20u);
}

TEST(GeometricMatch, UnrelatedSetsGiveFewMatches) {
  const Scene a = make_scene(0, 150, 0.002, 6);
  GeometricMatcher m = make(MatchScoreKind::kContinuous, false);
  Result<Span<const Match>> r = m.match(sp(a.prev), sp(a.cur), a.prior);
  ASSERT_TRUE(r.is_ok());
  EXPECT_LT(r.value().size(), 10u);
}

TEST(GeometricMatch, BadInputsAreCountedNotCrashes) {
  Scene s = make_scene(60, 0, 0.002, 7);
  GeometricMatcher m = make(MatchScoreKind::kContinuous, false);
  MotionPrior bad = s.prior;
  bad.R_prev_cur(0, 0) = std::nan("");
  EXPECT_EQ(m.match(sp(s.prev), sp(s.cur), bad).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(m.counters().get(MatchCounter::kBadPrior), 1u);
  bad = s.prior;
  bad.R_prev_cur *= 1.1;
  EXPECT_FALSE(m.match(sp(s.prev), sp(s.cur), bad).is_ok());
  s.prev[0].position_m.x() = std::nan("");
  s.cur[5].sigma_m = -1.0;
  Result<Span<const Match>> r = m.match(sp(s.prev), sp(s.cur), s.prior);
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(m.counters().get(MatchCounter::kBadLandmark), 2u);
  for (const Match& x : r.value()) EXPECT_NE(x.prev, 0);
  Result<Span<const Match>> e = m.match({}, sp(s.cur), s.prior);
  ASSERT_TRUE(e.is_ok());
  EXPECT_EQ(e.value().size(), 0u);
  EXPECT_GE(m.counters().get(MatchCounter::kTooFewMatches), 1u);
  EXPECT_FALSE(GeometricMatcher().match(sp(s.prev), sp(s.cur), s.prior).is_ok());
  GeometricMatchConfig c;
  c.f_max = 0.5;
  EXPECT_FALSE(GeometricMatcher::create(c).is_ok());
}

TEST(GeometricMatch, CapacitiesAreRespected) {
  const Scene s = make_scene(100, 0, 0.002, 8);
  GeometricMatchConfig c;
  c.max_landmarks = 50;
  c.max_matches = 30;
  Result<GeometricMatcher> m = GeometricMatcher::create(c);
  ASSERT_TRUE(m.is_ok());
  Result<Span<const Match>> r = m->match(sp(s.prev), sp(s.cur), s.prior);
  ASSERT_TRUE(r.is_ok());
  EXPECT_LE(r.value().size(), 30u);
  EXPECT_EQ(m->counters().get(MatchCounter::kLandmarksTruncated), 1u);
  for (const Match& x : r.value()) EXPECT_TRUE(x.prev < 50 && x.cur < 50);
}

// Eq. 4 by its definition, pair by pair in double with compat()'s f (the direction test by the same
// series for 1 - cos), over candidates gathered by brute force: the reference for the reordered
// score loop (score_candidates computes the prev side once per pair of groups).
double reference_f(const Vec3d& p, double sp, const Vec3d& c, double sc, const Vec3d& p2, double sp2,
                   const Vec3d& c2, double sc2, const GeometricMatchConfig& k) {
  const Vec3d va = p - p2, vb = c - c2;
  const double la = va.norm(), lb = vb.norm(), dl = std::fabs(la - lb);
  const double eps_n = k.n_sigma * std::sqrt(sp * sp + sp2 * sp2 + sc * sc + sc2 * sc2) + k.eps_n_floor_m;
  if (la >= k.min_vector_m && lb > 0.0) {
    const double tol = std::min(1.0, k.n_sigma * k.attitude_sigma_rad + eps_n / la), t2 = tol * tol;
    const double eps_p = t2 * (0.5 - t2 * (1.0 / 24.0 - t2 * (1.0 / 720.0)));
    if (va.dot(vb) < (1.0 - eps_p) * la * lb) return 0.0;
  }
  if (k.score == MatchScoreKind::kBinary) return dl < eps_n ? 1.0 : 0.0;
  return std::max(0.0, (1.0 - k.f_max) / eps_n * dl + k.f_max);
}

TEST(GeometricMatch, ScoresAreEquationFourOverTheGatedCandidates) {
  // Dense enough that most prev landmarks have several candidates (the cap of 5 is hit).
  Scene s = make_scene(150, 80, 0.006, 11);
  s.prior.translation_sigma_m = 0.05;
  for (const MatchScoreKind kind : {MatchScoreKind::kContinuous, MatchScoreKind::kBinary}) {
    GeometricMatcher m = make(kind, false);
    const GeometricMatchConfig& k = m.config();
    Result<Span<const Match>> r = m.match(sp(s.prev), sp(s.cur), s.prior);
    ASSERT_TRUE(r.is_ok());
    ASSERT_GT(r.value().size(), 50u);
    EXPECT_GT(m.counters().get(MatchCounter::kCandidateCapHit), 50u);
    std::vector<Vec3d> q(s.cur.size());
    for (std::size_t j = 0; j < q.size(); ++j) q[j] = s.prior.R_prev_cur * s.cur[j].position_m;
    std::vector<std::vector<int>> cands(s.prev.size());
    const double st2 = s.prior.translation_sigma_m * s.prior.translation_sigma_m;
    for (std::size_t i = 0; i < s.prev.size(); ++i) {
      std::vector<std::pair<double, int>> near;
      for (std::size_t j = 0; j < q.size(); ++j) {
        const double d = (s.prev[i].position_m - (q[j] + s.prior.t_prev_cur_m)).norm();
        const double gate = std::min(k.max_gate_m, k.n_sigma * std::sqrt(st2 + s.prev[i].sigma_m * s.prev[i].sigma_m +
                                                                         s.cur[j].sigma_m * s.cur[j].sigma_m));
        if (d < gate) near.push_back({d, static_cast<int>(j)});
      }
      std::stable_sort(near.begin(), near.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      for (std::size_t n = 0; n < near.size() && n < k.max_candidates_per_landmark; ++n) cands[i].push_back(near[n].second);
    }
    for (const Match& x : r.value()) {
      double ref = 0.0;
      for (std::size_t i2 = 0; i2 < s.prev.size(); ++i2) {
        if (i2 == static_cast<std::size_t>(x.prev)) continue;
        double best = 0.0;
        for (const int j2 : cands[i2]) {
          if (j2 == x.cur) continue;
          best = std::max(best, reference_f(s.prev[x.prev].position_m, s.prev[x.prev].sigma_m, q[x.cur],
                                            s.cur[x.cur].sigma_m, s.prev[i2].position_m, s.prev[i2].sigma_m, q[j2],
                                            s.cur[j2].sigma_m, k));
        }
        ref += best;
      }
      EXPECT_NEAR(x.score, ref, 1e-6 * ref) << "match " << x.prev << " -> " << x.cur;
    }
  }
}

TEST(GeometricMatch, MatchDoesNotAllocate) {
  const Scene s = make_scene(150, 50, 0.002, 9);
  GeometricMatcher m = make(MatchScoreKind::kContinuous, true);
  std::size_t n = 0;
  QNAV_EXPECT_NO_ALLOC(n = m.match(sp(s.prev), sp(s.cur), s.prior).value().size());
  EXPECT_GT(n, 20u);
}

}  // namespace
}  // namespace qnav::match
