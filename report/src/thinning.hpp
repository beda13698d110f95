#pragma once
// Long traces thinned for a figure: per pixel column the values that shape what the eye sees.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace furuta::report {

// The indices a trace keeps: every sample while there are few, else per pixel column its first,
// lowest, highest and last (in time order), so the polyline still reaches every extreme. `t` in
// time order over [t0, t1], `pixels` the columns it is drawn over.
inline std::vector<std::size_t> thinned(const std::vector<double>& t, const std::vector<double>& y,
                                        double t0, double t1, double pixels) {
  const std::size_t n = std::min(t.size(), y.size());
  std::vector<std::size_t> keep;
  if (n <= static_cast<std::size_t>(4 * pixels) || !(t1 > t0)) {
    for (std::size_t i = 0; i < n; ++i) keep.push_back(i);
    return keep;
  }
  std::size_t i = 0;
  while (i < n) {
    const auto column = [&](std::size_t k) {
      return static_cast<long>(std::floor((t[k] - t0) / (t1 - t0) * pixels));
    };
    const long c = column(i);
    std::size_t lo = i, hi = i, last = i;
    for (std::size_t k = i; k < n && column(k) == c; ++k) {
      if (y[k] < y[lo]) lo = k;
      if (y[k] > y[hi]) hi = k;
      last = k;
    }
    std::vector<std::size_t> picked = {i, lo, hi, last};
    std::sort(picked.begin(), picked.end());
    picked.erase(std::unique(picked.begin(), picked.end()), picked.end());
    keep.insert(keep.end(), picked.begin(), picked.end());
    i = last + 1;
  }
  return keep;
}

}  // namespace furuta::report
