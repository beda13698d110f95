#pragma once
// Taylor-mode automatic differentiation for the validated integrator (see validated/README.md).
//
// - `Taylor<T>`: a truncated power series in t (coefficients c[0..order]) with + - * / sqr sin cos.
//   Every operation is built on the per-coefficient recurrences of namespace `series`, which give
//   coefficient i of a result from coefficients 0..i of its operands (and 0..i-1 of itself).
// - `Grad<N, S>`: a forward-mode gradient (value and N partial derivatives, of scalar S: intervals
//   by default, or Taylor models). Taylor coefficients computed with T = Grad<N> carry their
//   derivatives with respect to the initial state: the Jacobian of the Taylor map.
// - `Jet2<N>`: a second-order directional jet (value, first and second coefficient in a scalar s
//   along an uncertain direction, linear in N interval coordinates): the second-order term of the
//   Taylor map over a set.
// - `Tape`, `record`: a vector field f, written once as a template over its scalar type, is
//   recorded into a list of operations by evaluating it on `Recorder` scalars.
// - `TaylorRunner<T>`: the Taylor coefficients x_[0..k] of the solution of x' = f(x), x(0) = x0,
//   from the tape, one order at a time over all nodes (coefficient i of a product costs O(i), so
//   the whole series costs O(k^2) per operation). T = Interval gives rigorous enclosures (every
//   operation is outward rounded); T = double or long double a plain point series.
//
// The concepts live in detail/ (one header each; include this one): series.hpp (the recurrences),
// taylor_series.hpp (Taylor<T>), grad.hpp, jet2.hpp, quad_jet.hpp, tape.hpp (Tape, Recorder,
// record), constant_as.hpp, taylor_runner.hpp.

#include "furuta/validated/detail/constant_as.hpp"
#include "furuta/validated/detail/grad.hpp"
#include "furuta/validated/detail/jet2.hpp"
#include "furuta/validated/detail/quad_jet.hpp"
#include "furuta/validated/detail/series.hpp"
#include "furuta/validated/detail/tape.hpp"
#include "furuta/validated/detail/taylor_runner.hpp"
#include "furuta/validated/detail/taylor_series.hpp"
