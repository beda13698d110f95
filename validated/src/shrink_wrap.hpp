#pragma once
// Shrink wrapping (Makino and Berz) for the Taylor-model flow: the error part B r taken into the
// polynomial by widening its start variables, so that it is carried with the flow's dependence on
// every variable instead of through an interval Jacobian. Internal to the validated library.

#include <Eigen/Dense>
#include <cstddef>
#include <optional>
#include <vector>

#include "furuta/interval/interval.hpp"
#include "furuta/validated/taylor_model.hpp"
#include "interval_matrix.hpp"

namespace furuta::validated::detail {

struct ShrinkWrap {
  bool done = false;
  std::vector<Interval> rest;  // the new error part (identity frame)
  // The slot (index into slots) left out when the whole error part could not be wrapped: its
  // start variable keeps its scale and the error along its own row stays in `rest`.
  std::size_t kept = static_cast<std::size_t>(-1);
  // Per variable, when done: the widening q (p is now p(q z)) and delta, such that a point z of
  // the variables before the wrap (with its error) is p(q z') for some z' with q z' - z in
  // [-delta, delta] (Krawczyk's fixed point); 1 and 0 for the variables left alone.
  std::vector<double> scale, delta;
};

// The slots' linear coefficients in the rows, L (entry i, j: p[rows[i]]'s coefficient of
// z_slots[j]; p's space not null); the column of slot `kept` (unless -1) is its row's unit
// vector times `scale`.
Eigen::MatrixXd linear_part(const std::vector<TaylorModel>& p, const std::vector<std::size_t>& rows,
                            const std::vector<std::size_t>& slots,
                            std::size_t kept = static_cast<std::size_t>(-1), double scale = 0.0);

// L^-1, or nothing when L is numerically singular: the slots' columns dependent, as after the
// arm's velocity has relaxed, when the four start columns lie in the three slow directions, and
// L^-1 is no useful preconditioner.
std::optional<Eigen::MatrixXd> linear_part_inverse(const std::vector<TaylorModel>& p,
                                                   const std::vector<std::size_t>& rows,
                                                   const std::vector<std::size_t>& slots,
                                                   std::size_t kept = static_cast<std::size_t>(-1),
                                                   double scale = 0.0);

// For p (polynomials on `rows`; the other components may keep a remainder, which stays in p) and
// the error part e (an interval per component, 0 off `rows`): q with p(q z_s, z_theta) + rest
// holding p(z) + e for every z and every e in e, where z_s are the variables `slots` (as many as
// `rows`, p's rows `rows` depend on them linearly through an invertible matrix) and q_i = 1 +
// delta_i. It is found by Krawczyk's argument: with A ~ L^-1 (L the slots' linear coefficients in
// the rows), G(z') = z' - A (p(z') - p(z) - e) maps z + [-delta, delta] into itself when |I - A M|
// delta + |A e| < delta, M the slots' derivatives over the widened box; a fixed point solves p(z')
// = p(z) + e (shrink_wrap.cpp says why). When that fails and `leave_out_slot` is set, once more
// with one slot left out (its column replaced by its row's unit vector, whose part stays in the
// error part): the slot whose leaving out needs the least widening, then the next. The slot to
// leave out is the one whose column has become dependent on the others: the Furuta arm's velocity,
// which decays at 150-230 /s and leaves its start's influence in the pendulum's slow directions, so
// that the four start columns span three; neither short nor long decides it. Nothing is done (done
// = false) when no delta <= max_delta passes; p is rescaled in place when done.
// With `at_base_point`, each attempt first takes A as a function of every variable, A(z) ~
// (p's slot derivatives at z)^-1, so that I - A M is left with the derivatives' change within
// delta of z only, instead of their spread over the whole box; the attempt over the box when it
// does not pass.
ShrinkWrap shrink_wrap(std::vector<TaylorModel>& p, const std::vector<Interval>& e,
                       const std::vector<std::size_t>& rows, const std::vector<std::size_t>& slots,
                       double max_delta, bool leave_out_slot, bool at_base_point = false);

}  // namespace furuta::validated::detail
