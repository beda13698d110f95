#include "furuta/validated/scenarios.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "furuta/validated/taylor_model_split.hpp"

namespace furuta::validated {

namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

double deg_to_rad(double deg) {
  return deg / kDegPerRad;
}

}  // namespace

std::vector<Scenario> paper_scenarios() {
  return {
      Scenario{1, deg_to_rad(-100.0), 0.0, 4.0},
      Scenario{2, deg_to_rad(50.0), 0.0, 4.0},
      Scenario{3, deg_to_rad(-90.0), 0.17, 4.0},
      Scenario{4, deg_to_rad(-45.0), -0.1, 4.0},
  };
}

Scenario paper_scenario(int number) {
  if (number < 1 || number > 4) {
    throw std::invalid_argument("scenario " + std::to_string(number) +
                                ": the paper's scenarios are 1 to 4");
  }
  return paper_scenarios()[static_cast<std::size_t>(number - 1)];
}

ScenarioMeasurement measure_scenario(const Scenario& scenario,
                                     const model::Parameters<double>& truth,
                                     const MeasurementOptions& options) {
  if (!(options.step_s > 0.0) || !(options.sample_period_s > 0.0) || !(scenario.duration_s > 0.0) ||
      !std::isfinite(scenario.duration_s)) {
    throw std::invalid_argument("measure_scenario: step, sample period and duration must be > 0");
  }
  const double steps_real = options.sample_period_s / options.step_s;
  const long steps_per_sample = std::lround(steps_real);
  if (steps_per_sample < 1 || std::abs(steps_real - static_cast<double>(steps_per_sample)) > 1e-9) {
    std::ostringstream message;
    message << "measure_scenario: the sample period " << options.sample_period_s
            << " s is not a whole number of steps of " << options.step_s << " s";
    throw std::invalid_argument(message.str());
  }
  if (options.arm_resolution_rad < 0.0 || options.pendulum_resolution_rad < 0.0) {
    throw std::invalid_argument("measure_scenario: negative encoder resolution");
  }
  ScenarioMeasurement m;
  m.arm_resolution_rad = options.arm_resolution_rad > 0.0 ? options.arm_resolution_rad
                                                          : 2 * std::numbers::pi / (512 * 26.0);
  m.pendulum_resolution_rad = options.pendulum_resolution_rad > 0.0
                                  ? options.pendulum_resolution_rad
                                  : 2 * std::numbers::pi / 4096;
  const auto quantise = [](double x, double resolution) {
    return std::round(x / resolution) * resolution;
  };
  model::PendulumState x{0.0, 0.0, scenario.q2_initial_rad, 0.0};
  const auto torque = [&](const model::PendulumState&) { return scenario.torque_nm; };
  // Sample times as k T (not accumulated) so they land on the tube's step ends where they should.
  for (long k = 0;; ++k) {
    const double t = static_cast<double>(k) * options.sample_period_s;
    if (t > scenario.duration_s * (1 + 1e-12)) break;
    m.t_s.push_back(t);
    m.q1_rad.push_back(quantise(x.q1, m.arm_resolution_rad));
    m.q2_rad.push_back(quantise(x.q2, m.pendulum_resolution_rad));
    m.q1_true_rad.push_back(x.q1);
    m.q2_true_rad.push_back(x.q2);
    for (long s = 0; s < steps_per_sample; ++s)
      x = model::rk4_step(truth, x, options.step_s, torque);
  }
  return m;
}

interval::Box initial_state_box(const Scenario& scenario, const StateUncertainty& u) {
  for (const double h : {u.q1_rad, u.dq1_rad_s, u.q2_rad, u.dq2_rad_s}) {
    if (!(h >= 0.0) || !std::isfinite(h)) {
      throw std::invalid_argument("initial state uncertainty: half-widths must be finite and >= 0");
    }
  }
  const auto around = [](double centre, double half) {
    return interval::Interval(centre) + interval::Interval(-half, half);
  };
  return interval::Box{around(0.0, u.q1_rad), around(0.0, u.dq1_rad_s),
                       around(scenario.q2_initial_rad, u.q2_rad), around(0.0, u.dq2_rad_s)};
}

