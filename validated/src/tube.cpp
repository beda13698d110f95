// The tube: its steps as a run appends them, and the enclosures it gives (see integrator.hpp and
// tube.hpp).

#include "tube.hpp"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "interval_matrix.hpp"
#include "quadratic_form.hpp"
#include "taylor_form.hpp"

namespace furuta::validated {

using detail::form_terms;
using detail::FormTerms;
using detail::from_point;

Box Tube::step_form(std::size_t index, const Interval& s) const {
  const TubeStep& step = steps.at(index);
  if (!step.has_form()) return step.over;
  const std::size_t n = dimension;
  const std::vector<Interval>& step_r0 = step.r0.empty() ? r0 : step.r0;
  const FormTerms t = form_terms(step, n, order, s, step_r0);
  const std::vector<Interval> linear0 = (t.v * from_point(n, step.c)) * step_r0;
  Box out(n);
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = t.polynomial[i] + linear0[i] + t.quadratic[i] + t.errors[i] + t.remainder[i];
  }
  return out;
}

Box Tube::enclosure_at(double t) const {
  if (!(t >= t_start && t <= t_end())) return Box(dimension, Interval::empty());
  if (t == t_start) return initial;
  const auto it = std::lower_bound(steps.begin(), steps.end(), t,
                                   [](const TubeStep& s, double time) { return s.t1 < time; });
  if (it->t1 == t) return it->end;
  const Interval s = (Interval(t) - Interval(it->t0)) & Interval(0.0, it->h.hi());
  return intersect(step_form(static_cast<std::size_t>(it - steps.begin()), s), it->over);
}

Box Tube::enclosure_over(double ta, double tb) const {
  if (!(ta <= tb)) return Box(dimension, Interval::empty());
  ta = std::max(ta, t_start);
  tb = std::min(tb, t_end());
  if (!(ta <= tb)) return Box(dimension, Interval::empty());
  if (ta == tb) return enclosure_at(ta);
  Box hull_box = ta == t_start ? initial : Box(dimension, Interval::empty());
  auto it = std::lower_bound(steps.begin(), steps.end(), ta,
                             [](const TubeStep& s, double time) { return s.t1 < time; });
  for (; it != steps.end() && it->t0 < tb; ++it) {
    const double a = std::max(ta, it->t0);
    const double b = std::min(tb, it->t1);
    Box part;
    if (a == it->t1) {
      part = it->end;
    } else {
      const Interval s = ((Interval(a) - Interval(it->t0)) | (Interval(b) - Interval(it->t0))) &
                         Interval(0.0, it->h.hi());
      part = intersect(step_form(static_cast<std::size_t>(it - steps.begin()), s), it->over);
    }
    hull_box = hull(hull_box, part);
  }
  return hull_box;
}

namespace detail {

FormTerms form_terms(const TubeStep& step, std::size_t n, int order, const Interval& s,
                     const std::vector<Interval>& step_r0) {
  FormTerms t{jacobian_series(step.jacobian, n, order, s), {}, {}, {}, {}};
  t.quadratic = t.v * forms_range(step.quad, step_r0);
  t.errors = (t.v * from_point(n, step.b)) * step.r;
  const Interval s_k1 = pow(s, order + 1);
  for (std::size_t i = 0; i < n; ++i) {
    t.polynomial.push_back(horner(step.centre, n, i, order, s) +
                           horner(step.second, n, i, order, s));
    t.remainder.push_back(s_k1 * step.remainder[i]);
  }
  return t;
}

TubeStep start_step(const Doubleton& set, const StepEnclosure& enclosure) {
  const std::size_t n = set.m.size();
  TubeStep step;
  step.t0 = set.t;
  step.t1 = enclosure.t1;
  step.h = enclosure.hi;
  {
    const Matrix ct = set.c.transpose();
    const Matrix bt = set.b.transpose();
    step.c.assign(ct.data(), ct.data() + n * n);
    step.b.assign(bt.data(), bt.data() + n * n);
  }
  step.r = set.r;
  step.r0 = set.r0;
  step.origin = set.origin;
  step.remainder = enclosure.remainder_coefficient;
  step.quad = set.p;
  return step;
}

void append_step(Tube& tube, TubeStep step, const Box& apriori, const Box& end) {
  const Interval h = step.h;
  step.apriori = apriori;
  step.end = end;
  tube.steps.push_back(std::move(step));
  TubeStep& stored = tube.steps.back();
  stored.over = intersect(tube.step_form(tube.steps.size() - 1, Interval(0.0, h.hi())), apriori);
}

}  // namespace detail
}  // namespace furuta::validated
