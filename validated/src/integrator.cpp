// The validated integrator (see validated/README.md). The set of solutions at t is kept as a
// doubleton m + C r0 + B r (m a point, C and B point matrices, r0 = x0 - mid(x0) fixed, r an
// interval vector). One step from t to t + h:
//
//  1. a priori enclosure A of every solution over [t, t + h] (Picard-Lindelof: X + [0, h] f(A~)
//     inside the interior of A~, A~ inflated from the previous Picard image; h halved until it
//     validates; X the box of the set);
//  2. Lagrange remainder R = h^(k+1) x_[k+1](A) (Taylor coefficient k+1 over A);
//  3. the Taylor map at the centre, T(m) = sum_i h^i x_[i](m), and its Jacobian J = sum_i h^i
//     V_[i](m) (forward-mode gradients of the coefficients; thin, m is a point);
//  4. the second-order term q = sum_i h^i q_i, q_i = half the second derivative of x_[i] along
//     delta = C rho + e (rho in r0, e in B r) over X (second-order jets, the direction carried as
//     a linear form in rho), so that T(x0) is in T(m) + J (C rho + B r) + q. With the quadratic
//     model (options.quadratic_model) the set is m + C rho + P(rho) + B r, P a quadratic form
//     in rho per component (point coefficients): the jets of orders 0..quadratic_order carry the
//     second-order term as a quadratic form over the coordinates (rho, r_L) (n + |L| <= 15; else
//     rho only; L the live components, below), the rho-rho block's midpoint, with J P, becomes
//     P', and only the variation of its coefficients over the set (third order), the blocks with
//     r, the terms with P(r0) and the higher orders' second-order terms go into the error part;
//  5. Lohner: z = T(m) + q + R, m' = mid(z), C' = mid(J C), B' = mid(J B) (parallelepiped) while
//     its condition number is small, else Q of the QR factorisation of mid(J B) (columns pivoted
//     by length times the width of r); r' = (B'^-1 J B) r + B'^-1 (z - m' + (J C - C') r0), with
//     an interval enclosure of B'^-1. The tight enclosure is m' + C' r0 + B' r' intersected with
//     z + J C r0 + J B r. Components whose derivative is the constant 0 (parameters carried as
//     state) get no error part: B = blockdiag(B_LL, I), r = (r_L, 0), the frame chosen on the
//     live block L alone (checked each step: their rows of J exact unit rows, their rest 0).
//
// The interval matrices (interval_matrix.hpp), the quadratic forms in rho (quadratic_form.hpp),
// the Horner evaluation of the Taylor form (taylor_form.hpp), the jets of the Taylor
// coefficients (jets.hpp), the a priori enclosure (a_priori.hpp), the frame of the error part
// and the live components (lohner_frame.hpp) and the set at a step boundary with a run's start
// and restart (doubleton.hpp) are in files of their own in this directory.

#include "furuta/validated/integrator.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <optional>
#include <sstream>
#include <utility>

#include "a_priori.hpp"
#include "doubleton.hpp"
#include "interval_matrix.hpp"
#include "jets.hpp"
#include "lohner_frame.hpp"
#include "quadratic_form.hpp"
#include "taylor_form.hpp"

