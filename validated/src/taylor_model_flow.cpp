// Validated integration with the set as a Taylor model plus Lohner's error part (see
// taylor_model_flow.hpp). Why it is sound, one step from t to t1 = t + h:
//   every solution is at t in y + d, y = p(z) (z its start's normalised deviation), d = B r;
//   x(t1) = T(y + d) + L, T the order-k Taylor map and L = h^(k+1) x_[k+1](A), A the a priori box
//   over the step; T(y + d) = T(y) + J d with J the Taylor map's Jacobian at points between y and
//   y + d (mean value theorem, row by row), enclosed over the box of the set and, cut by it, as
//   Taylor models in z; T(y) is in the Taylor models' polynomial at z plus their remainders e. So
//   x(t1) is in p'(z) + (J B r + e + L), and Lohner's step writes the bracket as B' r' with
//   r' = (B'^-1 J B) r + B'^-1 (e + L), B'^-1 enclosed. Shrink wrapping (shrink_wrap.cpp) may
//   then replace p'(z) + B' r' by p'(q z_s, z_theta) + (its rounding).

#include "furuta/validated/taylor_model_flow.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "a_priori.hpp"
#include "interval_matrix.hpp"
#include "jets.hpp"
#include "lohner_frame.hpp"
#include "reason.hpp"
#include "shrink_wrap.hpp"

