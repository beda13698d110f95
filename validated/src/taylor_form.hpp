#pragma once
// Evaluation of a step's Taylor form (internal to the validated integrator): the series of one
// component from its coefficient rows, and the Jacobian's series V(s) = sum_i s^i V_i, both by
// Horner; a step's form at s in its parts (form_terms, defined in tube.cpp).

#include <algorithm>
#include <cstddef>
#include <vector>

#include "furuta/interval/interval.hpp"
#include "furuta/validated/integrator.hpp"
#include "interval_matrix.hpp"

namespace furuta::validated::detail {

// sum_i s^i c[i stride + offset], i = 0..order.
inline Interval horner(const std::vector<Interval>& c, std::size_t stride, std::size_t offset,
                       int order, const Interval& s) {
  Interval y = c[static_cast<std::size_t>(order) * stride + offset];
  for (int i = order - 1; i >= 0; --i) y = y * s + c[static_cast<std::size_t>(i) * stride + offset];
  return y;
}

// V(s) = sum_i s^i V_i, i = 0..order, the n x n blocks V_i of `jacobian` (row-major).
inline IMatrix jacobian_series(const std::vector<Interval>& jacobian, std::size_t n, int order,
                               const Interval& s) {
  const auto k = static_cast<std::size_t>(order);
  IMatrix v(n);
  std::copy(jacobian.begin() + static_cast<std::ptrdiff_t>(k * n * n),
            jacobian.begin() + static_cast<std::ptrdiff_t>((k + 1) * n * n), v.v.begin());
  for (std::size_t i = k; i-- > 0;) {
    for (std::size_t e = 0; e < n * n; ++e) v.v[e] = v.v[e] * s + jacobian[i * n * n + e];
  }
  return v;
}

// The parts of a step's Taylor form at s that do not carry the start exactly: V(s) (by Horner),
// the centre's and the second-order term's polynomials, the quadratic part P(r0) and the gathered
// errors B r through V(s), and the Lagrange remainder. The start's own part is V(s) C r0.
struct FormTerms {
  IMatrix v;
  std::vector<Interval> polynomial, quadratic, errors, remainder;
};

// The step's form at s (a part of [0, h]), its quadratic part over step_r0 (the step's r0, or the
// tube's when the step has none); n and order are the tube's.
FormTerms form_terms(const TubeStep& step, std::size_t n, int order, const Interval& s,
                     const std::vector<Interval>& step_r0);

}  // namespace furuta::validated::detail