namespace furuta::validated {
namespace {

using internal::a_priori;
using internal::centre_coefficients;
using internal::confined_to_live;
using internal::constant_rows_exact;
using internal::Doubleton;
using internal::form_range;
using internal::forms_range;
using internal::from_point;
using internal::horner;
using internal::IMatrix;
using internal::inflation;
using internal::kMaxDimension;
using internal::kMaxExtended;
using internal::live_components;
using internal::Lohner;
using internal::lohner_candidate;
using internal::Matrix;
using internal::mid;
using internal::pair_count;
using internal::qr_frame;
using internal::second_order_coefficients;
using internal::second_order_extended;

constexpr double kInf = std::numeric_limits<double>::infinity();
// Components whose exact part is below this fraction of the widest one are left out of the
// excess ratio: a component that the flow contracts (the damped arm speed) has a tiny exact
// part, and its error part's ratio to it says nothing about the set.
constexpr double kExcessFloor = 0.05;

bool is_bounded(const Box& b) {
  return std::all_of(b.begin(), b.end(), [](const Interval& x) { return x.is_bounded(); });
}

// ---- A priori enclosure -------------------------------------------------------------------------

std::string describe(double value) {
  std::ostringstream out;
  out.precision(17);
  out << value;
  return out.str();
}

void validate(const std::vector<Tape>& tapes, const std::vector<double>& switches, const Box& x0,
              const IntegratorOptions& o) {
  const std::size_t n = x0.size();
  if (n == 0 || n > kMaxDimension) throw std::invalid_argument("x0: dimension must be 1..16");
  if (x0.is_empty() || !is_bounded(x0)) throw std::invalid_argument("x0: empty or unbounded");
  if (tapes.size() != switches.size() + 1) throw std::invalid_argument("tapes: one per piece");
  for (const Tape& t : tapes) {
    if (t.dimension != n) throw std::invalid_argument("tapes: dimension differs from x0");
  }
  if (!std::is_sorted(switches.begin(), switches.end())) {
    throw std::invalid_argument("switches: not sorted");
  }
  if (o.order < 1 || o.order > 40) throw std::invalid_argument("options.order: 1..40");
  if (!(o.tolerance > 0.0)) throw std::invalid_argument("options.tolerance: > 0");
  if (!(o.h_min > 0.0) || !(o.h_max >= o.h_min) || !(o.h_initial >= o.h_min)) {
    throw std::invalid_argument("options.h_min, h_max, h_initial: 0 < h_min <= h_initial, h_max");
  }
  if (!(o.max_width > 0.0)) throw std::invalid_argument("options.max_width: > 0");
  if (!(o.max_excess > 0.0)) throw std::invalid_argument("options.max_excess: > 0");
  if (!(o.max_inflation >= 1.0)) throw std::invalid_argument("options.max_inflation: >= 1");
  if (o.quadratic_order < -1) throw std::invalid_argument("options.quadratic_order: >= -1");
  if (!std::isfinite(o.t_start) || !std::isfinite(o.t_end) || o.t_end < o.t_start) {
    throw std::invalid_argument("options.t_start, t_end: finite, t_start <= t_end");
  }
}

}  // namespace

double excess_ratio(const std::vector<double>& exact, const std::vector<double>& error) {
  const double largest = exact.empty() ? 0.0 : *std::max_element(exact.begin(), exact.end());
  double ratio = 0.0;
  for (std::size_t v = 0; v < exact.size() && v < error.size(); ++v) {
    if (exact[v] > kExcessFloor * largest) ratio = std::max(ratio, error[v] / exact[v]);
  }
  return ratio;
}

const char* to_string(IntegrationResult::Status status) {
  switch (status) {
    case IntegrationResult::Status::ok:
      return "ok";
    case IntegrationResult::Status::step_not_validated:
      return "step_not_validated";
    case IntegrationResult::Status::width_exceeded:
      return "width_exceeded";
  }
  return "unknown";
}

Box Tube::step_form(std::size_t index, const Interval& s) const {
  const TubeStep& step = steps.at(index);
  const std::size_t n = dimension;
  const auto k = static_cast<std::size_t>(order);
  // V(s) = sum_i s^i V_i by Horner.
  IMatrix v(n);
  std::copy(step.jacobian.begin() + static_cast<std::ptrdiff_t>(k * n * n),
            step.jacobian.begin() + static_cast<std::ptrdiff_t>((k + 1) * n * n), v.v.begin());
  for (std::size_t i = k; i-- > 0;) {
    for (std::size_t e = 0; e < n * n; ++e) v.v[e] = v.v[e] * s + step.jacobian[i * n * n + e];
  }
  const std::vector<Interval>& step_r0 = step.r0.empty() ? r0 : step.r0;
  const std::vector<Interval> linear0 = (v * from_point(n, step.c)) * step_r0;
  const std::vector<Interval> linear = (v * from_point(n, step.b)) * step.r;
  // The quadratic part of the set at t0 (P(r0), if any), through V(s) as the rest.
  const std::vector<Interval> quadratic = v * forms_range(step.quad, step_r0);
  const Interval s_k1 = pow(s, order + 1);
  Box out(n);
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = horner(step.centre, n, i, order, s) + horner(step.second, n, i, order, s) +
             linear0[i] + quadratic[i] + linear[i] + s_k1 * step.remainder[i];
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

namespace {

// Integrates from `state` on, appending the steps to `tube` (which already covers
// [tube.t_start, state.t]).
IntegrationResult run(const std::vector<Tape>& tapes, const std::vector<double>& switches,
                      Tube tube, Doubleton state, const IntegratorOptions& options) {
  const auto started = std::chrono::steady_clock::now();
  const std::size_t n = tube.dimension;
  const auto en = static_cast<Eigen::Index>(n);
  const int k = options.order;
  const auto uk = static_cast<std::size_t>(k);
  const double root = 1.0 / (k + 1);

  IntegrationResult result;
  result.tube = std::move(tube);
  Tube& tube_out = result.tube;
  auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  };
  auto finish = [&](IntegrationResult::Status status, double t, std::string reason) {
    result.status = status;
    result.t_failed = t;
    result.reason = std::move(reason);
    result.seconds = elapsed();
    return result;
  };

  const std::vector<double> origin = std::move(state.origin);
  const std::vector<Interval> r0 = std::move(state.r0);
  std::vector<double> m = std::move(state.m);
  Matrix c = std::move(state.c);
  std::vector<double> quad = std::move(state.p);
  const std::size_t pairs = pair_count(n);
  if (quad.size() != n * pairs) quad.assign(n * pairs, 0.0);
  Matrix b = std::move(state.b);
  std::vector<Interval> r = std::move(state.r);
  Box x = std::move(state.x);
  // The error part B r is kept on the live components (those of nonzero field; the constant
  // ones, parameters carried as state, never get new errors): B = blockdiag(B_LL, I), r_K = 0.
  // The frame is then chosen on the live block alone and the quadratic jets run over (rho, r_L):
  // n + |L| coordinates instead of 2n. Without constant components L is everything (as before).
  // A start that does not have this form (a restart from a tube that fell back), or a step
  // whose constant rows are not exact, falls back to the full frame for the rest of the run.
  std::vector<std::size_t> live = live_components(tapes, n);
  std::vector<bool> is_live(n, false);
  for (std::size_t v : live) is_live[v] = true;
  auto all_live = [&] {
    live.resize(n);
    std::iota(live.begin(), live.end(), std::size_t{0});
    is_live.assign(n, true);
  };
  if (live.size() < n && !confined_to_live(b, r, is_live)) all_live();

  TaylorRunner<Interval> runner;
  double t = state.t;
  double h_next = state.h_next;
  while (t < options.t_end) {
    const std::size_t piece = piece_at(switches, t);
    const Tape& tape = tapes[piece];
    const double t_limit =
        std::min(options.t_end, piece < switches.size() ? switches[piece] : kInf);

    // 1-2. A priori enclosure and remainder; the step shrinks until both are acceptable.
    double h = std::min(h_next, t_limit - t);
    bool capped = h_next >= t_limit - t;  // the step ends at t_limit, not where h_next says
    double t1 = t_limit;
    Interval hi;
    Box apriori;
    std::vector<Interval> remainder_coefficient(n);
    Box remainder(n);
    double remainder_width = 0.0;
    for (;;) {
      t1 = h >= t_limit - t ? t_limit : t + h;
      if (!(t1 > t)) {
        return finish(IntegrationResult::Status::step_not_validated, t,
                      "step below the time resolution at t = " + describe(t));
      }
      hi = Interval(t1) - Interval(t);
      std::optional<Box> enclosure = a_priori(runner, tape, x, hi.hi());
      bool bounded = false;
      if (enclosure) {
        const std::vector<Interval> bs(enclosure->begin(), enclosure->end());
        runner.run(tape, std::span<const Interval>(bs), k + 1);
        const Interval h_k1 = pow(hi, k + 1);
        remainder_width = 0.0;
        bounded = true;
        for (std::size_t v = 0; v < n; ++v) {
          remainder_coefficient[v] = runner.coefficient(v, k + 1);
          remainder[v] = h_k1 * remainder_coefficient[v];
          bounded = bounded && remainder[v].is_bounded();
          remainder_width = std::max(remainder_width, remainder[v].width());
        }
        if (bounded && (remainder_width <= options.tolerance || h <= options.h_min)) {
          apriori = std::move(*enclosure);
          break;
        }
      }
      ++result.rejected;
      if (h <= options.h_min) {
        return finish(IntegrationResult::Status::step_not_validated, t,
                      "no a priori enclosure (Picard) at t = " + describe(t) +
                          " with h = " + describe(h) + " (h_min)");
      }
      double shrink = 0.5;
      if (bounded) {
        shrink = std::clamp(0.9 * std::pow(options.tolerance / remainder_width, root), 0.1, 0.9);
      }
      h = std::max(options.h_min, h * shrink);
      capped = false;
    }

    TubeStep step;
    step.t0 = t;
    step.t1 = t1;
    step.h = hi;
    {
      const Matrix ct = c.transpose();
      const Matrix bt = b.transpose();
      step.c.assign(ct.data(), ct.data() + n * n);
      step.b.assign(bt.data(), bt.data() + n * n);
    }
    step.r = r;
    step.r0 = r0;
    step.origin = origin;
    step.remainder = remainder_coefficient;
    step.quad = quad;

    // 3. Taylor coefficients at the centre m and their Jacobian V_[i](m) (thin: m is a point).
    centre_coefficients(tape, m, k, step.centre, step.jacobian);
    // 4. The second-order term over the set: coefficient s^2 of x_[i](y + s delta) over y in the
    // box (with the centre) and delta in C r0 + B r.
    const IMatrix ci = from_point(c);
    const IMatrix bi = from_point(b);
    // The set at t is m + C rho + P(rho) + B r: the direction's interval part e holds P(r0) and
    // B r (P is zero without the quadratic model).
    const std::vector<Interval> p_range = forms_range(quad, r0);
    std::vector<Interval> forms;
    std::vector<Interval> d2e;
    {
      std::vector<Interval> e = bi * r;
      for (std::size_t v = 0; v < n; ++v) e[v] += p_range[v];
      Box y = x;
      for (std::size_t v = 0; v < n; ++v) y[v] = y[v] | Interval(m[v]);
      if (options.quadratic_model && n + live.size() <= kMaxExtended) {
        second_order_extended(tape, y, c, b, live, r0, r, p_range, e, k, options.quadratic_order,
                              step.second, forms, d2e);
      } else {
        second_order_coefficients(tape, y, c, r0, e, k, options.quadratic_order, step.second,
                                  options.quadratic_model ? &forms : nullptr,
                                  options.quadratic_model ? &d2e : nullptr);
      }
    }
    // J = sum_i h^i V_[i](m).
    IMatrix j(n);
    std::copy(step.jacobian.begin() + static_cast<std::ptrdiff_t>(uk * n * n), step.jacobian.end(),
              j.v.begin());
    for (std::size_t i = uk; i-- > 0;) {
      for (std::size_t e = 0; e < n * n; ++e) j.v[e] = j.v[e] * hi + step.jacobian[i * n * n + e];
    }
    // T(x0) = T(m) + J (C rho + P(rho) + e) + S(rho) + R, S the second-order term. Without the
    // quadratic model S is enclosed by sum_i h^i q_i (its range) and P = 0. With it, S(rho) =
    // Q(rho) + D, Q the quadratic form sum_i h^i forms_i (interval coefficients) and D the
    // interval sum_i h^i d2e_i; the new quadratic part is P'(rho) = mid(J P + Q)(rho) and the
    // coefficients' rest ((J P + Q) - P')(rho) over r0, with D, goes to the error part.
    std::vector<double> p_next(n * pairs, 0.0);
    std::vector<Interval> second_rest(n, Interval(0.0));
    if (options.quadratic_model) {
      std::vector<Interval> coefficients(n * pairs, Interval(0.0));
      for (std::size_t v = 0; v < n; ++v) {
        for (std::size_t a = 0; a < pairs; ++a) {
          Interval sum = forms[(uk * n + v) * pairs + a];
          for (std::size_t i = uk; i-- > 0;) sum = sum * hi + forms[(i * n + v) * pairs + a];
          for (std::size_t w = 0; w < n; ++w) {
            if (quad[w * pairs + a] != 0.0) sum += j(v, w) * Interval(quad[w * pairs + a]);
          }
          p_next[v * pairs + a] = sum.is_bounded() ? sum.mid() : 0.0;
          coefficients[v * pairs + a] = sum - Interval(p_next[v * pairs + a]);
        }
        second_rest[v] = form_range(coefficients.data() + v * pairs, r0) + horner(d2e, n, v, k, hi);
      }
    } else {
      // P is zero unless the run was restarted (integrate_sub_box) from a tube that carried it:
      // then J P(rho) goes into the error part too.
      const std::vector<Interval> image = j * p_range;
      for (std::size_t v = 0; v < n; ++v) {
        second_rest[v] = horner(step.second, n, v, k, hi) + image[v];
      }
    }
    // z: the image of the centre, with what the second-order term leaves and the remainder.
    std::vector<Interval> z(n);
    for (std::size_t v = 0; v < n; ++v) {
      z[v] = horner(step.centre, n, v, k, hi) + second_rest[v] + remainder[v];
    }

    // 5. Lohner's step on the doubleton.
    const IMatrix jc = j * ci;
    const IMatrix jb = j * bi;
    const Matrix c_next = mid(jc);
    // m' = mid(z); the rest of z, with the rounding of C' = mid(J C), goes to the r part.
    std::vector<double> m_next(n);
    std::vector<Interval> rest(n);
    IMatrix jc_error = jc;
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t col = 0; col < n; ++col) {
        jc_error(i, col) -=
            Interval(c_next(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(col)));
      }
    }
    const std::vector<Interval> jc_error_r0 = jc_error * r0;
    for (std::size_t v = 0; v < n; ++v) {
      m_next[v] = z[v].mid();
      rest[v] = z[v] - Interval(m_next[v]) + jc_error_r0[v];
    }
    // B' = mid(J B) (the parallelepiped method: r is not wrapped, only the rest is, through
    // B'^-1) while it is well conditioned, else Q of the QR of mid(J B) with columns pivoted by
    // their length times the width of r (Lohner's QR method); r' = (B'^-1 J B) r + B'^-1 rest.
    // On a field with constant components the frame is chosen on the live block alone (B' =
    // blockdiag(B'_LL, I), r'_K = 0): with r_K = 0 and the constant rows of J exact unit rows,
    // (J B) r + rest is ((J B)_LL r_L + rest_L, 0) exactly.
    if (live.size() < n && !constant_rows_exact(j, rest, is_live)) all_live();
    const std::size_t nl = live.size();
    const auto enl = static_cast<Eigen::Index>(nl);
    IMatrix jb_live(nl);
    std::vector<Interval> r_live(nl);
    std::vector<Interval> rest_live(nl);
    for (std::size_t a = 0; a < nl; ++a) {
      for (std::size_t col = 0; col < nl; ++col) jb_live(a, col) = jb(live[a], live[col]);
      r_live[a] = r[live[a]];
      rest_live[a] = rest[live[a]];
    }
    const Matrix p = mid(jb_live);
    const Matrix p_inv = p.partialPivLu().inverse();
    const double kappa = inflation(p, p_inv);
    Lohner parallelepiped;
    Lohner qr;
    Lohner* chosen = nullptr;
    if (kappa <= options.max_inflation) {
      parallelepiped = lohner_candidate(p, p_inv, jb_live, r_live, rest_live);
      if (parallelepiped.valid) chosen = &parallelepiped;
    }
    if (chosen == nullptr) {
      qr = lohner_candidate(qr_frame(p, r_live), Matrix(), jb_live, r_live, rest_live);
      if (qr.valid) chosen = &qr;
    }
    Lohner identity_frame;
    if (chosen == nullptr) {  // never seen; B' = I keeps the step sound (only wider)
      identity_frame = lohner_candidate(Matrix::Identity(enl, enl), Matrix::Identity(enl, enl),
                                        jb_live, r_live, rest_live);
      chosen = &identity_frame;
    }
    if (chosen == &qr) ++result.qr_steps;
    Matrix b_next = Matrix::Identity(en, en);
    std::vector<Interval> r_next(n, Interval(0.0));
    std::vector<Interval> new1(n, Interval(0.0));
    for (std::size_t a = 0; a < nl; ++a) {
      for (std::size_t col = 0; col < nl; ++col) {
        b_next(static_cast<Eigen::Index>(live[a]), static_cast<Eigen::Index>(live[col])) =
            chosen->b(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(col));
      }
      r_next[live[a]] = chosen->r[a];
      new1[live[a]] = chosen->box[a];
    }
    // The tight enclosure: the new doubleton, intersected with the direct image.
    const std::vector<Interval> new0 = from_point(c_next) * r0;
    const std::vector<Interval> new_quadratic = forms_range(p_next, r0);
    const std::vector<Interval> old0 = jc * r0;
    const std::vector<Interval> old_quadratic = j * p_range;
    const std::vector<Interval> old1 = jb * r;
    Box end(n);
    for (std::size_t v = 0; v < n; ++v) {
      const Interval direct = horner(step.centre, n, v, k, hi) + horner(step.second, n, v, k, hi) +
                              remainder[v] + old0[v] + old_quadratic[v] + old1[v];
      end[v] = (Interval(m_next[v]) + new0[v] + new_quadratic[v] + new1[v]) & direct;
    }

    step.apriori = apriori;
    step.end = end;
    tube_out.steps.push_back(std::move(step));
    TubeStep& stored = tube_out.steps.back();
    stored.over =
        intersect(tube_out.step_form(tube_out.steps.size() - 1, Interval(0.0, hi.hi())), apriori);
    ++result.steps;
    m = std::move(m_next);
    c = c_next;
    quad = std::move(p_next);
    b = std::move(b_next);
    r = std::move(r_next);
    x = std::move(end);
    t = t1;

    if (x.is_empty()) {  // both forms contain every solution: cannot happen unless a bug
      return finish(IntegrationResult::Status::step_not_validated, t,
                    "empty enclosure at t = " + describe(t) + " (internal error)");
    }
    const double width = is_bounded(x) ? x.max_width() : kInf;
    if (!(width <= options.max_width)) {
      return finish(IntegrationResult::Status::width_exceeded, t,
                    "enclosure width " + describe(width) + " > max_width " +
                        describe(options.max_width) + " at t = " + describe(t));
    }
    // The error part against the part carried exactly (the image of r0): when it dominates, the
    // set is no longer followed, only wrapped (a split run then bisects the box).
    if (options.max_excess < kInf) {
      std::vector<double> exact(n);
      std::vector<double> error(n);
      for (std::size_t v = 0; v < n; ++v) {
        exact[v] = (new0[v] + new_quadratic[v]).width();
        error[v] = new1[v].width();
      }
      const double ratio = excess_ratio(exact, error);
      if (ratio > options.max_excess) {
        return finish(IntegrationResult::Status::width_exceeded, t,
                      "error part " + describe(ratio) + " x the exact part (max_excess " +
                          describe(options.max_excess) + ") at t = " + describe(t));
      }
    }
    if (!capped) {
      const double grow =
          remainder_width > 0.0
              ? std::clamp(0.9 * std::pow(options.tolerance / remainder_width, root), 0.25, 2.0)
              : 2.0;
      h_next = std::min(options.h_max, std::max(options.h_min, h * grow));
    }
  }
  result.seconds = elapsed();
  return result;
}

}  // namespace