namespace furuta::validated {

using internal::IMatrix;
using internal::Matrix;

namespace {

constexpr std::size_t kN = internal::kMaxDimension;

bool is_bounded(const Box& b) {
  return std::all_of(b.begin(), b.end(), [](const Interval& x) { return x.is_bounded(); });
}

// The box of p(z) + B r.
Box box_of(const std::vector<TaylorModel>& p, const Matrix& b, const std::vector<Interval>& r) {
  const std::vector<Interval> br = internal::from_point(b) * r;
  Box x(p.size());
  for (std::size_t v = 0; v < p.size(); ++v) x[v] = p[v].bound() + br[v];
  return x;
}

// sum_i c(i) s^i for i = 0..k (Horner) at s = h and over s in [0, h]: a Jacobian entry of the
// Taylor map from its Taylor coefficients' derivatives.
template <class T, class Coefficient>
std::pair<T, T> at_and_over(const Coefficient& c, int k, const Interval& h) {
  const Interval s_over(0.0, h.hi());
  T at = c(k);
  T over = at;
  for (int i = k - 1; i >= 0; --i) {
    at = at * h + c(i);
    over = over * s_over + c(i);
  }
  return {at, over};
}

// J (over the step's end) and J over [0, h] cut by the same Jacobians as Taylor models in z: the
// Taylor map's gradient run from p(z) + [0, 1] B r, p reduced to `jacobian_space`, and each entry
// bounded over z. The interval run evaluates the field over the set's box, where the components'
// dependence on each other and on the parameters is lost; this one keeps it to the first order
// (bench/README.md, "Taylor models II", compares them with the range sampled over the set).
void tighten_jacobians(TaylorRunner<Grad<kN, TaylorModel>>& runner, const Tape& tape,
                       const std::vector<TaylorModel>& p, const Matrix& b,
                       const std::vector<Interval>& r,
                       const std::shared_ptr<const MonomialSpace>& jacobian_space, int k,
                       const Interval& hi, IMatrix& j, IMatrix& j_over) {
  const std::size_t n = p.size();
  const std::vector<Interval> br = internal::from_point(b) * r;
  std::vector<Grad<kN, TaylorModel>> g(n);
  for (std::size_t v = 0; v < n; ++v) {
    TaylorModel x = p[v].reduced_to(jacobian_space);
    x.add_to_remainder(hull(Interval(0.0), br[v]));
    g[v] = Grad<kN, TaylorModel>::variable(x, v);
  }
  runner.run(tape, g, k);
  for (std::size_t v = 0; v < n; ++v) {
    for (std::size_t w = 0; w < n; ++w) {
      const auto [at, over] =
          at_and_over<TaylorModel>([&](int i) { return runner.coefficient(v, i).d[w]; }, k, hi);
      j(v, w) = intersect(j(v, w), at.bound());
      j_over(v, w) = intersect(j_over(v, w), over.bound());
    }
  }
}

}  // namespace

Box TaylorModelFlowResult::enclosure_at(double t) const {
  const std::size_t n = initial.size();
  if (!(t >= t_start && t <= t_reached())) return Box(n, Interval::empty());
  if (t == t_start) return initial;
  const auto it =
      std::lower_bound(steps.begin(), steps.end(), t,
                       [](const TaylorModelFlowStep& s, double time) { return s.t1 < time; });
  return it->t1 == t ? it->end : it->over;
}

TaylorModelFlowResult integrate_taylor_models(const std::vector<Tape>& tapes,
                                              const std::vector<double>& switches, const Box& x0,
                                              const TaylorModelFlowOptions& options) {
  const IntegratorOptions& o = options.integrator;
  const std::size_t n = x0.size();
  if (n == 0 || n > kN) throw std::invalid_argument("x0: dimension must be 1..16");
  if (x0.is_empty() || !is_bounded(x0)) throw std::invalid_argument("x0: empty or unbounded");
  if (tapes.size() != switches.size() + 1) throw std::invalid_argument("tapes: one per piece");
  for (const Tape& t : tapes) {
    if (t.dimension != n) throw std::invalid_argument("tapes: dimension differs from x0");
  }
  if (o.order < 1 || o.order > 40) throw std::invalid_argument("options.order: 1..40");
  if (!(o.h_min > 0.0) || !(o.h_max >= o.h_min) || !(o.h_initial >= o.h_min)) {
    throw std::invalid_argument("options.h_min, h_max, h_initial: 0 < h_min <= h_initial, h_max");
  }
  if (!std::isfinite(o.t_start) || !std::isfinite(o.t_end) || o.t_end < o.t_start) {
    throw std::invalid_argument("options.t_start, t_end: finite, t_start <= t_end");
  }
  if (options.jacobian_order < 0 || options.jacobian_order > options.space_order) {
    throw std::invalid_argument("options.jacobian_order: 0..space_order");
  }
  const auto space = std::make_shared<const MonomialSpace>(n, options.space_order);
  const auto jacobian_space = std::make_shared<const MonomialSpace>(n, options.jacobian_order);

  const auto started = std::chrono::steady_clock::now();
  TaylorModelFlowResult result;
  result.initial = x0;
  result.t_start = o.t_start;
  auto finish = [&](IntegrationResult::Status status, std::string reason) {
    result.status = status;
    result.reason = std::move(reason);
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return result;
  };

  std::vector<TaylorModel> p;
  for (std::size_t v = 0; v < n; ++v) {
    p.push_back(x0[v].is_point() ? TaylorModel(space, x0[v])
                                 : TaylorModel::variable(space, v, x0[v]));
  }
  // The start's rounding (mid and rad of each component) goes into the error part at once.
  std::vector<Interval> r(n, Interval(0.0));
  for (std::size_t v = 0; v < n; ++v) {
    r[v] = p[v].remainder();
    p[v] = p[v].polynomial();
  }
  Matrix b = Matrix::Identity(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  internal::LiveSet live(tapes, n);
  if (live.live.size() < n && !internal::confined_to_live(b, r, live.is_live)) live.all();

  // The start variables the error part can be wrapped into: the live components' own.
  std::vector<std::size_t> wrap_slots;
  for (std::size_t v : live.live) {
    if (!x0[v].is_point()) wrap_slots.push_back(v);
  }
  TaylorRunner<Interval> runner;
  TaylorRunner<TaylorModel> models;
  TaylorRunner<Grad<kN>> gradients;
  TaylorRunner<Grad<kN, TaylorModel>> model_gradients;
  const int k = o.order;
  double t = o.t_start;
  double h_next = o.h_initial;
  while (t < o.t_end) {
    const std::size_t piece = piece_at(switches, t);
    const Tape& tape = tapes[piece];
    const double t_limit = std::min(o.t_end, piece < switches.size() ? switches[piece] : o.t_end);
    const Box x = box_of(p, b, r);
    const internal::StepEnclosure enclosure =
        internal::enclose_step(runner, tape, x, t, t_limit, h_next, o, result.rejected);
    if (!enclosure.failure.empty()) {
      return finish(IntegrationResult::Status::step_not_validated, enclosure.failure);
    }
    const Interval& hi = enclosure.hi;
    const Interval s_over(0.0, hi.hi());

    // The Taylor map of the polynomial part, in Taylor models; its Jacobian over the set's box.
    models.run(tape, p, k);
    std::vector<Grad<kN>> g(n);
    for (std::size_t v = 0; v < n; ++v) g[v] = Grad<kN>::variable(x[v], v);
    gradients.run(tape, g, k);

    std::vector<TaylorModel> p_next(n);
    std::vector<Interval> rest(n);
    IMatrix j(n);
    IMatrix j_over(n);  // over s in [0, h], for the box over the step
    Box over(n);
    for (std::size_t v = 0; v < n; ++v) {
      TaylorModel sum = models.coefficient(v, k);
      Interval sum_over = models.coefficient(v, k).bound();
      for (int i = k - 1; i >= 0; --i) {
        sum = sum * hi + models.coefficient(v, i);
        sum_over = sum_over * s_over + models.coefficient(v, i).bound();
      }
      rest[v] = sum.remainder() + enclosure.remainder[v];
      p_next[v] = sum.polynomial();
      over[v] = sum_over + pow(s_over, k + 1) * enclosure.remainder_coefficient[v];
      for (std::size_t w = 0; w < n; ++w) {
        std::tie(j(v, w), j_over(v, w)) =
            at_and_over<Interval>([&](int i) { return gradients.coefficient(v, i).d[w]; }, k, hi);
      }
    }
    if (options.jacobian_order > 0) {
      tighten_jacobians(model_gradients, tape, p, b, r, jacobian_space, k, hi, j, j_over);
    }
    const IMatrix jb = j * internal::from_point(b);
    const std::vector<Interval> br_over = (j_over * internal::from_point(b)) * r;
    for (std::size_t v = 0; v < n; ++v) {
      over[v] = intersect(over[v] + br_over[v], enclosure.apriori[v]);
    }
    internal::Frame frame = internal::choose_frame(j, jb, r, rest, live, o.max_inflation);

    TaylorModelFlowStep step;
    step.t0 = t;
    step.t1 = enclosure.t1;
    step.over = over;
    step.end = intersect(box_of(p_next, frame.b, frame.r), over);
    for (const Interval& e : frame.box)
      step.remainder_width = std::max(step.remainder_width, e.width());
    if (step.end.is_empty()) {
      return finish(IntegrationResult::Status::step_not_validated,
                    "empty enclosure at t = " + internal::describe(step.t1) + " (internal error)");
    }
    const double width = is_bounded(step.end) ? step.end.max_width() : HUGE_VAL;
    if (!(width <= o.max_width)) {
      return finish(IntegrationResult::Status::width_exceeded,
                    "enclosure width " + internal::describe(width) + " > max_width " +
                        internal::describe(o.max_width) + " at t = " + internal::describe(step.t1));
    }
    result.steps.push_back(std::move(step));
    if (options.shrink_wrap_max_delta > 0.0) {
      const internal::ShrinkWrap wrap =
          internal::shrink_wrap(p_next, frame.box, live.live, wrap_slots,
                                options.shrink_wrap_max_delta, options.wrap_without_collapsed);
      if (wrap.done) {
        ++result.shrink_wraps;
        result.partial_wraps += wrap.kept < wrap_slots.size();
        frame.b = Matrix::Identity(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
        frame.r = wrap.rest;
      }
    }
    p = std::move(p_next);
    b = std::move(frame.b);
    r = std::move(frame.r);
    t = enclosure.t1;
    h_next = internal::next_step_size(enclosure, h_next, o);
  }
  return finish(IntegrationResult::Status::ok, "");
}

}  // namespace furuta::validated
