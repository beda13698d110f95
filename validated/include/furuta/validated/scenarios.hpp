#pragma once
// The paper's validation by guaranteed simulation (section IV.B, Fig. 6, Table III): four
// scenarios run on the simulated rig as "measurements", tubes from interval (SIVIA) and point
// (LSMI) parameters with the data's uncertainty on the initial state, coverage rates: the numbers
// of Table III and Fig. 6 (their text and figures are report/'s). See validated/README.md,
// "Scenarios and coverage".
//
//   const Scenario s = paper_scenario(1);
//   const ScenarioMeasurement m = measure_scenario(s, model::paper_run1());
//   const ScenarioResult r = evaluate_scenario(s, point_parameters("LSMI", estimate), m, {}, {});

#include <cstddef>
#include <string>
#include <vector>

#include "furuta/interval/box.hpp"
#include "furuta/model/model.hpp"
#include "furuta/validated/coverage.hpp"
#include "furuta/validated/integrator.hpp"
#include "furuta/validated/ode.hpp"
#include "furuta/validated/split.hpp"
#include "furuta/validated/taylor_model_flow.hpp"

namespace furuta::validated {

// From rest at x0 = [q1, dq1, q2, dq2] = [0, 0, q2_initial, 0] under a constant arm torque.
struct Scenario {
  int number = 1;  // the paper's (a)..(d) are 1..4
  double q2_initial_rad = 0.0;
  double torque_nm = 0.0;
  double duration_s = 4.0;
};

// The paper's four: [0,0,-100 deg,0] u = 0; [0,0,50 deg,0] u = 0; [0,0,-90 deg,0] u = 0.17 N m;
// [0,0,-45 deg,0] u = -0.1 N m; 4 s each.
std::vector<Scenario> paper_scenarios();
// One of them; std::invalid_argument outside 1..4.
Scenario paper_scenario(int number);

// How the simulated rig "measures" a scenario (the rig's defaults).
struct MeasurementOptions {
  double step_s = 1e-3;                  // RK4 step of the true model
  double sample_period_s = 0.016;        // the daemon's loop
  double arm_resolution_rad = 0.0;       // 0: one count of the 512-line motor encoder behind 26:1
  double pendulum_resolution_rad = 0.0;  // 0: one count of the pendulum channel's 4096 per turn
};

struct ScenarioMeasurement {
  std::vector<double> t_s;     // 0, T, 2T, ... up to the scenario's duration
  std::vector<double> q1_rad;  // quantised like the encoders
  std::vector<double> q2_rad;
  std::vector<double> q1_true_rad;  // the model's own values at the samples (no quantisation)
  std::vector<double> q2_true_rad;
  double arm_resolution_rad = 0.0;
  double pendulum_resolution_rad = 0.0;
};

// The true model from exactly x0 with the scenario's torque, RK4 at options.step_s, sampled
// every sample period with the encoders' quantisation. std::invalid_argument for a non-positive
// step, period or duration, or a period that is not a whole number of steps.
ScenarioMeasurement measure_scenario(const Scenario& scenario,
                                     const model::Parameters<double>& truth,
                                     const MeasurementOptions& options = {});

// The data's uncertainty on the initial state (half-widths): the tube starts from x0 +- these.
struct StateUncertainty {
  double q1_rad = 1e-3;
  double dq1_rad_s = 1e-3;
  double q2_rad = 1.6e-3;  // about one pendulum count and the zero's uncertainty
  double dq2_rad_s = 1e-3;
};

// [q1, dq1, q2, dq2] of the scenario's x0 widened by the uncertainty (std::invalid_argument for
// a negative or non-finite half-width).
interval::Box initial_state_box(const Scenario& scenario, const StateUncertainty& uncertainty);

// A named set of model parameters for the tubes: intervals (SIVIA) or points (LSMI).
struct ParameterSet {
  std::string name;
  model::Parameters<Interval> parameters;
  // The scenario's torque acts as torque_nm * torque_scale. The model is homogeneous in its
  // parameters and the torque: the rig's parameters g theta under a torque u move as theta under
  // u / g. So a set known only up to a drive gain g (the scaled parameters of a guaranteed set,
  // identification/physical_inputs.hpp) is given as theta with torque_scale = 1 / g's interval.
  Interval torque_scale{1.0};
  // Carry the set through the Taylor-model flow (run_scenario_taylor_models) rather than the
  // doubleton integrator: for sets narrow enough that the flow's higher orders in the
  // parameters, not the splits of the start box, decide how far a tube goes.
  bool taylor_models = false;
};

// Point parameters (every interval a single value).
ParameterSet point_parameters(std::string name, const model::Parameters<double>& p);

// The integrator's settings for the Furuta scenarios (chosen with bench/validated_bench.cpp, its
// figures in docs/measurements/validated.md): tolerance 1e-11 (a looser one ends scenario (a)
// sooner, a tighter one takes more steps for little further), the QR frame at every step (the
// arm's damping, about 150 /s, makes the parallelepiped ill-conditioned), and max_width 2 pi (a
// q2 tube wider than a turn says nothing about the angle).
IntegratorOptions scenario_integrator_options();

// Split options that never split: one tube.
inline SplitOptions single_tube() {
  SplitOptions o;
  o.max_pieces = 1;
  return o;
}

// `pieces` tubes for a scenario of `duration_s`: 1 is single_tube(); a power of two plans the
// split (SplitOptions::planned_depth) at 0.5 s, or at an eighth of a shorter duration (the
// pieces' second-order leftovers shrink with them while the error inherited at the split is still
// small, so a few pieces bring q2's tube at the end much closer to the sampled spread:
// docs/measurements/validated.md, "Limits, in full"). Throws std::invalid_argument for another
// count.
SplitOptions scenario_split_options(std::size_t pieces, double duration_s);

// The tube set of one scenario: one piece from `integrate`, or the pieces of a split run.
struct ScenarioTubes {
  // What the integrator was given: the start box at t = 0 ([q1, dq1, q2, dq2], then the
  // parameters when they are carried as state) and the constant arm torque.
  interval::Box initial;
  Interval torque_nm;
  std::vector<Tube> pieces;
  IntegrationResult::Status status = IntegrationResult::Status::ok;
  std::string reason;                   // why the run ended early (empty when it reached the end)
  std::optional<WidthStop> width_stop;  // when max_width ended it: its numbers
  double t_reached_s = 0.0;
  std::size_t steps = 0;
  std::size_t rejected = 0;
  double seconds = 0.0;  // wall time

