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
// This file holds the run (run(): the outline of a step) and the public entry points; the parts
// are in this directory, one concept each (private headers, see validated/README.md):
// a_priori (steps 1-2 and the step size), jets (the coefficients at the centre and the
// second-order term), step (steps 3-5: the Taylor map and Lohner's update), lohner_frame (the
// frame of the error part, the live components), doubleton (the set at a step boundary, a run's
// start and restart), tube (the Tube's steps and enclosures), interval_matrix, quadratic_form,
// taylor_form.

#include "furuta/validated/integrator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <utility>

#include "a_priori.hpp"
#include "doubleton.hpp"
#include "jets.hpp"
#include "lohner_frame.hpp"
#include "quadratic_form.hpp"
#include "reason.hpp"
#include "step.hpp"
#include "tube.hpp"

namespace furuta::validated {
namespace {

using detail::describe;
using detail::Doubleton;

constexpr double kInf = std::numeric_limits<double>::infinity();
// Components whose exact part is below this fraction of the widest one are left out of the
// excess ratio: a component that the flow contracts (the damped arm speed) has a tiny exact
// part, and its error part's ratio to it says nothing about the set.
constexpr double kExcessFloor = 0.05;

bool is_bounded(const Box& b) {
  return std::all_of(b.begin(), b.end(), [](const Interval& x) { return x.is_bounded(); });
}

void validate(const std::vector<Tape>& tapes, const std::vector<double>& switches, const Box& x0,
              const IntegratorOptions& o) {
  const std::size_t n = x0.size();
  if (n == 0 || n > detail::kMaxDimension)
    throw std::invalid_argument("x0: dimension must be 1..16");
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

WidthStop widest_component(const Box& x, double max_width, double t) {
  WidthStop out{0, 0.0, max_width, t};
  for (std::size_t v = 0; v < x.size(); ++v) {
    const double width = x[v].is_bounded() ? x[v].width() : kInf;
    if (v == 0 || width > out.width) out = WidthStop{v, width, max_width, t};
  }
  return out;
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

namespace {

// Why a run ends at the end of a step, when it does.
struct Stop {
  IntegrationResult::Status status;
  std::string reason;
  std::optional<WidthStop> width = std::nullopt;
};

// The acceptance of the set at the end of a step (`next`, at next.set.t): not empty (both its
// forms contain every solution), within max_width, and its error part within max_excess of its
// exact part.
std::optional<Stop> refused(const detail::LohnerStep& next, const IntegratorOptions& options) {
  const std::size_t n = next.set.m.size();
  const Box& x = next.set.x;
  const double t = next.set.t;
  if (x.is_empty()) {  // both forms contain every solution: cannot happen unless a bug
    return Stop{IntegrationResult::Status::step_not_validated,
                "empty enclosure at t = " + describe(t) + " (internal error)"};
  }
  const double width = is_bounded(x) ? x.max_width() : kInf;
  if (!(width <= options.max_width)) {
    return Stop{IntegrationResult::Status::width_exceeded,
                "enclosure width " + describe(width) + " > max_width " +
                    describe(options.max_width) + " at t = " + describe(t),
                widest_component(x, options.max_width, t)};
  }
  // The error part against the part carried exactly (the image of r0): when it dominates, the
  // set is no longer followed, only wrapped (a split run then bisects the box).
  if (options.max_excess < kInf) {
    std::vector<double> exact(n);
    std::vector<double> error(n);
    for (std::size_t v = 0; v < n; ++v) {
      exact[v] = (next.exact[v] + next.exact_quadratic[v]).width();
      error[v] = next.error[v].width();
    }
    const double ratio = excess_ratio(exact, error);
    if (ratio > options.max_excess) {
      return Stop{IntegrationResult::Status::width_exceeded,
                  "error part " + describe(ratio) + " x the exact part (max_excess " +
                      describe(options.max_excess) + ") at t = " + describe(t)};
    }
  }
  return std::nullopt;
}

// Integrates from `state` on, appending the steps to `tube` (which already covers
// [tube.t_start, state.t]).
IntegrationResult run(const std::vector<Tape>& tapes, const std::vector<double>& switches,
                      Tube tube, Doubleton state, const IntegratorOptions& options) {
  const auto started = std::chrono::steady_clock::now();
  IntegrationResult result;
  result.tube = std::move(tube);
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
  const std::size_t n = result.tube.dimension;
  const std::size_t pairs = detail::pair_count(n);
  if (state.p.size() != n * pairs) state.p.assign(n * pairs, 0.0);
  // The error part B r is kept on the live components (those of nonzero field; the constant
  // ones, parameters carried as state, never get new errors): B = blockdiag(B_LL, I), r_K = 0.
  // The frame is then chosen on the live block alone and the quadratic jets run over (rho, r_L):
  // n + |L| coordinates instead of 2n. Without constant components L is everything (as before).
  // A start that does not have this form (a restart from a tube that fell back), or a step
  // whose constant rows are not exact, falls back to the full frame for the rest of the run.
  detail::LiveSet live(tapes, n);
  if (live.live.size() < n && !detail::confined_to_live(state.b, state.r, live.is_live)) {
    live.all();
  }

  TaylorRunner<Interval> runner;
  while (state.t < options.t_end) {
    const std::size_t piece = piece_at(switches, state.t);
    const Tape& tape = tapes[piece];
    const double t_limit =
        std::min(options.t_end, piece < switches.size() ? switches[piece] : kInf);
    // 1-2. A priori enclosure and remainder; the step shrinks until both are acceptable.
    const detail::StepEnclosure enclosure = detail::enclose_step(
        runner, tape, state.x, state.t, t_limit, state.h_next, options, result.rejected);
    if (!enclosure.failure.empty()) {
      return finish(IntegrationResult::Status::step_not_validated, state.t, enclosure.failure);
    }
    // 3-4. The Taylor map: at the centre with its Jacobian, the second-order term over the set.
    TubeStep step = detail::start_step(state, enclosure);
    const detail::TaylorMap map =
        detail::taylor_map(tape, state, live.live, enclosure, options, step);
    // 5. Lohner's step on the doubleton, and the tight enclosure at t1.
    detail::LohnerStep next = detail::lohner_step(state, map, step, enclosure, live, options);
    if (next.qr) ++result.qr_steps;
    // The step goes into the tube. Its box at t1 is the intersection of the three that hold every
    // solution there: the Lohner set's, the step's box over [t0, t1] and its Taylor form at h (the
    // Lohner box alone is at times wider than the box over the step); the next step starts from it.
    detail::append_step(result.tube, std::move(step), enclosure.apriori, next.set.x);
    {
      TubeStep& stored = result.tube.steps.back();
      stored.end = intersect(intersect(stored.end, stored.over),
                             result.tube.step_form(result.tube.steps.size() - 1, stored.h));
      next.set.x = stored.end;
    }
    // A set at t1 that is refused ends the run before the step: its boxes would say nothing
    // (wider than max_width), and the tube, with the time it reaches, ends at t0.
    if (const std::optional<Stop> stop = refused(next, options)) {
      result.tube.steps.pop_back();
      result.width_stop = stop->width;
      return finish(stop->status, state.t, stop->reason);
    }
    ++result.steps;
    state = std::move(next.set);
    // 6. The next step size from this step's remainder.
    state.h_next = detail::next_step_size(enclosure, state.h_next, options);
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
  Doubleton start = detail::initial_doubleton(x0, options);
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

  Doubleton state = detail::restart_doubleton(tapes, tube, step, piece, options);
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
