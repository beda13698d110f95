#pragma once
// The doubleton tube's enclosure at one time as an affine form in its start: what the study of set
// inversion through the ODE over windows (bench/guaranteed_windows.cpp) reads as linear
// constraints on the start and on parameters carried as state. The product's set inversion goes
// through the Taylor-model flow instead (identification/window_inversion.hpp).
//
//   const IntegrationResult r = integrate(FurutaDynamics(tau), x0, options);
//   const AffineEnclosure e = affine_at(r.tube, t);   // x(t) in e.offset + e.a (x0 - e.origin)

#include <cstddef>
#include <vector>

#include "furuta/interval/interval.hpp"
#include "furuta/validated/integrator.hpp"

namespace furuta::validated::research {

// Every solution at one time as an affine form in its start: x(t) in offset + a rho for every
// start x0 = origin + rho with rho in `rho`. `a` is a point matrix (the midpoint of the step's
// V(s) C); the rest of V(s) C over rho, the quadratic part, the gathered errors and the Lagrange
// remainder are in `offset`. Set inversion reads the measured components of it as linear
// constraints on the start and on parameters carried as state.
struct AffineEnclosure {
  std::size_t dimension = 0;
  std::vector<double> a;         // dimension x dimension, row-major
  std::vector<Interval> offset;  // dimension
  std::vector<Interval> rho;     // the box rho lives in (the start minus origin)
  std::vector<double> origin;    // dimension
};

// The affine form of every solution of `tube` at t in [t_start, t_end()] (see AffineEnclosure);
// at a step's boundary the later step's. Throws std::out_of_range outside the tube or in a step
// without a form.
AffineEnclosure affine_at(const Tube& tube, double t);

}  // namespace furuta::validated::research
