// The a priori enclosure of a step and its Lagrange remainder (see a_priori.hpp).

#include "a_priori.hpp"

#include <algorithm>
#include <cmath>
#include <span>
#include <utility>

#include "reason.hpp"

namespace furuta::validated::detail {
namespace {

Box field(TaylorRunner<Interval>& runner, const Tape& tape, const Box& x) {
  const std::vector<Interval> xs(x.begin(), x.end());
  runner.run(tape, std::span<const Interval>(xs), 1);
  Box f(x.size());
  for (std::size_t v = 0; v < x.size(); ++v) f[v] = runner.coefficient(v, 1);
  return f;
}

}  // namespace

// A box containing every solution from x over [0, h], or nothing if Picard's test fails.
std::optional<Box> a_priori(TaylorRunner<Interval>& runner, const Tape& tape, const Box& x,
                            double h) {
  const Interval span(0.0, h);
  const std::size_t n = x.size();
  Box f = field(runner, tape, x);
  Box b(n);
  for (std::size_t v = 0; v < n; ++v) b[v] = x[v] + span * f[v];
  for (int iteration = 0; iteration < 8; ++iteration) {
    Box inflated(n);
    for (std::size_t v = 0; v < n; ++v) {
      if (!b[v].is_bounded()) return std::nullopt;
      const double d = 0.1 * b[v].width() + 1e-13 * b[v].mag() + 1e-300;
      inflated[v] = b[v] + Interval(-d, d);
    }
    f = field(runner, tape, inflated);
    bool inside = true;
    for (std::size_t v = 0; v < n; ++v) {
      if (!f[v].is_bounded()) return std::nullopt;
      b[v] = x[v] + span * f[v];
      inside = inside && b[v].is_interior_subset(inflated[v]);
    }
    // Every solution stays in `inflated`, hence in x + [0, h] f(inflated) = b.
    if (inside) return b;
  }
  return std::nullopt;
}

StepEnclosure enclose_step(TaylorRunner<Interval>& runner, const Tape& tape, const Box& x, double t,
                           double t_limit, double h_next, const IntegratorOptions& options,
                           std::size_t& rejected) {
  const std::size_t n = x.size();
  const int k = options.order;
  const double root = 1.0 / (k + 1);
  StepEnclosure out;
  double h = std::min(h_next, t_limit - t);
  out.capped = h_next >= t_limit - t;
  out.t1 = t_limit;
  out.remainder_coefficient.resize(n);
  out.remainder = Box(n);
  for (;;) {
    out.t1 = h >= t_limit - t ? t_limit : t + h;
    if (!(out.t1 > t)) {
      out.failure = "step below the time resolution at t = " + describe(t);
      return out;
    }
    out.hi = Interval(out.t1) - Interval(t);
    std::optional<Box> enclosure = a_priori(runner, tape, x, out.hi.hi());
    bool bounded = false;
    if (enclosure) {
      const std::vector<Interval> bs(enclosure->begin(), enclosure->end());
      runner.run(tape, std::span<const Interval>(bs), k + 1);
      const Interval h_k1 = pow(out.hi, k + 1);
      out.remainder_width = 0.0;
      bounded = true;
      for (std::size_t v = 0; v < n; ++v) {
        out.remainder_coefficient[v] = runner.coefficient(v, k + 1);
        out.remainder[v] = h_k1 * out.remainder_coefficient[v];
        bounded = bounded && out.remainder[v].is_bounded();
        out.remainder_width = std::max(out.remainder_width, out.remainder[v].width());
      }
      if (bounded && (out.remainder_width <= options.tolerance || h <= options.h_min)) {
        out.h = h;
        out.apriori = std::move(*enclosure);
        return out;
      }
    }
    ++rejected;
    if (h <= options.h_min) {
      out.failure = "no a priori enclosure (Picard) at t = " + describe(t) +
                    " with h = " + describe(h) + " (h_min)";
      return out;
    }
    double shrink = 0.5;
    if (bounded) {
      shrink = std::clamp(0.9 * std::pow(options.tolerance / out.remainder_width, root), 0.1, 0.9);
    }
    h = std::max(options.h_min, h * shrink);
    out.capped = false;
  }
}

double next_step_size(const StepEnclosure& step, double h_next, const IntegratorOptions& options) {
  const double root = 1.0 / (options.order + 1);
  if (step.capped) return h_next;
  const double grow =
      step.remainder_width > 0.0
          ? std::clamp(0.9 * std::pow(options.tolerance / step.remainder_width, root), 0.25, 2.0)
          : 2.0;
  return std::min(options.h_max, std::max(options.h_min, step.h * grow));
}

}  // namespace furuta::validated::detail
