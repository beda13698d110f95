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
#include <optional>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "reason.hpp"
#include "shrink_wrap.hpp"
#include "taylor_model_flow_core.hpp"

namespace furuta::validated {

using detail::IMatrix;
using detail::Matrix;

namespace {

constexpr std::size_t kN = detail::kMaxDimension;

bool is_bounded(const Box& b) {
  return std::all_of(b.begin(), b.end(), [](const Interval& x) { return x.is_bounded(); });
}

// The box of p(z) + B r.
Box box_of(const std::vector<TaylorModel>& p, const Matrix& b, const std::vector<Interval>& r) {
  const std::vector<Interval> br = detail::from_point(b) * r;
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
// (docs/measurements/taylor-model-flow.md, "Taylor models II", compares them with the range
// sampled over the set).
void tighten_jacobians(TaylorRunner<Grad<kN, TaylorModel>>& runner, const Tape& tape,
                       const std::vector<TaylorModel>& p, const Matrix& b,
                       const std::vector<Interval>& r,
                       const std::shared_ptr<const MonomialSpace>& jacobian_space, int k,
                       const Interval& hi, IMatrix& j, IMatrix& j_over) {
  const std::size_t n = p.size();
  const std::vector<Interval> br = detail::from_point(b) * r;
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

Tube as_tube(const TaylorModelFlowResult& result) {
  Tube tube;
  tube.dimension = result.initial.size();
  tube.t_start = result.t_start;
  tube.initial = result.initial;
  tube.r0 = std::vector<Interval>(result.initial.size());
  for (std::size_t i = 0; i < result.initial.size(); ++i) {
    tube.r0[i] = result.initial[i] - Interval(result.initial[i].mid());
  }
  tube.steps.reserve(result.steps.size());
  for (const TaylorModelFlowStep& s : result.steps) {
    TubeStep& step = tube.steps.emplace_back();
    step.t0 = s.t0;
    step.t1 = s.t1;
    step.h = Interval(s.t1) - Interval(s.t0);
    step.apriori = s.over;
    step.over = s.over;
    step.end = s.end;
  }
  return tube;
}

namespace detail {

TaylorModelFlowSetup::TaylorModelFlowSetup(const std::vector<Tape>& tapes_,
                                           const std::vector<double>& switches_, const Box& x0,
                                           const TaylorModelFlowOptions& options_)
    : tapes(tapes_), switches(switches_), options(options_), n(x0.size()) {
  const IntegratorOptions& o = options.integrator;
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
  space = std::make_shared<const MonomialSpace>(n, options.space_order);
  jacobian_space = std::make_shared<const MonomialSpace>(n, options.jacobian_order);
  // The start variables the error part can be wrapped into: the live components' own.
  for (std::size_t v : LiveSet(tapes, n).live) {
    if (!x0[v].is_point()) wrap_slots.push_back(v);
  }
}

TaylorModelFlowState initial_flow_state(const TaylorModelFlowSetup& setup, const Box& x0) {
  const std::size_t n = setup.n;
  TaylorModelFlowState state{
      {},
      Matrix::Identity(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n)),
      std::vector<Interval>(n, Interval(0.0)),
      LiveSet(setup.tapes, n)};
  for (std::size_t v = 0; v < n; ++v) {
    state.p.push_back(x0[v].is_point() ? TaylorModel(setup.space, x0[v])
                                       : TaylorModel::variable(setup.space, v, x0[v]));
  }
  // The start's rounding (mid and rad of each component) goes into the error part at once.
  for (std::size_t v = 0; v < n; ++v) {
    state.r[v] = state.p[v].remainder();
    state.p[v] = state.p[v].polynomial();
  }
  if (state.live.live.size() < n && !confined_to_live(state.b, state.r, state.live.is_live)) {
    state.live.all();
  }
  state.t = setup.options.integrator.t_start;
  state.h_next = setup.options.integrator.h_initial;
  return state;
}

std::optional<TaylorModelFlowFailure> taylor_model_flow_step(const TaylorModelFlowSetup& setup,
                                                             TaylorModelFlowRunners& runners,
                                                             TaylorModelFlowState& state,
                                                             TaylorModelFlowResult& result) {
  const TaylorModelFlowOptions& options = setup.options;
  const IntegratorOptions& o = options.integrator;
  const std::size_t n = setup.n;
  const std::vector<TaylorModel>& p = state.p;
  const int k = o.order;
  const std::size_t piece = piece_at(setup.switches, state.t);
  const Tape& tape = setup.tapes[piece];
  const double t_limit =
      std::min(o.t_end, piece < setup.switches.size() ? setup.switches[piece] : o.t_end);
  const Box x = box_of(p, state.b, state.r);
  const StepEnclosure enclosure =
      enclose_step(runners.intervals, tape, x, state.t, t_limit, state.h_next, o, result.rejected);
  if (!enclosure.failure.empty()) {
    return TaylorModelFlowFailure{IntegrationResult::Status::step_not_validated, enclosure.failure};
  }
  const Interval& hi = enclosure.hi;
  const Interval s_over(0.0, hi.hi());

  // The Taylor map of the polynomial part, in Taylor models; its Jacobian over the set's box.
  runners.models.run(tape, p, k);
  std::vector<Grad<kN>> g(n);
  for (std::size_t v = 0; v < n; ++v) g[v] = Grad<kN>::variable(x[v], v);
  runners.gradients.run(tape, g, k);

  std::vector<TaylorModel> p_next(n);
  std::vector<Interval> rest(n);
  IMatrix j(n);
  IMatrix j_over(n);  // over s in [0, h], for the box over the step
  Box over(n);
  for (std::size_t v = 0; v < n; ++v) {
    TaylorModel sum = runners.models.coefficient(v, k);
    Interval sum_over = runners.models.coefficient(v, k).bound();
    for (int i = k - 1; i >= 0; --i) {
      sum = sum * hi + runners.models.coefficient(v, i);
      sum_over = sum_over * s_over + runners.models.coefficient(v, i).bound();
    }
    if (state.live.is_live[v]) {
      rest[v] = sum.remainder() + enclosure.remainder[v];
      p_next[v] = sum.polynomial();
    } else {
      // A constant component keeps its remainder in p (its value does not change, so p's own
      // remainder holds it at t1): in the error part it would end the confined frame.
      rest[v] = enclosure.remainder[v];
      p_next[v] = std::move(sum);
    }
    over[v] = sum_over + pow(s_over, k + 1) * enclosure.remainder_coefficient[v];
    for (std::size_t w = 0; w < n; ++w) {
      std::tie(j(v, w), j_over(v, w)) = at_and_over<Interval>(
          [&](int i) { return runners.gradients.coefficient(v, i).d[w]; }, k, hi);
    }
  }
  if (options.jacobian_order > 0) {
    tighten_jacobians(runners.model_gradients, tape, p, state.b, state.r, setup.jacobian_space, k,
                      hi, j, j_over);
  }
  const IMatrix jb = j * from_point(state.b);
  const std::vector<Interval> br_over = (j_over * from_point(state.b)) * state.r;
  for (std::size_t v = 0; v < n; ++v) {
    over[v] = intersect(over[v] + br_over[v], enclosure.apriori[v]);
  }
  LiveSet live = state.live;
  Frame frame = choose_frame(j, jb, state.r, rest, live, o.max_inflation);

  TaylorModelFlowStep step;
  step.t0 = state.t;
  step.t1 = enclosure.t1;
  step.over = over;
  step.end = intersect(box_of(p_next, frame.b, frame.r), over);
  for (const Interval& e : frame.box)
    step.remainder_width = std::max(step.remainder_width, e.width());
  if (step.end.is_empty()) {
    return TaylorModelFlowFailure{
        IntegrationResult::Status::step_not_validated,
        "empty enclosure at t = " + describe(step.t1) + " (internal error)"};
  }
  const double width = is_bounded(step.end) ? step.end.max_width() : HUGE_VAL;
  if (!(width <= o.max_width)) {
    return TaylorModelFlowFailure{IntegrationResult::Status::width_exceeded,
                                  "enclosure width " + describe(width) + " > max_width " +
                                      describe(o.max_width) + " at t = " + describe(step.t1),
                                  widest_component(step.end, o.max_width, step.t1)};
  }
  if (options.keep_end_models) {
    const std::vector<Interval> error = from_point(frame.b) * frame.r;
    step.end_models = p_next;
    for (std::size_t v = 0; v < n; ++v) step.end_models[v].add_to_remainder(error[v]);
  }
  result.steps.push_back(std::move(step));
  state.wrapped = false;
  if (options.shrink_wrap_max_delta > 0.0) {
    const ShrinkWrap wrap =
        shrink_wrap(p_next, frame.box, live.live, setup.wrap_slots, options.shrink_wrap_max_delta,
                    options.wrap_without_collapsed, options.wrap_at_base_point);
    if (wrap.done) {
      result.steps.back().wrapped = true;
      result.steps.back().wrap_scale = wrap.scale;
      result.steps.back().wrap_delta = wrap.delta;
      ++result.shrink_wraps;
      result.partial_wraps += wrap.kept < setup.wrap_slots.size();
      state.wrapped = wrap.kept >= setup.wrap_slots.size();
      frame.b = Matrix::Identity(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
      frame.r = wrap.rest;
    }
  }
  state.p = std::move(p_next);
  state.b = std::move(frame.b);
  state.r = std::move(frame.r);
  state.live = std::move(live);
  state.t = enclosure.t1;
  state.h_next = next_step_size(enclosure, state.h_next, o);
  return std::nullopt;
}

}  // namespace detail

TaylorModelFlowResult integrate_taylor_models(const std::vector<Tape>& tapes,
                                              const std::vector<double>& switches, const Box& x0,
                                              const TaylorModelFlowOptions& options) {
  const detail::TaylorModelFlowSetup setup(tapes, switches, x0, options);
  const auto started = std::chrono::steady_clock::now();
  TaylorModelFlowResult result;
  result.initial = x0;
  result.t_start = options.integrator.t_start;
  detail::TaylorModelFlowState state = detail::initial_flow_state(setup, x0);
  detail::TaylorModelFlowRunners runners;
  while (state.t < options.integrator.t_end) {
    if (auto failure = detail::taylor_model_flow_step(setup, runners, state, result)) {
      result.status = failure->status;
      result.reason = std::move(failure->reason);
      result.width_stop = failure->width;
      break;
    }
  }
  result.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return result;
}

}  // namespace furuta::validated