ParameterSet point_parameters(std::string name, const model::Parameters<double>& p) {
  return ParameterSet{std::move(name), interval_parameters(p)};
}

std::vector<const Tube*> ScenarioTubes::views() const {
  std::vector<const Tube*> out;
  for (const Tube& t : pieces) out.push_back(&t);
  return out;
}

IntegratorOptions scenario_integrator_options() {
  IntegratorOptions o;
  o.tolerance = 1e-11;
  o.max_inflation = 1.0;
  o.max_width = 2 * std::numbers::pi;
  return o;
}

SplitOptions scenario_split_options(std::size_t pieces, double duration_s) {
  if (pieces == 1) return single_tube();
  if (pieces == 0 || (pieces & (pieces - 1)) != 0 || pieces > 64) {
    throw std::invalid_argument("pieces: " + std::to_string(pieces) +
                                " is not one of 1, 2, 4, 8, 16, 32, 64");
  }
  SplitOptions o;
  o.max_pieces = pieces;
  o.planned_depth = std::countr_zero(pieces);
  o.max_depth = o.planned_depth;
  o.planned_split_s = std::min(0.5, duration_s / 8);
  return o;
}

namespace {

bool all_points(const model::Parameters<Interval>& p) {
  for (const Interval* x : {&p.mu1, &p.mu2, &p.mu3, &p.mu4, &p.mug, &p.fv1, &p.fv2}) {
    if (x->width() != 0.0) return false;
  }
  return true;
}

}  // namespace

namespace {

ScenarioTubes scaled_torque_tubes(const Scenario& scenario,
                                  const model::Parameters<Interval>& parameters,
                                  const Interval& torque, const StateUncertainty& uncertainty,
                                  IntegratorOptions options, const SplitOptions& split) {
  options.t_start = 0.0;
  options.t_end = scenario.duration_s;
  const Box state = initial_state_box(scenario, uncertainty);
  // Point parameters need not be carried as state: the 4-dimensional system is several times
  // cheaper per step and its q1, dq1, q2, dq2 are the same components.
  const bool points = all_points(parameters);
  ScenarioTubes out;
  out.initial = points ? state : FurutaDynamics::initial_box(state, parameters);
  out.torque_nm = torque;
  SplitResult r =
      points ? integrate_split(FurutaStateDynamics(parameters, torque), out.initial, options, split)
             : integrate_split(FurutaDynamics(torque), out.initial, options, split);
  out.status = r.status;
  out.reason = r.reason;
  out.width_stop = r.width_stop;
  out.steps = r.steps;
  out.seconds = r.seconds;
  out.pieces = std::move(r.pieces);
  out.t_reached_s = time_reached(out.views());
  return out;
}

}  // namespace

ScenarioTubes run_scenario_tubes(const Scenario& scenario,
                                 const model::Parameters<Interval>& parameters,
                                 const StateUncertainty& uncertainty, IntegratorOptions options,
                                 const SplitOptions& split) {
  return scaled_torque_tubes(scenario, parameters, Interval(scenario.torque_nm), uncertainty,
                             std::move(options), split);
}

TaylorModelFlowOptions scenario_taylor_model_options() {
  TaylorModelFlowOptions o;
  o.integrator.order = 8;
  // The Lagrange remainder's target: the models' truncation is far above it.
  o.integrator.tolerance = 1e-8;
  o.integrator.max_inflation = 1.0;
  o.integrator.max_width = 2 * std::numbers::pi;
  o.space_order = 3;
  o.shrink_wrap_max_delta = 1.0;
  o.wrap_without_collapsed = true;
  o.wrap_at_base_point = true;
  return o;
}

