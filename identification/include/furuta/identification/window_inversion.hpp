#pragma once
// Set inversion through the ODE over one short window of a recording: which parameters can
// explain every angle read in the window, for some start state in a given box.
//
// The window's start state and the scaled parameters (physical_inputs.hpp: the duty is the
// input) are the variables of the Taylor-model flow (validated/taylor_model_flow.hpp); the flow
// stops at every reading's time, where the read joint's angle is a model m(z) = c + a.z + h(z)
// that must meet the reading's interval. Each such constraint contracts z: for each variable,
// z_v is within (reading - c - h - the other linear terms) / a_v, h bounded over the current
// box. Sweeps over all readings repeat while they contract. An empty z proves no parameter of the
// box explains the window (`inconsistent`); otherwise the parameters' box shrinks to what the
// contracted z allows (`contracted`). Every step is in outward-rounded interval arithmetic, so
// nothing consistent is ever removed.
//
// The flow may shrink-wrap its error part into the start variables (TaylorModelFlowOptions::
// shrink_wrap_max_delta): each wrap opens start variables of its own, tied to those before by the
// wrap's scale and delta (TaylorModelFlowStep::wrap_scale, wrap_delta), so readings before and
// after a wrap still constrain one start; the parameters' variables are shared by every reading
// of every window. Without wrapping the flow's error part grows through the arm's stiff mode and
// soon ends a window, even on a narrow box (docs/measurements/identification.md, "Guaranteed
// identification III, first step").

#include <cstddef>
#include <string>
#include <vector>

#include "furuta/interval/box.hpp"
#include "furuta/interval/interval.hpp"
#include "furuta/model/model.hpp"
#include "furuta/validated/ode.hpp"
#include "furuta/validated/taylor_model_flow.hpp"

namespace furuta::identification {

// One encoder reading: the joint (0: arm q1, 1: pendulum q2) and the interval its true angle is
// in, at its time.
struct AngleReading {
  double t_s = 0.0;
  int joint = 0;
  interval::Interval angle_rad;
};

// A window's times are the input's (the commands' clock); a reading's t_s is when the host got it,
// `lag_s` after the time of the state it shows (the data path's lag, one unknown shared by every
// reading of every window inverted together).
struct RecordingWindow {
  double t0_s = 0.0;
  double t1_s = 0.0;
  interval::Box start;  // [q1, dq1, q2, dq2] at t0_s
  // The duty (the scaled model's input) as pieces; the first starts at t0_s. With `ramped`, each
  // piece's tau is the duty's rate [1/s] and duty_start the duty at t0_s: the duty is then exact
  // between the pieces' times (validated::FurutaRampedDynamics, the board's ramp).
  std::vector<validated::InputPiece> duty;
  bool ramped = false;
  interval::Interval duty_start{0.0};
  interval::Interval lag_s{0.0};
  // A pendulum reading's interval holds the angle less this unknown (the zero's offset from
  // hanging, shared by every reading inverted together); the arm's angle is free of it.
  interval::Interval pendulum_zero_rad{0.0};
  std::vector<AngleReading> readings;  // t0_s + lag_s.hi() < t_s <= t1_s + lag_s.lo(), in order
};

struct WindowOptions {
  validated::TaylorModelFlowOptions flow;  // t_start, t_end and keep_end_models are the window's
  int max_sweeps = 8;                      // contraction sweeps over all readings
  double min_sweep_gain = 0.01;            // stop once a sweep shrinks no width by this fraction
  // Passes: the flows run again over the contracted box, whose models are sharper (their
  // non-linear parts smaller), while a pass shrinks some parameter's width by min_pass_gain.
  int max_passes = 1;
  double min_pass_gain = 0.05;
  // A flow that stops before its window's end gives its end box (WindowOutcome::ends) at the step
  // this fraction of the way from the window's start to where it stopped.
  double restart_fraction = 0.8;
};

// The settings recordings are inverted with: Taylor order 8 in time, models of order 3 in the
// variables, shrink wraps tying the start variables, three passes.
WindowOptions default_window_options();

enum class WindowVerdict {
  inconsistent,  // no parameter in the box explains the window from any start in the box
  contracted,    // the box, shrunk (possibly not at all) to what the window allows
  flow_failed,   // the flow did not carry the box through the window: nothing is concluded
};

struct WindowOutcome {
  WindowVerdict verdict = WindowVerdict::flow_failed;
  model::Parameters<interval::Interval> parameters;  // contracted (as given when flow_failed)
  interval::Box start;                               // the start state, contracted
  interval::Interval lag_s;                          // the data path's lag, contracted
  interval::Interval pendulum_zero_rad;              // the pendulum's zero, contracted
  // Per window, in order: the state for every parameter and start the contraction kept (a step's
  // models over the contracted variables) at its t1_s, or, when its flow stopped early, at the
  // step WindowOptions::restart_fraction of the way there; an empty box when its flow took no
  // step. What a next window chained to this one starts from.
  std::vector<interval::Box> ends;
  // Per window: the time of `ends`, and how far its flow went.
  std::vector<double> end_times, reached;
  std::string reason;  // why the flow failed, or which reading
  std::size_t flow_steps = 0;
  std::size_t shrink_wraps = 0;  // the flows' wraps, each tying the start before and after it
  std::size_t sweeps = 0;        // the last pass's
  std::size_t passes = 0;
  // The widest prediction of a reading before contraction, in units of its reading's width: how
  // much of the data the flow's set resolves (below 1: every reading can cut).
  double widest_prediction = 0.0;
  double flow_seconds = 0.0;
};

// The parameters are the scaled ones (theta, b, fv2 / g), the state box the window's own start.
// Steps, wraps and seconds are summed over the passes.
// Throws std::invalid_argument for a window without duty pieces, with readings outside
// (t0_s + lag_s.hi(), t1_s + lag_s.lo()] or a joint other than 0 or 1.
WindowOutcome invert_window(const RecordingWindow& window,
                            const model::Parameters<interval::Interval>& parameters,
                            const WindowOptions& options);

// Several windows of one rig: each with start variables of its own, all sharing the parameters'
// (so that windows which pin different combinations of the parameters contract them together).
// The windows' flows run in parallel (oneTBB). The outcome's `start` is the first window's; steps
// and seconds are summed over the windows.
WindowOutcome invert_windows(const std::vector<RecordingWindow>& windows,
                             const model::Parameters<interval::Interval>& parameters,
                             const WindowOptions& options);

}  // namespace furuta::identification