  std::vector<const Tube*> views() const;
};

// Validated integration of the Furuta model from the initial state box, with the scenario's
// torque, over [0, scenario.duration_s] (options' t_start and t_end are set from the scenario; the
// rest is used as given): FurutaStateDynamics for point parameters, FurutaDynamics (parameters
// carried as state) for intervals. A run that fails is split into pieces up to split.max_pieces
// (1: one tube, no splitting).
ScenarioTubes run_scenario_tubes(const Scenario& scenario,
                                 const model::Parameters<Interval>& parameters,
                                 const StateUncertainty& uncertainty, IntegratorOptions options,
                                 const SplitOptions& split = single_tube());

// The Taylor-model flow's settings for the Furuta scenarios
// (docs/measurements/taylor-model-flow.md, "Taylor models IV" and "V"): order 8 in time at
// tolerance 1e-8, order 3 in the variables, the error part wrapped into the start (the arm's
// collapsed velocity left out when the whole wrap fails, the wrap's preconditioner at the base
// point), the QR frame, max_width 2 pi.
TaylorModelFlowOptions scenario_taylor_model_options();

// One tube of a scenario through the Taylor-model flow over `set` (its `taylor_models` flag is
// not read): FurutaRampedDynamics with the torque torque_nm * set.torque_scale as the input
// variable (rate 0), so that the set's parameters and its torque scale are variables of the flow.
// The tube's components are [q1, dq1, q2, dq2, mu1, ..., fv2, u]; options' t_start and t_end are
// set from the scenario. With max_pieces 1 a run that fails ends the tube; with more it is cut
// where it fails (taylor_model_split.hpp) into at most that many pieces. The pieces are not boxes
// of the start: each piece's Tube starts from the whole start box with its ancestors' steps, and
// every solution is at each time inside some piece's enclosure.
ScenarioTubes run_scenario_taylor_models(const Scenario& scenario, const ParameterSet& set,
                                         const StateUncertainty& uncertainty,
                                         TaylorModelFlowOptions options,
                                         std::size_t max_pieces = 1);

// The tube set of `set` for a scenario: run_scenario_taylor_models when the set says so (with
// scenario_taylor_model_options() and at most split.max_pieces pieces), else run_scenario_tubes
// with the torque times the set's torque scale.
ScenarioTubes run_scenario_tubes(const Scenario& scenario, const ParameterSet& set,
                                 const StateUncertainty& uncertainty,
                                 const IntegratorOptions& options, const SplitOptions& split);

// One step of the q2 tube (for figures): the enclosure of q2 over [t0, t1].
struct TubeBand {
  double t0_s = 0.0;
  double t1_s = 0.0;
  double lo_rad = 0.0;
  double hi_rad = 0.0;
};

// A row of Table III, with what its figure needs.
struct ScenarioResult {
  Scenario scenario;
  ParameterSet parameters;
  StateUncertainty uncertainty;
  IntegrationResult::Status status = IntegrationResult::Status::ok;
  std::string reason;
  // When max_width ended the tube: the widest component ([q1, dq1, q2, dq2, then what is carried
  // as state]), its width and the limit in its unit (rad, rad/s), and when.
  std::optional<WidthStop> width_stop;
  double t_reached_s = 0.0;
  std::size_t steps = 0;
  std::size_t pieces = 0;
  double seconds = 0.0;
  Coverage q1_step, q1_interpolated, q2_step, q2_interpolated;
  // Width of the q2 enclosure at the sample times reached (interpolated): mean and largest.
  double q2_mean_width_rad = 0.0;
  double q2_max_width_rad = 0.0;
  std::vector<TubeBand> q2_tube;      // every piece's steps
  std::vector<bool> q2_covered_step;  // per measurement, the paper's test
  ScenarioMeasurement measurement;
};

// Coverage rates and figures' data of a tube set against a measurement.
ScenarioResult evaluate_tubes(const Scenario& scenario, const ParameterSet& parameters,
                              const StateUncertainty& uncertainty,
                              const ScenarioMeasurement& measurement, const ScenarioTubes& tubes);
// run_scenario_tubes for the set, then evaluate_tubes.
ScenarioResult evaluate_scenario(const Scenario& scenario, const ParameterSet& parameters,
                                 const ScenarioMeasurement& measurement,
                                 const StateUncertainty& uncertainty,
                                 const IntegratorOptions& options,
                                 const SplitOptions& split = single_tube());

}  // namespace furuta::validated
