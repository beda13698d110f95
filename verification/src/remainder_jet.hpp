#pragma once
// The plant's distance from its linearisation with its derivatives (internal to the verifier), as
// a function of y = (e, w1, w2): the pendulum's angle from upright and the rates the momenta give
// at upright, w = M(pi)^-1 p for the plant's own parameters. The linearisation's a(v) with v the
// plant's M(pi)^-1 (the verifier carries v's spread in sensitivities); at a point the value and
// gradient give the first-order part the verifier carries in the noise symbols, over a box the
// higher derivatives bound the rest (Taylor and mean value forms).

#include <array>
#include <cstddef>

#include "furuta/interval/interval.hpp"
#include "furuta/model/parameters.hpp"
#include "loop_maps.hpp"

namespace furuta::verification::detail {

// The second and third derivatives' indices, sorted, in the order RemainderJet holds them.
inline constexpr std::array<std::array<std::size_t, 2>, 6> kPairs{
    {{0, 0}, {0, 1}, {0, 2}, {1, 1}, {1, 2}, {2, 2}}};
inline constexpr std::array<std::array<std::size_t, 3>, 10> kTriples{{{0, 0, 0},
                                                                      {0, 0, 1},
                                                                      {0, 0, 2},
                                                                      {0, 1, 1},
                                                                      {0, 1, 2},
                                                                      {0, 2, 2},
                                                                      {1, 1, 1},
                                                                      {1, 1, 2},
                                                                      {1, 2, 2},
                                                                      {2, 2, 2}}};

// The position of (i, j) in kPairs, in either order.
constexpr std::size_t pair_index(std::size_t i, std::size_t j) {
  return i > j ? pair_index(j, i) : (i == 0 ? j : (i == 1 ? 2 + j : 5));
}

struct RemainderJet {
  IVector4 value;                                   // n(y), the duty's term excluded
  std::array<std::array<Interval, 3>, 4> gradient;  // dn_i / dy_k
  // d2n_i / dy_k dy_l, the upper triangle: (0,0) (0,1) (0,2) (1,1) (1,2) (2,2).
  std::array<std::array<Interval, 6>, 4> hessian;
  // d3n_i / dy_k dy_l dy_m, sorted k <= l <= m: 000 001 002 011 012 022 111 112 122 222.
  std::array<std::array<Interval, 10>, 4> third;
};

// n = f(z, u) - a(v) z - b u over every y in `y` and parameter in `p` (kw the back-EMF constant),
// without (kd - plant.kd) u: the field in momentum coordinates (MomentumPlant), a(v) with the
// plant's damping, pendulum friction and mug at the centre's.
// third: also the third derivatives (else 0).
RemainderJet remainder_jet(const MomentumPlant& plant, const model::Parameters<Interval>& p,
                           const Interval& kw, const std::array<Interval, 3>& y, bool third = true);

}  // namespace furuta::verification::detail
