#pragma once
// Quadratic forms in rho (internal to the validated integrator): the second-order part P(rho) of
// the set, one form per component, pair_count(n) coefficients each (pairs a <= b, row by row, as
// QuadJet).

#include <cstddef>
#include <vector>

#include "furuta/interval/interval.hpp"

namespace furuta::validated::detail {

using interval::Interval;

inline std::size_t pair_count(std::size_t n) {
  return n * (n + 1) / 2;
}

// The range over the box rho of the quadratic form with coefficients q[0..P) (pairs a <= b, row
// by row, as QuadJet): each rho_a^2 as a square.
template <class Coefficient>
Interval form_range(const Coefficient* q, const std::vector<Interval>& rho) {
  const std::size_t n = rho.size();
  Interval out(0.0);
  std::size_t k = 0;
  for (std::size_t a = 0; a < n; ++a) {
    out += Interval(q[k++]) * sqr(rho[a]);
    for (std::size_t b = a + 1; b < n; ++b) out += Interval(q[k++]) * (rho[a] * rho[b]);
  }
  return out;
}

// The ranges of the n forms p[v P .. (v + 1) P) over rho (zeros when p is empty).
inline std::vector<Interval> forms_range(const std::vector<double>& p,
                                         const std::vector<Interval>& rho) {
  const std::size_t n = rho.size();
  std::vector<Interval> out(n, Interval(0.0));
  if (p.empty()) return out;
  const std::size_t pairs = pair_count(n);
  for (std::size_t v = 0; v < n; ++v) out[v] = form_range(p.data() + v * pairs, rho);
  return out;
}

}  // namespace furuta::validated::detail
