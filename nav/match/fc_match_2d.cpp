#include "nav/match/fc_match_2d.hpp"

#include <algorithm>
#include <cmath>

namespace qnav::match {

float zncc_i8(const std::int8_t* a, const std::int8_t* b, std::size_t n) noexcept {
  std::int32_t sa = 0, sb = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sa += a[i];
    sb += b[i];
  }
  std::int64_t saa = 0, sbb = 0, sab = 0;
  for (std::size_t i = 0; i < n; ++i) {
    saa += static_cast<std::int32_t>(a[i]) * a[i];
    sbb += static_cast<std::int32_t>(b[i]) * b[i];
    sab += static_cast<std::int32_t>(a[i]) * b[i];
  }
  const double nn = static_cast<double>(n);
  const double va = static_cast<double>(saa) - static_cast<double>(sa) * sa / nn;
  const double vb = static_cast<double>(sbb) - static_cast<double>(sb) * sb / nn;
  if (va <= 1e-9 || vb <= 1e-9) return 0.0f;
  const double cov = static_cast<double>(sab) - static_cast<double>(sa) * sb / nn;
  return static_cast<float>(cov / std::sqrt(va * vb));
}

namespace {

// Integer dot product of two widened descriptors: int16 x int16 summed in int32 (exact: |product| <=
// 2^14, at most a few hundred terms). The fixed-length form lets the compiler unroll and vectorise it
// (pmaddwd on x86, smlal on ARM); without SIMD it is the plain loop.
template <std::size_t D>
inline std::int32_t dot_i16(const std::int16_t* a, const std::int16_t* b) noexcept {
  std::int32_t s = 0;
  for (std::size_t q = 0; q < D; ++q) s += static_cast<std::int32_t>(a[q]) * b[q];
  return s;
}

inline std::int32_t dot_i16(const std::int16_t* a, const std::int16_t* b, std::size_t d) noexcept {
  std::int32_t s = 0;
  for (std::size_t q = 0; q < d; ++q) s += static_cast<std::int32_t>(a[q]) * b[q];
  return s;
}

}  // namespace

std::size_t FcMatcher2d::arena_bytes(const FcMatch2dConfig& c) noexcept {
  const std::size_t nc = c.max_points * c.max_candidates_per_point;
  return nc * sizeof(Candidate) + (c.max_points + 1) * sizeof(std::uint32_t) + nc * sizeof(std::uint32_t) +
         2 * c.max_points + 4 * c.max_points * sizeof(float) + 2 * c.max_points * c.max_descriptor_bytes * sizeof(std::int16_t) +
         128;
}

Status FcMatcher2d::init(const FcMatch2dConfig& c, Arena& arena) noexcept {
  if (c.max_points == 0 || c.max_points > 65535 || c.max_candidates_per_point == 0 || c.max_candidates_per_point > 32 ||
      !(c.sigma_dist_m > 0.0) || !(c.sigma_dir_rad > 0.0) || !(c.appearance_weight >= 0.0f && c.appearance_weight <= 1.0f) ||
      !std::isfinite(c.min_appearance) || !std::isfinite(c.min_support) || c.max_descriptor_bytes == 0 ||
      c.max_descriptor_bytes > 4096)
    return Status(StatusCode::kInvalidArgument, "fc_match_2d: bad configuration");
  const std::size_t nc = c.max_points * c.max_candidates_per_point;
  cand_ = arena.allocate<Candidate>(nc);
  first_ = arena.allocate<std::uint32_t>(c.max_points + 1);
  order_ = arena.allocate<std::uint32_t>(nc);
  used_a_ = arena.allocate<std::uint8_t>(c.max_points);
  used_b_ = arena.allocate<std::uint8_t>(c.max_points);
  stats_a_ = arena.allocate<float>(2 * c.max_points);
  stats_b_ = arena.allocate<float>(2 * c.max_points);
  wide_a_ = arena.allocate<std::int16_t>(c.max_points * c.max_descriptor_bytes);
  wide_b_ = arena.allocate<std::int16_t>(c.max_points * c.max_descriptor_bytes);
  if (cand_.empty() || first_.empty() || order_.empty() || used_a_.empty() || used_b_.empty() || stats_a_.empty() || stats_b_.empty() ||
      wide_a_.empty() || wide_b_.empty())
    return Status(StatusCode::kCapacityExceeded, "fc_match_2d: arena too small");
  config_ = c;
  ready_ = true;
  return Status::ok();
}

