#pragma once
// The set of solutions at a step boundary (internal to the validated integrator): Lohner's
// doubleton with the second-order part, where a run starts and what each step carries on.

#include <cstddef>
#include <vector>

#include "furuta/interval/box.hpp"
#include "furuta/interval/interval.hpp"
#include "furuta/validated/integrator.hpp"
#include "interval_matrix.hpp"

namespace furuta::validated::detail {

using interval::Box;

// Where a run stands at a step boundary: every solution from x0 = origin + rho, rho in r0, is at
// time t in m + C rho + P(rho) + B r (for some point of r), and in the box x.
struct Doubleton {
  double t = 0.0;
  std::vector<double> origin;
  std::vector<Interval> r0;
  std::vector<double> m;
  Matrix c;
  std::vector<double> p;  // the quadratic part P(rho): n forms of pair_count(n) coefficients
  Matrix b;
  std::vector<Interval> r;
  Box x;
  double h_next = 0.0;
};

// The start of a run from x0 at options.t_start: centre and origin mid(x0), C = B = I, r = 0.
Doubleton initial_doubleton(const Box& x0, const IntegratorOptions& options);

// The restart of integrate_sub_box: the doubleton of tube.steps[step] at its t0, re-centred on
// `piece` (a sub-box of tube.initial; the arguments are checked by the caller).
// std::invalid_argument when the step's frame is singular.
Doubleton restart_doubleton(const std::vector<Tape>& tapes, const Tube& tube, std::size_t step,
                            const Box& piece, const IntegratorOptions& options);

}  // namespace furuta::validated::detail
