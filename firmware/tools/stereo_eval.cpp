#include "firmware/tools/stereo_eval.hpp"

#include <cmath>
#include <cstdlib>

namespace qnav::tools {

std::vector<double> epipolar_row_offsets(ConstImageViewU8 L, ConstImageViewU8 R, Span<const vision::Corner> corners) {
  std::vector<double> dys;
  if (L.empty() || R.empty() || L.width() != R.width() || L.height() != R.height()) return dys;
  const int rad = 5, W = L.width(), H = L.height();
  for (const vision::Corner& c : corners) {
    const int x = static_cast<int>(std::lround(c.x)), y = static_cast<int>(std::lround(c.y));
    if (x < rad + 81 || y < rad + 5 || x >= W - rad || y >= H - rad - 5) continue;
    double best = -2, second = -2, sc[9][81];
    int bd = 0, by = 0;
    for (int dy = -4; dy <= 4; ++dy)
      for (int dd = 1; dd <= 80; ++dd) {
        double sl = 0, sr = 0, sll = 0, srr = 0, slr = 0;
        for (int j = -rad; j <= rad; ++j)
          for (int i = -rad; i <= rad; ++i) {
            const double a = L(x + i, y + j), b = R(x - dd + i, y + dy + j);
            sl += a, sr += b, sll += a * a, srr += b * b, slr += a * b;
          }
        const double n = (2 * rad + 1) * (2 * rad + 1);
        const double den = std::sqrt((sll - sl * sl / n) * (srr - sr * sr / n));
        const double z = den > 1e-9 ? (slr - sl * sr / n) / den : -1;
        sc[dy + 4][dd] = z;
        if (z > best) {
          if (std::abs(dd - bd) > 2) second = best;
          best = z, bd = dd, by = dy;
        } else if (z > second && std::abs(dd - bd) > 2) {
          second = z;
        }
      }
    if (best < 0.9 || second > best - 0.05 || by == -4 || by == 4) continue;
    const double a = sc[by + 3][bd], b = sc[by + 4][bd], cc = sc[by + 5][bd];
    const double den = a - 2 * b + cc;
    dys.push_back(std::fabs(by + (den < 0 ? 0.5 * (a - cc) / den : 0.0)));
  }
  return dys;
}

}  // namespace qnav::tools
