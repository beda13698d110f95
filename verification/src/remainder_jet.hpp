#pragma once
// The plant's distance from its linearisation with its gradient (internal to the verifier), as a
// function of y = (e, w1, w2): the pendulum's angle from upright and the rates the linearisation
// gives, w = inverse p. Evaluated at a point it gives the first-order part the verifier carries in
// the noise symbols; over a box, the gradient's range that bounds the rest (the mean value form).

#include <array>

#include "furuta/interval/interval.hpp"
#include "furuta/model/parameters.hpp"
#include "loop_maps.hpp"

namespace furuta::verification::detail {

struct RemainderJet {
  IVector4 value;                                   // n(y), the duty's term excluded
  std::array<std::array<Interval, 3>, 4> gradient;  // dn_i / dy_k
  // d2n_i / dy_k dy_l, the upper triangle: (0,0) (0,1) (0,2) (1,1) (1,2) (2,2).
  std::array<std::array<Interval, 6>, 4> hessian;
  // d3n_i / dy_k dy_l dy_m, sorted k <= l <= m: 000 001 002 011 012 022 111 112 122 222.
  std::array<std::array<Interval, 10>, 4> third;
};

// n = f(z, u) - a z - b u over every y in `y` and parameter in `p` (kw the back-EMF constant),
// without (kd - plant.kd) u: the field in momentum coordinates (MomentumPlant) with p = mass w.
RemainderJet remainder_jet(const MomentumPlant& plant, const model::Parameters<Interval>& p,
                           const Interval& kw, const std::array<Interval, 3>& y);

}  // namespace furuta::verification::detail
