#include "nav/match/geometric_match.hpp"

#include <cmath>
#include <new>

namespace qnav::match {

const char* const GeometricMatcher::kCounterNames[static_cast<std::size_t>(MatchCounter::kCount)] = {
    "match_bad_prior",          "match_bad_landmark",         "match_landmarks_truncated",
    "match_candidate_cap_hit",  "match_potential_capped",     "match_too_few_matches"};

namespace {

template <typename T>
bool alloc_array(std::unique_ptr<T[]>& p, std::size_t n, std::size_t& bytes) noexcept {
  p.reset(new (std::nothrow) T[n]);
  bytes += n * sizeof(T);
  return p != nullptr;
}

bool finite_landmark(const Landmark3& l) noexcept {
  return l.position_m.allFinite() && std::isfinite(l.sigma_m) && l.sigma_m >= 0.0;
}

double ncc(const Landmark3& a, const Landmark3& b) noexcept {
  double s = 0.0;
  for (std::size_t i = 0; i < kAppearanceDims; ++i) s += static_cast<double>(a.appearance[i]) * static_cast<double>(b.appearance[i]);
  return s;
}

}  // namespace

Result<GeometricMatcher> GeometricMatcher::create(const GeometricMatchConfig& c) noexcept {
  if (c.max_landmarks < 3 || c.max_landmarks > 65535 || c.max_candidates_per_landmark == 0 ||
      c.max_candidates_per_landmark > 64 || c.max_matches < 3 || c.max_matches > 4096)
    return Status(StatusCode::kInvalidArgument, "geometric matcher capacities out of range");
  if (!(c.n_sigma > 0.0) || !(c.eps_n_floor_m >= 0.0) || !(c.attitude_sigma_rad >= 0.0) || !(c.f_max > 1.0) ||
      !(c.max_gate_m > 0.0) || !(c.min_vector_m >= 0.0) || !(c.appearance_weight >= 0.0 && c.appearance_weight <= 1.0) ||
      c.batch_size == 0 || !std::isfinite(c.min_support))
    return Status(StatusCode::kInvalidArgument, "geometric matcher thresholds out of range");
  GeometricMatcher m;
  m.config_ = c;
  const std::size_t n = c.max_landmarks;
  const std::size_t nc = n * c.max_candidates_per_landmark;
  m.words_per_row_ = (c.max_matches + 63) / 64;
  std::size_t& b = m.bytes_;
  const bool ok = alloc_array(m.prev_pos_, n, b) && alloc_array(m.cur_rot_, n, b) && alloc_array(m.prev_sigma_, n, b) &&
                  alloc_array(m.cur_sigma_, n, b) && alloc_array(m.prev_ok_, n, b) && alloc_array(m.cur_ok_, n, b) &&
                  alloc_array(m.cands_, nc, b) && alloc_array(m.groups_, n, b) && alloc_array(m.best_of_cur_, n, b) &&
                  alloc_array(m.potential_, n, b) &&
                  alloc_array(m.compat_bits_, m.words_per_row_ * c.max_matches, b) &&
                  alloc_array(m.compat_count_, c.max_matches, b) && alloc_array(m.compat_sum_, c.max_matches, b) &&
                  alloc_array(m.alive_, c.max_matches, b) && alloc_array(m.out_, c.max_matches, b);
  if (!ok) return Status(StatusCode::kCapacityExceeded, "out of memory for geometric matcher");
  return m;
}

double GeometricMatcher::compat(std::size_t p, std::size_t c, std::size_t p2, std::size_t c2,
                                bool* binary_ok) const noexcept {
  const Vec3d va = prev_pos_[p] - prev_pos_[p2];
  const Vec3d vb = cur_rot_[c] - cur_rot_[c2];
  const double la = va.norm();
  const double lb = vb.norm();
  const double dl = std::fabs(la - lb);
  const double s2 = prev_sigma_[p] * prev_sigma_[p] + prev_sigma_[p2] * prev_sigma_[p2] + cur_sigma_[c] * cur_sigma_[c] +
                    cur_sigma_[c2] * cur_sigma_[c2];
  const double eps_n = config_.n_sigma * std::sqrt(s2) + config_.eps_n_floor_m;
  *binary_ok = false;
  if (la >= config_.min_vector_m && lb > 0.0) {
    double tol = config_.n_sigma * config_.attitude_sigma_rad + eps_n / la;
    if (tol > 1.0) tol = 1.0;
    // eps_p = 1 - cos(tol) by its Taylor series to t^6 (error < 2e-5 for tol <= 1 rad; no libm call in
    // the O(N^2) loop). Test va.vb >= (1 - eps_p) la lb without dividing.
    const double t2 = tol * tol;
    const double eps_p = t2 * (0.5 - t2 * (1.0 / 24.0 - t2 * (1.0 / 720.0)));
    if (va.dot(vb) < (1.0 - eps_p) * la * lb) return 0.0;
  }
  if (dl < eps_n) *binary_ok = true;
  if (config_.score == MatchScoreKind::kBinary) return *binary_ok ? 1.0 : 0.0;
  const double f = (1.0 - config_.f_max) / eps_n * dl + config_.f_max;
  return f > 0.0 ? f : 0.0;
}

void GeometricMatcher::run_round(std::size_t np, std::size_t nc, const MotionPrior& prior) noexcept {
  gather_candidates(np, nc, prior);
  stats_.candidates = n_cands_;
  score_candidates();
  const std::size_t m = select_potential(nc);
  stats_.potential_matches = m;
  stats_.removed_by_consistency = consistency_pass(m);
  n_out_ = 0;
  for (std::size_t k = 0; k < m; ++k) {
    if (!alive_[k]) continue;
    Match o = potential_[k];
    o.consistency = static_cast<float>(compat_sum_[k]);
    out_[n_out_++] = o;
  }
}

// 1. gated candidates, k nearest per prev landmark (insertion into a sorted run of <= kmax).
void GeometricMatcher::gather_candidates(std::size_t np, std::size_t nc, const MotionPrior& prior) noexcept {
  const std::size_t kmax = config_.max_candidates_per_landmark;
  const double st2 = prior.translation_sigma_m * prior.translation_sigma_m;
  n_cands_ = 0;
  n_groups_ = 0;
  for (std::size_t i = 0; i < np; ++i) {
    if (!prev_ok_[i]) continue;
    const std::uint32_t first = static_cast<std::uint32_t>(n_cands_);
    std::uint32_t count = 0;
    bool capped = false;
    for (std::size_t j = 0; j < nc; ++j) {
      if (!cur_ok_[j]) continue;
      const double d = (prev_pos_[i] - (cur_rot_[j] + prior.t_prev_cur_m)).norm();
      double gate = config_.n_sigma * std::sqrt(st2 + prev_sigma_[i] * prev_sigma_[i] + cur_sigma_[j] * cur_sigma_[j]);
      if (gate > config_.max_gate_m) gate = config_.max_gate_m;
      if (!(d < gate)) continue;
      if (count == kmax) {
        capped = true;
        if (d >= cands_[first + count - 1].dist_m) continue;
        --count;  // drop the farthest
      }
      std::uint32_t k = count;
      while (k > 0 && cands_[first + k - 1].dist_m > d) {
        cands_[first + k] = cands_[first + k - 1];
        --k;
      }
      cands_[first + k] = Candidate{static_cast<std::uint16_t>(i), static_cast<std::uint16_t>(j), d, 0.0};
      ++count;
    }
    if (capped) counters_.increment(MatchCounter::kCandidateCapHit);
    if (count == 0) continue;
    groups_[n_groups_++] = Group{first, count, 0.0};
    n_cands_ += count;
  }
}

// 2. matching scores (eq. 4 with f = fb or fc), max over each other prev landmark's candidates.
// The same arithmetic as compat(), reordered for the O(N^2) loop without changing a result. A group
// holds the candidates of one prev landmark, and a pair of groups (g, h), g < h, is visited once for
// both directions: the prev side (va = M_g - M_h, its length, the sum of the two prev sigma^2) is the
// same, negated or swapped exactly, for g's candidates against h's and h's against g's, and so are
// vb, lb and the dot product; only eps_n is summed in each direction's own order, so each pair's two
// scores are the ones compat() gives. A candidate's sum still runs over the other groups in ascending
// order (those before its own group are added while they are the outer group), so the sums are the
// same. The direction test (a division, a dot product) is only made for a pair whose score would
// raise the maximum, since a pair that fails it scores 0 and the maximum starts at 0. Before any
// square root a pair is dropped when its length difference |la - lb| certainly exceeds the distance
// at which its score is 0 in both directions (fc: f <= 0 beyond eps_n f_max / (f_max - 1); fb:
// eps_n), bounded with the two groups' largest cur sigma^2 and a relative margin of 1e-9 (far above
// the rounding of these sums), tested on the squared length lb^2; the pairs it drops score 0 in the
// exact test too.
void GeometricMatcher::score_candidates() noexcept {
  const bool continuous = config_.score == MatchScoreKind::kContinuous;
  const double n_sigma = config_.n_sigma;
  const double eps_floor = config_.eps_n_floor_m;
  const double att_tol = config_.n_sigma * config_.attitude_sigma_rad;
  const double min_vector = config_.min_vector_m;
  const double f_max = config_.f_max;
  const double f_slope_num = 1.0 - config_.f_max;
  const double k_skip = (continuous ? f_max / (f_max - 1.0) : 1.0) * (1.0 + 1e-9);
  for (std::size_t g = 0; g < n_groups_; ++g) {
    double m = 0.0;  // the largest cur sigma^2 of g's candidates
    for (std::uint32_t a = groups_[g].first; a < groups_[g].first + groups_[g].count; ++a) {
      const double sc = cur_sigma_[cands_[a].cur];
      if (sc * sc > m) m = sc * sc;
      cands_[a].score = 0.0;  // the sum over the other groups
    }
    groups_[g].max_sc2 = m;
  }
  // The pair's score from eps_n and dl, 0 when its direction test fails (only made when it would
  // raise best).
  const auto score = [&](double eps_n, double dl, bool direction, double dot, double la, double lb,
                         double best) noexcept {
    double v;
    if (continuous) {
      const double f = f_slope_num / eps_n * dl + f_max;
      v = f > 0.0 ? f : 0.0;
    } else {
      v = dl < eps_n ? 1.0 : 0.0;
    }
    if (!(v > best)) return best;
    if (direction) {
      double tol = att_tol + eps_n / la;
      if (tol > 1.0) tol = 1.0;
      const double t2 = tol * tol;
      const double eps_p = t2 * (0.5 - t2 * (1.0 / 24.0 - t2 * (1.0 / 720.0)));
      if (dot < (1.0 - eps_p) * la * lb) return best;  // scores 0
    }
    return v;
  };
  double best_b[64];  // max_candidates_per_landmark <= 64 (create())
  std::size_t evaluations = 0;
  for (std::size_t g = 0; g < n_groups_; ++g) {
    const std::uint32_t a0 = groups_[g].first, a1 = groups_[g].first + groups_[g].count;
    const std::uint16_t p = cands_[a0].prev;
    const Vec3d pa = prev_pos_[p];
    const double spa = prev_sigma_[p] * prev_sigma_[p];
    const double gsc2 = groups_[g].max_sc2;
    for (std::size_t h = g + 1; h < n_groups_; ++h) {
      const std::uint32_t b0 = groups_[h].first, b1 = groups_[h].first + groups_[h].count;
      const std::uint16_t p2 = cands_[b0].prev;  // one prev landmark per group
      const Vec3d va = pa - prev_pos_[p2];
      const double la = va.norm();
      const double sp = spa + prev_sigma_[p2] * prev_sigma_[p2];
      const bool direction_test = la >= min_vector;
      const double eps_upper = n_sigma * std::sqrt(sp + gsc2 + groups_[h].max_sc2) + eps_floor;
      const double t = eps_upper * k_skip;  // |la - lb| > t: the pair scores 0 both ways
      const double hi2 = (la + t) * (la + t) * (1.0 + 1e-9);
      const double lo = la - t;
      const double lo2 = lo > 0.0 ? lo * lo * (1.0 - 1e-9) : -1.0;
      for (std::uint32_t b = b0; b < b1; ++b) best_b[b - b0] = 0.0;
      for (std::uint32_t a = a0; a < a1; ++a) {
        Candidate& ca = cands_[a];
        const Vec3d qa = cur_rot_[ca.cur];
        const double sca = cur_sigma_[ca.cur] * cur_sigma_[ca.cur];
        double best_a = 0.0;
        for (std::uint32_t b = b0; b < b1; ++b) {
          const Candidate& cb = cands_[b];
          if (cb.cur == ca.cur) continue;
          evaluations += 2;
          const Vec3d vb = qa - cur_rot_[cb.cur];
          const double lb2 = vb.squaredNorm();
          if (lb2 > hi2 || lb2 < lo2) continue;
          const double lb = vb.norm();
          const double dl = std::fabs(la - lb);
          const double scb = cur_sigma_[cb.cur] * cur_sigma_[cb.cur];
          const double eps_ab = n_sigma * std::sqrt(sp + sca + scb) + eps_floor;  // a's score against h
          const double eps_ba = n_sigma * std::sqrt(sp + scb + sca) + eps_floor;  // b's score against g
          const bool direction = direction_test && lb > 0.0;
          const double dot = direction ? va.dot(vb) : 0.0;  // (-va).(-vb) for b's: the same
          best_a = score(eps_ab, dl, direction, dot, la, lb, best_a);
          best_b[b - b0] = score(eps_ba, dl, direction, dot, la, lb, best_b[b - b0]);
        }
        ca.score += best_a;
      }
      for (std::uint32_t b = b0; b < b1; ++b) cands_[b].score += best_b[b - b0];
    }
  }
  if (config_.appearance_weight > 0.0 && continuous) {
    for (std::size_t a = 0; a < n_cands_; ++a) {
      Candidate& ca = cands_[a];
      const Landmark3& lp = prev_in_[ca.prev];
      const Landmark3& lc = cur_in_[ca.cur];
      if (lp.has_appearance && lc.has_appearance) {
        double r = ncc(lp, lc);
        if (r < 0.0) r = 0.0;
        ca.score *= (1.0 - config_.appearance_weight) + config_.appearance_weight * r;
      }
    }
  }
  stats_.pair_evaluations += evaluations;
}

// 3. potential matches: best candidate per prev, then best prev per cur (one-to-one), at most
// max_matches of the highest scores; returns their count.
std::size_t GeometricMatcher::select_potential(std::size_t nc) noexcept {
  const std::uint32_t kNone = 0xFFFFFFFFu;
  for (std::size_t j = 0; j < nc; ++j) best_of_cur_[j] = kNone;
  std::size_t n_best = 0;
  for (std::size_t g = 0; g < n_groups_; ++g) {
    std::uint32_t best = kNone;
    for (std::uint32_t a = groups_[g].first; a < groups_[g].first + groups_[g].count; ++a)
      if (best == kNone || cands_[a].score > cands_[best].score) best = a;
    if (best == kNone || cands_[best].score < config_.min_support) continue;
    const std::uint16_t j = cands_[best].cur;
    if (best_of_cur_[j] == kNone || cands_[best].score > cands_[best_of_cur_[j]].score) best_of_cur_[j] = best;
  }
  for (std::size_t j = 0; j < nc; ++j) {
    if (best_of_cur_[j] == kNone) continue;
    const Candidate& c = cands_[best_of_cur_[j]];
    potential_[n_best++] = Match{c.prev, c.cur, static_cast<float>(c.score), 0.0f};
  }
  // Keep the max_matches highest scores (partial selection sort: bounded by max_matches * n_best).
  std::size_t m = n_best;
  if (m > config_.max_matches) {
    counters_.increment(MatchCounter::kPotentialMatchesCapped);
    for (std::size_t k = 0; k < config_.max_matches; ++k) {
      std::size_t arg = k;
      for (std::size_t q = k + 1; q < n_best; ++q)
        if (potential_[q].score > potential_[arg].score) arg = q;
      const Match t = potential_[k];
      potential_[k] = potential_[arg];
      potential_[arg] = t;
    }
    m = config_.max_matches;
  }
  return m;
}

// 4. consistency pass (eq. 6) over the m potential matches: the least consistent is removed until every
// one left agrees with all others; alive_ and compat_sum_ say which are left and their consistency.
// Returns the number removed.
std::size_t GeometricMatcher::consistency_pass(std::size_t m) noexcept {
  const std::size_t w = words_per_row_;
  for (std::size_t k = 0; k < m; ++k) {
    for (std::size_t q = 0; q < w; ++q) compat_bits_[k * w + q] = 0;
    compat_count_[k] = 0;
    compat_sum_[k] = 0.0;
    alive_[k] = 1;
  }
  for (std::size_t k = 0; k < m; ++k) {
    for (std::size_t q = k + 1; q < m; ++q) {
      bool bin = false;
      const double f = compat(potential_[k].prev, potential_[k].cur, potential_[q].prev, potential_[q].cur, &bin);
      ++stats_.pair_evaluations;
      if (bin) {
        compat_bits_[k * w + q / 64] |= (std::uint64_t{1} << (q % 64));
        compat_bits_[q * w + k / 64] |= (std::uint64_t{1} << (k % 64));
        ++compat_count_[k];
        ++compat_count_[q];
        compat_sum_[k] += f;
        compat_sum_[q] += f;
      }
    }
  }
  std::size_t alive = m;
  std::size_t removed = 0;
  for (std::size_t iter = 0; iter < m && alive > 0; ++iter) {  // each iteration removes one: bounded by m
    std::size_t worst = m;
    for (std::size_t k = 0; k < m; ++k) {
      if (!alive_[k]) continue;
      if (worst == m || compat_count_[k] < compat_count_[worst] ||
          (compat_count_[k] == compat_count_[worst] && compat_sum_[k] < compat_sum_[worst]))
        worst = k;
    }
    if (compat_count_[worst] + 1u >= alive) break;  // every remaining match agrees with all others
    alive_[worst] = 0;
    --alive;
    ++removed;
    for (std::size_t k = 0; k < m; ++k) {
      if (!alive_[k]) continue;
      if (compat_bits_[worst * w + k / 64] & (std::uint64_t{1} << (k % 64))) {
        --compat_count_[k];
        bool bin = false;
        compat_sum_[k] -= compat(potential_[k].prev, potential_[k].cur, potential_[worst].prev, potential_[worst].cur, &bin);
      }
    }
  }
  return removed;
}

Result<Span<const Match>> GeometricMatcher::match(Span<const Landmark3> prev, Span<const Landmark3> cur,
                                                  const MotionPrior& prior) noexcept {
  stats_ = MatchStats{};
  n_out_ = 0;
  if (!prev_pos_) return Status(StatusCode::kInvalidArgument, "geometric matcher not created");
  const Mat3d& R = prior.R_prev_cur;
  if (!R.allFinite() || !prior.t_prev_cur_m.allFinite() || !std::isfinite(prior.translation_sigma_m) ||
      prior.translation_sigma_m < 0.0 || !((R.transpose() * R - Mat3d::Identity()).cwiseAbs().maxCoeff() < 1e-6) ||
      !(R.determinant() > 0.0)) {
    counters_.increment(MatchCounter::kBadPrior);
    return Status(StatusCode::kInvalidArgument, "motion prior is not a finite rotation and translation");
  }
  std::size_t np = prev.size();
  std::size_t nc = cur.size();
  if (np > config_.max_landmarks || nc > config_.max_landmarks) {
    counters_.increment(MatchCounter::kLandmarksTruncated);
    if (np > config_.max_landmarks) np = config_.max_landmarks;
    if (nc > config_.max_landmarks) nc = config_.max_landmarks;
  }
  prev_in_ = prev;
  cur_in_ = cur;
  for (std::size_t i = 0; i < np; ++i) {
    prev_ok_[i] = finite_landmark(prev[i]) ? 1 : 0;
    if (!prev_ok_[i]) {
      counters_.increment(MatchCounter::kBadLandmark);
      continue;
    }
    prev_pos_[i] = prev[i].position_m;
    prev_sigma_[i] = prev[i].sigma_m;
  }
  for (std::size_t j = 0; j < nc; ++j) {
    cur_ok_[j] = finite_landmark(cur[j]) ? 1 : 0;
    if (!cur_ok_[j]) {
      counters_.increment(MatchCounter::kBadLandmark);
      continue;
    }
    cur_rot_[j] = R * cur[j].position_m;
    cur_sigma_[j] = cur[j].sigma_m;
  }
  const std::size_t nmax = np > nc ? np : nc;
  const std::size_t batch = config_.fast ? config_.batch_size : (nmax > 0 ? nmax : 1);
  const std::size_t rounds = nmax == 0 ? 0 : (nmax + batch - 1) / batch;
  for (std::size_t r = 1; r <= rounds; ++r) {
    const std::size_t kp = r * batch < np ? r * batch : np;
    const std::size_t kc = r * batch < nc ? r * batch : nc;
    run_round(kp, kc, prior);
    stats_.rounds = r;
    stats_.prev_used = kp;
    stats_.cur_used = kc;
    if (n_out_ >= config_.min_matches) break;
  }
  stats_.matches = n_out_;
  if (n_out_ < 3) counters_.increment(MatchCounter::kTooFewMatches);
  return Span<const Match>(out_.get(), n_out_);
}

}  // namespace qnav::match