Status FcMatcher2d::match(const KeypointSet2d& a, const KeypointSet2d& b, double dtheta_rad,
                          BoundedVector<Match2d>& out) noexcept {
  out.clear();
  if (!ready_) return Status(StatusCode::kNotReady, "fc_match_2d: not initialised");
  if (!std::isfinite(dtheta_rad) || a.desc_bytes == 0 || a.desc_bytes != b.desc_bytes || a.desc_bytes > config_.max_descriptor_bytes ||
      a.descriptors.size() < a.position_m.size() * a.desc_bytes || b.descriptors.size() < b.position_m.size() * b.desc_bytes) {
    counters_.increment(FcMatchCounter::kBadInput);
    return Status(StatusCode::kInvalidArgument, "fc_match_2d: inconsistent keypoint sets");
  }
  std::size_t na = a.position_m.size(), nb = b.position_m.size();
  if (na > config_.max_points) {
    counters_.increment(FcMatchCounter::kPointsIgnored, static_cast<std::uint32_t>(na - config_.max_points));
    na = config_.max_points;
  }
  if (nb > config_.max_points) {
    counters_.increment(FcMatchCounter::kPointsIgnored, static_cast<std::uint32_t>(nb - config_.max_points));
    nb = config_.max_points;
  }
  if (na < 2 || nb < 2) return Status::ok();
  const std::size_t k = config_.max_candidates_per_point;
  const std::size_t d = a.desc_bytes;

  // 1. Appearance candidates, grouped by a, best first (insertion into a k-long list). Each
  //    descriptor's sum and 1/sqrt(n var) are computed once, so a pair costs one integer dot product.
  auto stats = [d](const std::int8_t* p, float* st) {
    std::int32_t s1 = 0, s2 = 0;
    for (std::size_t q = 0; q < d; ++q) {
      s1 += p[q];
      s2 += static_cast<std::int32_t>(p[q]) * p[q];
    }
    const double var = static_cast<double>(s2) - static_cast<double>(s1) * s1 / static_cast<double>(d);
    st[0] = static_cast<float>(s1);
    st[1] = var > 1e-9 ? static_cast<float>(1.0 / std::sqrt(var)) : 0.0f;
  };
  for (std::size_t i = 0; i < na; ++i) stats(a.descriptors.data() + i * d, stats_a_.data() + 2 * i);
  for (std::size_t j = 0; j < nb; ++j) stats(b.descriptors.data() + j * d, stats_b_.data() + 2 * j);
  for (std::size_t q = 0; q < na * d; ++q) wide_a_[q] = a.descriptors[q];
  for (std::size_t q = 0; q < nb * d; ++q) wide_b_[q] = b.descriptors[q];
  const float inv_d = 1.0f / static_cast<float>(d);
  std::size_t nc = 0;
  for (std::size_t i = 0; i < na; ++i) {
    first_[i] = static_cast<std::uint32_t>(nc);
    const float sa = stats_a_[2 * i], ia = stats_a_[2 * i + 1];
    if (ia == 0.0f) continue;  // a flat descriptor has no candidates
    std::size_t have = 0;
    Candidate* list = cand_.data() + nc;
    const std::int16_t* da = wide_a_.data() + i * d;
    for (std::size_t j = 0; j < nb; ++j) {
      const float ib = stats_b_[2 * j + 1];
      if (ib == 0.0f) continue;
      const std::int16_t* db = wide_b_.data() + j * d;
      const std::int32_t dot = d == 64 ? dot_i16<64>(da, db) : dot_i16(da, db, d);
      const float z = (static_cast<float>(dot) - sa * stats_b_[2 * j] * inv_d) * ia * ib;
      if (!(z >= config_.min_appearance)) continue;
      if (have == k && z <= list[k - 1].appearance) continue;
      std::size_t pos = have < k ? have++ : k - 1;
      while (pos > 0 && list[pos - 1].appearance < z) {
        list[pos] = list[pos - 1];
        --pos;
      }
      list[pos] = Candidate{static_cast<std::uint16_t>(i), static_cast<std::uint16_t>(j), z, 0.0f};
    }
    nc += have;
  }
  first_[na] = static_cast<std::uint32_t>(nc);
  if (nc == 0) return Status::ok();

  // 2. Continuous geometric score. Work per keypoint a (its <= k candidates share the vectors to the
  //    other keypoints a'), so each (a', candidate of a') pair costs one norm, one dot and one exp.
  const Mat2d r = Pose2{0.0, 0.0, dtheta_rad}.rotation();
  const double inv2sd = 1.0 / (2.0 * config_.sigma_dist_m * config_.sigma_dist_m);
  const float w = config_.appearance_weight;
  constexpr std::size_t kMaxK = 32;
  double acc[kMaxK];
  for (std::size_t i = 0; i < na; ++i) {
    const std::uint32_t c0 = first_[i], c1 = first_[i + 1];
    if (c0 == c1) continue;
    const std::size_t nci = c1 - c0;
    for (std::size_t q = 0; q < nci; ++q) acc[q] = 0.0;
    const Vec2d pa = a.position_m[i];
    for (std::size_t i2 = 0; i2 < na; ++i2) {
      if (i2 == i || first_[i2] == first_[i2 + 1]) continue;
      const Vec2d va = r * (a.position_m[i2] - pa);
      const double la = va.norm();
      if (la < 1e-9) continue;
      const double sphi = config_.sigma_dir_rad + config_.sigma_dist_m / la;
      const double inv2sp = 1.0 / (2.0 * sphi * sphi);
      // Gate: f >= 1e-3 needs dd^2 < 13.8 sd^2 and phi^2 < 13.8 sphi^2, so |vb - va|^2 (~ dd^2 +
      // (la phi)^2) stays below 13.8 (sd^2 + la^2 sphi^2); x2 margin for the small-angle form.
      const double gate2 = 2.0 * 13.8 * (config_.sigma_dist_m * config_.sigma_dist_m + la * la * sphi * sphi);
      for (std::size_t q = 0; q < nci; ++q) {
        const Candidate& cc = cand_[c0 + q];
        const Vec2d pb = b.position_m[cc.b];
        double best = 0.0;
        for (std::uint32_t c2 = first_[i2]; c2 < first_[i2 + 1]; ++c2) {
          if (cand_[c2].b == cc.b) continue;
          const Vec2d vb = b.position_m[cand_[c2].b] - pb;
          if ((vb - va).squaredNorm() > gate2) continue;
          const double lb = vb.norm();
          const double dd = la - lb;
          const double ed = dd * dd * inv2sd;
          if (ed > 4.5 || lb < 1e-9) continue;  // beyond 3 sigma
          const double cosphi = va.dot(vb) / (la * lb);
          if (cosphi <= 0.0) continue;  // directions disagree by more than 90 degrees
          const double phi2 = 2.0 * (1.0 - cosphi);  // ~ phi^2 for small phi
          const double e = ed + phi2 * inv2sp;
          if (e > 6.9) continue;  // f < 1e-3
          const double f = std::exp(-e);
          if (f > best) best = f;
        }
        acc[q] += best;
      }
    }
    for (std::size_t q = 0; q < nci; ++q) {
      Candidate& cc = cand_[c0 + q];
      cc.score = static_cast<float>(acc[q]) * ((1.0f - w) + w * std::max(0.0f, cc.appearance));
    }
  }

  // 3. Greedy one-to-one selection.
  for (std::size_t c = 0; c < nc; ++c) order_[c] = static_cast<std::uint32_t>(c);
  std::sort(order_.begin(), order_.begin() + nc, [this](std::uint32_t x, std::uint32_t y) {
    if (cand_[x].score != cand_[y].score) return cand_[x].score > cand_[y].score;
    return x < y;
  });
  for (std::size_t i = 0; i < na; ++i) used_a_[i] = 0;
  for (std::size_t j = 0; j < nb; ++j) used_b_[j] = 0;
  for (std::size_t o = 0; o < nc; ++o) {
    const Candidate& cc = cand_[order_[o]];
    if (cc.score < config_.min_support) break;
    if (used_a_[cc.a] || used_b_[cc.b]) continue;
    if (!out.push_back(Match2d{cc.a, cc.b, cc.score, cc.appearance})) break;
    used_a_[cc.a] = 1;
    used_b_[cc.b] = 1;
  }
  return Status::ok();
}

}  // namespace qnav::match
