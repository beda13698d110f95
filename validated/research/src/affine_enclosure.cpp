#include "furuta/validated/research/affine_enclosure.hpp"

#include <algorithm>
#include <stdexcept>

#include "interval_matrix.hpp"
#include "taylor_form.hpp"

namespace furuta::validated::research {

using detail::form_terms;
using detail::FormTerms;
using detail::from_point;
using detail::IMatrix;

AffineEnclosure affine_at(const Tube& tube, double t) {
  if (!(t >= tube.t_start && t <= tube.t_end()) || tube.steps.empty()) {
    throw std::out_of_range("affine_at: t outside the tube");
  }
  // The step that starts at or before t and ends after it (the last one at t_end()).
  auto it = std::upper_bound(tube.steps.begin(), tube.steps.end(), t,
                             [](double time, const TubeStep& s) { return time < s.t1; });
  if (it == tube.steps.end()) --it;
  const TubeStep& step = *it;
  if (!step.has_form()) throw std::out_of_range("affine_at: the step has no Taylor form");
  const std::size_t n = tube.dimension;
  const Interval s = (Interval(t) - Interval(step.t0)) & Interval(0.0, step.h.hi());
  AffineEnclosure out;
  out.dimension = n;
  out.rho = step.r0.empty() ? tube.r0 : step.r0;
  out.origin = step.origin.empty() ? tube.initial.mid() : step.origin;
  const FormTerms terms = form_terms(step, n, tube.order, s, out.rho);
  // V(s) C splits into its midpoint (the point matrix a) and the rest, enclosed over rho.
  const IMatrix vc = terms.v * from_point(n, step.c);
  out.a.resize(n * n);
  IMatrix rest(n);
  for (std::size_t k = 0; k < n * n; ++k) {
    out.a[k] = vc.v[k].mid();
    rest.v[k] = vc.v[k] - Interval(out.a[k]);
  }
  const std::vector<Interval> linear_rest = rest * out.rho;
  out.offset.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    out.offset[i] = terms.polynomial[i] + linear_rest[i] + terms.quadratic[i] + terms.errors[i] +
                    terms.remainder[i];
  }
  return out;
}

}  // namespace furuta::validated::research
