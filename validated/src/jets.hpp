#pragma once
// The jets of the Taylor coefficients (internal to the validated integrator): at the centre, the
// coefficients and their Jacobian (Grad<N>, centre_jets.cpp); over the set, their second-order
// term along the set's direction (Jet2<N> and QuadJet<N>, second_order_jets.cpp). Each runs
// TaylorRunner on the step's tape, instantiated for every dimension 1..kMaxDimension.

#include <cstddef>
#include <vector>

#include "furuta/interval/box.hpp"
#include "furuta/interval/interval.hpp"
#include "furuta/validated/taylor.hpp"
#include "interval_matrix.hpp"

namespace furuta::validated::detail {

using interval::Box;

constexpr std::size_t kMaxDimension = 16;

// The Taylor coefficients at the point m (values[i n + v] = x_[i]_v) and their derivatives with
// respect to the initial state (jac[(i n + v) n + c] = d x_[i]_v / d x0_c), i = 0..order.
void centre_coefficients(const Tape& tape, const std::vector<double>& m, int order,
                         std::vector<Interval>& values, std::vector<Interval>& jac);

// The second-order term over the set inside the box y: second[i n + v] = half the second
// derivative of x_[i]_v along delta = C rho + e (rho in r0, e in the interval vector `e`) over y,
// i = 0..order. Both jets enclose the same quantity: the low orders (0..quadratic_order), where
// the terms are largest, from the quadratic forms (tight, several times Jet2's cost), the
// others from Jet2. With `forms` (not null) the low orders also give their quadratic form in rho:
// forms[(i n + v) P + pair] (interval coefficients over y, P = n (n + 1) / 2 pairs a <= b) and
// d2e[i n + v] (the terms with e), so that second = forms(rho) + d2e; the other orders have a
// zero form and d2e = second.
// quadratic_part false: only the orders above quadratic_order (Jet2); the caller computes the
// others (second_order_extended).
void second_order_coefficients(const Tape& tape, const Box& y, const Matrix& c,
                               const std::vector<Interval>& r0, const std::vector<Interval>& e,
                               int order, int quadratic_order, std::vector<Interval>& second,
                               std::vector<Interval>* forms = nullptr,
                               std::vector<Interval>* d2e = nullptr, bool quadratic_part = true);

// The jets over (rho, r_L) run for n + |L| coordinates up to this (second_order_extended).
// 15 = the Furuta model with its seven parameters carried as state (11 coordinates of rho, 4 of r).
constexpr std::size_t kMaxExtended = 15;

// The second-order term of the Taylor coefficients 0..order over the set m + C rho + P(rho) +
// B r inside y, with the quadratic forms of orders 0..quadratic_order over (rho, r_L) (n + |L|
// <= kMaxExtended; e_all = B r + P(r0), e_quadratic = P(r0)): the direction is delta = C rho +
// B r + e, the QuadJet runs on the coordinates (rho (all n), r_l for l in `live`), so that the
// products of first-order terms with B r are kept as a form too (the field's large terms cancel
// in them as in the rho terms). B's columns outside `live` must meet r entries that are exactly
// 0 (the constant components). forms (sized as by second_order_coefficients): the rho-rho block;
// d2e: the jets' d2e plus the range of the blocks with r over (r0, r).
void second_order_extended(const Tape& tape, const Box& y, const Matrix& c, const Matrix& b,
                           const std::vector<std::size_t>& live, const std::vector<Interval>& r0,
                           const std::vector<Interval>& r, const std::vector<Interval>& e_quadratic,
                           const std::vector<Interval>& e_all, int order, int quadratic_order,
                           std::vector<Interval>& second, std::vector<Interval>& forms,
                           std::vector<Interval>& d2e);

}  // namespace furuta::validated::detail
