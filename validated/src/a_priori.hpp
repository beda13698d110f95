#pragma once
// The a priori enclosure of a step and its Lagrange remainder (internal to the validated
// integrator, method steps 1, 2 and 6 of validated/README.md): the step size shrinks until
// Picard's test validates and the remainder is within the tolerance (or h_min is reached), and
// grows again from the remainder's width.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "furuta/interval/box.hpp"
#include "furuta/interval/interval.hpp"
#include "furuta/validated/integrator.hpp"
#include "furuta/validated/taylor.hpp"

namespace furuta::validated::detail {

using interval::Box;
using interval::Interval;

// A box containing every solution from x over [0, h], or nothing if Picard's test fails.
std::optional<Box> a_priori(TaylorRunner<Interval>& runner, const Tape& tape, const Box& x,
                            double h);

// An accepted step from t: its end t1 (t_limit when capped), h = t1 - t enclosed, the a priori
// enclosure over [t, t1] and the Lagrange remainder R = h^(k+1) x_[k+1](apriori).
struct StepEnclosure {
  double h = 0.0;       // the step size accepted (as tried, before t1 - t is rounded)
  bool capped = false;  // the step ends at t_limit, not where h_next said
  double t1 = 0.0;
  Interval hi;  // t1 - t
  Box apriori;
  std::vector<Interval> remainder_coefficient;  // x_[k+1] over apriori
  Box remainder;                                // hi^(k+1) remainder_coefficient
  double remainder_width = 0.0;                 // the widest component of remainder
  std::string failure;  // not empty: no step could be validated from t (why)
};

// The step from the box x at t towards t_limit, starting from h_next; each rejected attempt
// (Picard not validated, remainder too wide) counts in `rejected`.
StepEnclosure enclose_step(TaylorRunner<Interval>& runner, const Tape& tape, const Box& x, double t,
                           double t_limit, double h_next, const IntegratorOptions& options,
                           std::size_t& rejected);

// The step size after an accepted step: h (tolerance / w(R))^(1/(k+1)) x 0.9, between 0.25 and 2
// times the step; h_next unchanged after a step capped at t_limit.
double next_step_size(const StepEnclosure& step, double h_next, const IntegratorOptions& options);

}  // namespace furuta::validated::detail