ScenarioTubes run_scenario_taylor_models(const Scenario& scenario, const ParameterSet& set,
                                         const StateUncertainty& uncertainty,
                                         TaylorModelFlowOptions options, std::size_t max_pieces) {
  options.integrator.t_start = 0.0;
  options.integrator.t_end = scenario.duration_s;
  const Interval torque = Interval(scenario.torque_nm) * set.torque_scale;
  const FurutaRampedDynamics system({InputPiece{0.0, Interval(0.0)}});
  ScenarioTubes out;
  out.initial = FurutaRampedDynamics::initial_box(initial_state_box(scenario, uncertainty),
                                                  set.parameters, torque);
  out.torque_nm = torque;
  if (max_pieces <= 1) {
    const TaylorModelFlowResult r = integrate_taylor_models(system, out.initial, options);
    out.status = r.status;
    out.reason = r.reason;
    out.width_stop = r.width_stop;
    out.steps = r.steps.size();
    out.rejected = r.rejected;
    out.seconds = r.seconds;
    out.pieces.push_back(as_tube(r));
  } else {
    TaylorModelSplitOptions split;
    split.max_pieces = max_pieces;
    const TaylorModelSplitResult r =
        integrate_taylor_models_split(system, out.initial, options, split);
    out.status = r.status;
    out.reason = r.reason;
    out.width_stop = r.width_stop;
    out.steps = r.steps;
    out.seconds = r.seconds;
    for (const TaylorModelFlowResult& piece : r.pieces) {
      out.rejected += piece.rejected;
      out.pieces.push_back(as_tube(piece));
    }
  }
  out.t_reached_s = time_reached(out.views());
  return out;
}

ScenarioTubes run_scenario_tubes(const Scenario& scenario, const ParameterSet& set,
                                 const StateUncertainty& uncertainty,
                                 const IntegratorOptions& options, const SplitOptions& split) {
  if (set.taylor_models) {
    return run_scenario_taylor_models(scenario, set, uncertainty, scenario_taylor_model_options(),
                                      split.max_pieces);
  }
  return scaled_torque_tubes(scenario, set.parameters,
                             Interval(scenario.torque_nm) * set.torque_scale, uncertainty, options,
                             split);
}

ScenarioResult evaluate_tubes(const Scenario& scenario, const ParameterSet& parameters,
                              const StateUncertainty& uncertainty,
                              const ScenarioMeasurement& measurement, const ScenarioTubes& tubes) {
  const std::vector<const Tube*> pieces = tubes.views();
  ScenarioResult r;
  r.scenario = scenario;
  r.parameters = parameters;
  r.uncertainty = uncertainty;
  r.status = tubes.status;
  r.reason = tubes.reason;
  r.width_stop = tubes.width_stop;
  r.t_reached_s = time_reached(pieces);
  r.steps = tubes.steps;
  r.pieces = tubes.pieces.size();
  r.seconds = tubes.seconds;
  const auto q1 = FurutaDynamics::q1;
  const auto q2 = FurutaDynamics::q2;
  r.q1_step = coverage(pieces, q1, measurement.t_s, measurement.q1_rad, CoverageMode::step);
  r.q1_interpolated =
      coverage(pieces, q1, measurement.t_s, measurement.q1_rad, CoverageMode::interpolated);
  r.q2_step = coverage(pieces, q2, measurement.t_s, measurement.q2_rad, CoverageMode::step,
                       &r.q2_covered_step);
  r.q2_interpolated =
      coverage(pieces, q2, measurement.t_s, measurement.q2_rad, CoverageMode::interpolated);
  double width_sum = 0.0;
  std::size_t widths = 0;
  for (const double t : measurement.t_s) {
    const interval::Interval e = enclosure_at(pieces, q2, t);
    if (e.is_empty()) continue;
    width_sum += e.width();
    r.q2_max_width_rad = std::max(r.q2_max_width_rad, e.width());
    ++widths;
  }
  r.q2_mean_width_rad = widths == 0 ? 0.0 : width_sum / static_cast<double>(widths);
  for (const Tube* tube : pieces) {
    for (const TubeStep& s : tube->steps) {
      r.q2_tube.push_back({s.t0, s.t1, s.over[q2].lo(), s.over[q2].hi()});
    }
  }
  r.measurement = measurement;
  return r;
}

ScenarioResult evaluate_scenario(const Scenario& scenario, const ParameterSet& parameters,
                                 const ScenarioMeasurement& measurement,
                                 const StateUncertainty& uncertainty,
                                 const IntegratorOptions& options, const SplitOptions& split) {
  const ScenarioTubes tubes = run_scenario_tubes(scenario, parameters, uncertainty, options, split);
  return evaluate_tubes(scenario, parameters, uncertainty, measurement, tubes);
}

}  // namespace furuta::validated
