// Order statistics for the tool's reports, defined once (header-only, host side): the median is the
// upper middle element v[n / 2] (for an even count the larger of the two middle values), a percentile
// q in [0, 1] is the element at rank floor(q (n - 1)). Both reorder the caller's vector
// (std::nth_element, O(n)); the caller passes a copy when the order matters.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace qnav::tools {

// false (out untouched) when v is empty.
template <typename T>
bool median_of(std::vector<T>& v, T& out) {
  if (v.empty()) return false;
  const std::size_t k = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  out = v[k];
  return true;
}

template <typename T>
bool percentile_of(std::vector<T>& v, double q, T& out) {
  if (v.empty()) return false;
  const double qc = q < 0.0 ? 0.0 : (q > 1.0 ? 1.0 : q);
  const std::size_t k = static_cast<std::size_t>(qc * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  out = v[k];
  return true;
}

}  // namespace qnav::tools
