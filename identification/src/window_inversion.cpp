#include "furuta/identification/window_inversion.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "furuta/validated/taylor_model.hpp"

namespace furuta::identification {

namespace {

using interval::Box;
using interval::Interval;
using validated::FurutaDynamics;
using validated::InputPiece;
using validated::TaylorModel;

constexpr std::size_t kStateVariables = 4;  // q1, dq1, q2, dq2: the start's variables
constexpr std::size_t kVariables = FurutaDynamics::dimension;

// The duty pieces with a switch at every reading's time (the same duty on both sides), so that
// the flow ends a step exactly there.
std::vector<InputPiece> pieces_with_reading_times(const RecordingWindow& window) {
  std::vector<double> times;
  for (const InputPiece& piece : window.duty) times.push_back(piece.t_start);
  for (const AngleReading& reading : window.readings) {
    if (reading.t_s < window.t1_s) times.push_back(reading.t_s);
  }
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  std::vector<InputPiece> pieces;
  std::size_t current = 0;
  for (const double t : times) {
    while (current + 1 < window.duty.size() && window.duty[current + 1].t_start <= t) ++current;
    pieces.push_back({t, window.duty[current].tau});
  }
  return pieces;
}

void check_window(const RecordingWindow& window) {
  if (window.duty.empty()) throw std::invalid_argument("window: no duty pieces");
  if (!(window.t1_s > window.t0_s)) throw std::invalid_argument("window: t1_s must follow t0_s");
  if (window.start.size() != kStateVariables) {
    throw std::invalid_argument("window: the start box has 4 components (q1, dq1, q2, dq2)");
  }
  for (const AngleReading& reading : window.readings) {
    if (!(reading.t_s > window.t0_s && reading.t_s <= window.t1_s)) {
      throw std::invalid_argument("window: a reading at t = " + std::to_string(reading.t_s) +
                                  " s is outside (t0_s, t1_s]");
    }
    if (reading.joint != 0 && reading.joint != 1) {
      throw std::invalid_argument("window: a reading's joint must be 0 (arm) or 1 (pendulum)");
    }
  }
}

// A reading's constraint: the read joint's model at the reading's time, its epoch of start
// variables.
struct Constraint {
  const TaylorModel* model;
  Interval reading;
  std::size_t epoch;
  double t_s;
};

// The variables' box of one constraint: the start's of its epoch, the parameters' shared.
std::vector<Interval> variables_of(const std::vector<std::vector<Interval>>& starts,
                                   const std::vector<Interval>& shared, std::size_t epoch) {
  std::vector<Interval> z = shared;
  for (std::size_t v = 0; v < kStateVariables; ++v) z[v] = starts[epoch][v];
  return z;
}

// The terms of degree 2 and above, and the remainder, over z.
Interval nonlinear_part(const TaylorModel& m, const std::vector<Interval>& z) {
  Interval sum = m.remainder();
  if (!m.space()) return sum;
  const validated::MonomialSpace& space = *m.space();
  const std::vector<double>& coefficients = m.coefficients();
  for (std::size_t k = space.end_of_degree(1); k < space.size(); ++k) {
    if (coefficients[k] == 0.0) continue;
    Interval term(coefficients[k]);
    for (std::size_t v = 0; v < space.variables(); ++v) {
      const int e = space.exponent(k, v);
      if (e > 0) term = term * pow(z[v], e);
    }
    sum = sum + term;
  }
  return sum;
}

// Narrows z with one constraint; false when it proves the constraint cannot hold.
bool contract_with_reading(const Constraint& c, std::vector<Interval>& z) {
  const TaylorModel& m = *c.model;
  const Interval constant(m.coefficient(0));
  const Interval rest = nonlinear_part(m, z);
  std::vector<Interval> linear(kVariables, Interval(0.0));
  for (std::size_t v = 0; v < kVariables; ++v) {
    if (m.space()) linear[v] = Interval(m.coefficient(m.space()->variable(v))) * z[v];
  }
  Interval all = constant + rest;
  for (const Interval& term : linear) all = all + term;
  if (intersect(all, c.reading).is_empty()) return false;
  for (std::size_t v = 0; v < kVariables; ++v) {
    const double a = m.space() ? m.coefficient(m.space()->variable(v)) : 0.0;
    if (a == 0.0) continue;
    Interval others = c.reading - constant - rest;
    for (std::size_t w = 0; w < kVariables; ++w) {
      if (w != v) others = others - linear[w];
    }
    z[v] = intersect(z[v], others / Interval(a));
    if (z[v].is_empty()) return false;
    linear[v] = Interval(a) * z[v];
  }
  return true;
}

// All readings together: with A the readings' linear coefficients (a row per reading, a column
// per variable: the parameters' then each epoch's start), A z lies in r = y - c - h. For any
// matrix P, z = P A z + (I - P A) z, so z_i lies in (P r)_i + sum_j (I - P A)_ij z_j: sound
// whatever P is, evaluated in interval arithmetic. The P's tried are ridge-regularised weighted
// least-squares inverses, P = (A' W^2 A + mu I)^-1 A' W^2 with W the rows' inverse widths: with
// mu small P A is close to I but P amplifies the rows' widths; larger mu leaves more of the other
// variables' ranges in, with less amplification. Each mu gives an enclosure; all are intersected.
// Columns: the parameters' variables 4..10 first, then 4 per epoch. False when z is emptied.
bool contract_together(const std::vector<Constraint>& constraints,
                       std::vector<std::vector<Interval>>& starts, std::vector<Interval>& shared) {
  const std::size_t parameters = kVariables - kStateVariables;
  const std::size_t columns = parameters + kStateVariables * starts.size();
  const std::size_t rows = constraints.size();
  if (rows < 2) return true;
  const auto column_of = [&](std::size_t epoch, std::size_t v) {
    return v >= kStateVariables ? v - kStateVariables : parameters + kStateVariables * epoch + v;
  };
  std::vector<Interval> z(columns);
  for (std::size_t v = kStateVariables; v < kVariables; ++v) z[column_of(0, v)] = shared[v];
  for (std::size_t e = 0; e < starts.size(); ++e) {
    for (std::size_t v = 0; v < kStateVariables; ++v) z[column_of(e, v)] = starts[e][v];
  }
  const auto n = static_cast<Eigen::Index>(columns);
  const auto m_rows = static_cast<Eigen::Index>(rows);
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(m_rows, n);
  Eigen::VectorXd weight(m_rows);
  std::vector<Interval> residual(rows);
  for (std::size_t k = 0; k < rows; ++k) {
    const TaylorModel& m = *constraints[k].model;
    if (!m.space()) return true;
    for (std::size_t v = 0; v < kVariables; ++v) {
      a(static_cast<Eigen::Index>(k),
        static_cast<Eigen::Index>(column_of(constraints[k].epoch, v))) =
          m.coefficient(m.space()->variable(v));
    }
    residual[k] = constraints[k].reading - Interval(m.coefficient(0)) -
                  nonlinear_part(m, variables_of(starts, shared, constraints[k].epoch));
    const double width = residual[k].width();
    if (!(width > 0.0) || !std::isfinite(width)) return true;
    weight(static_cast<Eigen::Index>(k)) = 1.0 / width;
  }
  const Eigen::MatrixXd weighted = weight.asDiagonal() * a;
  const Eigen::MatrixXd gram = weighted.transpose() * weighted;
  const double scale = gram.diagonal().maxCoeff();
  if (!(scale > 0.0) || !std::isfinite(scale)) return true;
  for (const double relative : {1e-10, 1e-7, 1e-4, 1e-2}) {
    const Eigen::MatrixXd regularised = gram + relative * scale * Eigen::MatrixXd::Identity(n, n);
    const Eigen::MatrixXd p = regularised.ldlt().solve(weighted.transpose() * weight.asDiagonal());
    if (!p.allFinite()) continue;
    for (std::size_t i = 0; i < columns; ++i) {
      const auto row = static_cast<Eigen::Index>(i);
      Interval bound(0.0);
      std::vector<Interval> coupling(columns, Interval(0.0));  // (P A)_ij
      for (std::size_t k = 0; k < rows; ++k) {
        const Interval pik(p(row, static_cast<Eigen::Index>(k)));
        if (pik.lo() == 0.0 && pik.hi() == 0.0) continue;
        bound = bound + pik * residual[k];
        for (std::size_t j = 0; j < columns; ++j) {
          const double akj = a(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(j));
          if (akj != 0.0) coupling[j] = coupling[j] + pik * Interval(akj);
        }
      }
      for (std::size_t j = 0; j < columns; ++j) {
        const Interval identity(i == j ? 1.0 : 0.0);
        bound = bound + (identity - coupling[j]) * z[j];
      }
      z[i] = intersect(z[i], bound);
      if (z[i].is_empty()) return false;
    }
  }
  for (std::size_t v = kStateVariables; v < kVariables; ++v) shared[v] = z[column_of(0, v)];
  for (std::size_t e = 0; e < starts.size(); ++e) {
    for (std::size_t v = 0; v < kStateVariables; ++v) starts[e][v] = z[column_of(e, v)];
  }
  return true;
}

double widest_relative_width(const std::vector<Interval>& before,
                             const std::vector<Interval>& after) {
  double gain = 0.0;
  for (std::size_t v = 0; v < before.size(); ++v) {
    if (before[v].width() > 0.0) gain = std::max(gain, 1.0 - after[v].width() / before[v].width());
  }
  return gain;
}

model::Parameters<Interval> parameters_of(const Box& x) {
  return {x[FurutaDynamics::mu1], x[FurutaDynamics::mu2], x[FurutaDynamics::mu3],
          x[FurutaDynamics::mu4], x[FurutaDynamics::mug], x[FurutaDynamics::fv1],
          x[FurutaDynamics::fv2]};
}

}  // namespace

WindowOutcome invert_windows(const std::vector<RecordingWindow>& windows,
                             const model::Parameters<Interval>& parameters,
                             const WindowOptions& options) {
  if (windows.empty()) throw std::invalid_argument("windows: none given");
  for (const RecordingWindow& window : windows) check_window(window);
  WindowOutcome out;
  out.parameters = parameters;
  out.start = windows.front().start;
  std::vector<Box> x0s;
  std::vector<validated::TaylorModelFlowResult> results;
  for (const RecordingWindow& window : windows) {
    x0s.push_back(FurutaDynamics::initial_box(window.start, parameters));
    validated::TaylorModelFlowOptions flow = options.flow;
    flow.integrator.t_start = window.t0_s;
    flow.integrator.t_end = window.t1_s;
    flow.keep_end_models = true;
    results.push_back(validated::integrate_taylor_models(
        FurutaDynamics(pieces_with_reading_times(window)), x0s.back(), flow));
    out.flow_steps += results.back().steps.size();
    out.flow_seconds += results.back().seconds;
    if (!results.back().ok() && out.reason.empty()) out.reason = results.back().reason;
  }

  // Each reading against the step that ends at its time (the flow ends a step at every switch);
  // each window's start variables are its own (and renewed at each shrink wrap), the parameters'
  // are shared by all.
  std::vector<Constraint> constraints;
  std::size_t epoch = 0;
  for (std::size_t w = 0; w < windows.size(); ++w) {
    const RecordingWindow& window = windows[w];
    std::size_t next = 0;
    for (const validated::TaylorModelFlowStep& step : results[w].steps) {
      for (; next < window.readings.size() && window.readings[next].t_s <= step.t1; ++next) {
        const AngleReading& reading = window.readings[next];
        if (std::abs(reading.t_s - step.t1) > 1e-12 * std::max(1.0, std::abs(step.t1))) continue;
        const std::size_t joint = reading.joint == 0 ? FurutaDynamics::q1 : FurutaDynamics::q2;
        constraints.push_back({&step.end_models[joint], reading.angle_rad, epoch, reading.t_s});
        const double width = reading.angle_rad.width();
        if (width > 0.0) {
          out.widest_prediction =
              std::max(out.widest_prediction, step.end_models[joint].bound().width() / width);
        }
      }
      if (step.wrapped) ++epoch;
    }
    ++epoch;
  }
  if (constraints.empty()) {
    out.verdict = WindowVerdict::flow_failed;
    if (out.reason.empty()) out.reason = "no reading within the flows' steps";
    return out;
  }

  std::vector<std::vector<Interval>> starts(
      epoch, std::vector<Interval>(kStateVariables, Interval(-1, 1)));
  std::vector<Interval> shared(kVariables, Interval(-1, 1));
  for (out.sweeps = 0; out.sweeps < static_cast<std::size_t>(options.max_sweeps);) {
    ++out.sweeps;
    const std::vector<Interval> before = shared;
    const std::vector<Interval> starts_before = starts.front();
    for (std::size_t k = 0; k < constraints.size(); ++k) {
      std::vector<Interval> z = variables_of(starts, shared, constraints[k].epoch);
      if (!contract_with_reading(constraints[k], z)) {
        out.verdict = WindowVerdict::inconsistent;
        out.reason =
            "the reading at t = " + std::to_string(constraints[k].t_s) + " s cannot be met";
        return out;
      }
      for (std::size_t v = 0; v < kStateVariables; ++v) starts[constraints[k].epoch][v] = z[v];
      for (std::size_t v = kStateVariables; v < kVariables; ++v) shared[v] = z[v];
    }
    if (!contract_together(constraints, starts, shared)) {
      out.verdict = WindowVerdict::inconsistent;
      out.reason = "the window's readings together cannot be met";
      return out;
    }
    if (std::max(widest_relative_width(before, shared),
                 widest_relative_width(starts_before, starts.front())) < options.min_sweep_gain) {
      break;
    }
  }

  // Back from z to the parameters and the start: each as the flow's own variable over its part.
  const auto space = std::make_shared<validated::MonomialSpace>(kVariables, 1);
  std::vector<std::size_t> all(kVariables);
  for (std::size_t v = 0; v < kVariables; ++v) all[v] = v;
  const std::vector<Interval> z = variables_of(starts, shared, 0);
  const Box& x0 = x0s.front();
  Box x = x0;
  for (std::size_t v = 0; v < kVariables; ++v) {
    if (x0[v].is_point()) continue;
    const Interval part = TaylorModel::variable(space, v, x0[v]).bounded_in(all, z).bound();
    x[v] = intersect(x0[v], part);
  }
  for (std::size_t v = 0; v < kStateVariables; ++v) out.start[v] = x[v];
  out.parameters = parameters_of(x);
  out.verdict = WindowVerdict::contracted;
  return out;
}

}  // namespace furuta::identification

namespace furuta::identification {

WindowOutcome invert_window(const RecordingWindow& window,
                            const model::Parameters<Interval>& parameters,
                            const WindowOptions& options) {
  return invert_windows({window}, parameters, options);
}

}  // namespace furuta::identification