IntegrationResult integrate_tapes(const std::vector<Tape>& tapes,
                                  const std::vector<double>& switches, const Box& x0,
                                  const IntegratorOptions& options) {
  validate(tapes, switches, x0, options);
  Tube tube;
  tube.dimension = x0.size();
  tube.order = options.order;
  tube.t_start = options.t_start;
  tube.initial = x0;
  Doubleton start = internal::initial_doubleton(x0, options);
  tube.r0 = start.r0;
  return run(tapes, switches, std::move(tube), std::move(start), options);
}

IntegrationResult integrate_sub_box(const std::vector<Tape>& tapes,
                                    const std::vector<double>& switches, const Tube& tube,
                                    std::size_t step, const Box& piece,
                                    const IntegratorOptions& options) {
  validate(tapes, switches, piece, options);
  const std::size_t n = piece.size();
  if (n != tube.dimension || !piece.is_subset(tube.initial)) {
    throw std::invalid_argument("integrate_sub_box: the piece is not a sub-box of tube.initial");
  }
  if (step >= tube.steps.size()) throw std::invalid_argument("integrate_sub_box: no such step");
  if (tube.order != options.order) throw std::invalid_argument("integrate_sub_box: order differs");

  Doubleton state = internal::restart_doubleton(tapes, tube, step, piece, options);
  Tube prefix;
  prefix.dimension = n;
  prefix.order = tube.order;
  prefix.t_start = tube.t_start;
  prefix.initial = piece;
  prefix.r0.resize(n);
  for (std::size_t v = 0; v < n; ++v) prefix.r0[v] = piece[v] - Interval(state.origin[v]);
  prefix.steps.assign(tube.steps.begin(), tube.steps.begin() + static_cast<std::ptrdiff_t>(step));
  return run(tapes, switches, std::move(prefix), std::move(state), options);
}

}  // namespace furuta::validated
