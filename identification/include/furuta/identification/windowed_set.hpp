#pragma once
// Guaranteed identification from recordings by windowed set inversion (window_inversion.hpp):
// which scaled parameters of a search box explain every angle each recording read, from the rest
// before its first command, through a chain of windows.
//
// Each recording is a chain of windows on the commands' clock from its first command. The first
// starts from the rest the daemon waited for (the last readings before the command with their
// errors and the pendulum's zero; the pendulum's speed bounded by the energy of a swing within
// that band, the arm's by [guaranteed] arm_rest_speed_rad_s); each later one from the box the one
// before ended in, for every parameter and start it kept. A window is window_s long or ends where
// its flow stopped on the current box; the next starts there. Every reading is its angle plus the
// encoder's error at its host time, which is the state's time plus the data path's lag (an
// unknown in [guaranteed] lag_ms); a pendulum reading is also off by the zero's offset (an unknown
// in the rest check's band); both are shared by every reading. The duty
// is exact: the commands written, ramped by the board as OeExperiment rebuilds them, carried as a
// state of the flow. Step k inverts the k-th window of every recording together (their flows in
// parallel, the parameters and the lag shared); an inconsistent window proves that the search box
// holds no parameter explaining the data. Only the search box is examined: a parameter outside it
// is neither kept nor excluded.

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "furuta/identification/output_error.hpp"
#include "furuta/identification/physical_inputs.hpp"
#include "furuta/identification/window_inversion.hpp"

namespace furuta::identification {

struct WindowedSetOptions {
  double window_s = 0.25;             // each window's longest length
  std::size_t windows = 8;            // per recording, chained from its first command
  double min_window_s = 0.01;         // a chain whose flow reaches less than this further stops
  double arm_rest_speed_rad_s = 0.0;  // |dq1| at the first command ([guaranteed])
  WindowOptions inversion = default_window_options();
};

// Where a recording's chain starts: the first command's time, the rest box there ([q1, dq1, q2,
// dq2]) and the latest time a window may end (its windows' total, the last reading, a return to
// zero duty). Throws std::invalid_argument for an input that is not a duty or is cubic between
// samples, a recording without a command, without readings of both joints before it or any
// after it.
struct ChainStart {
  double t0_s = 0, t_end_s = 0;
  interval::Box rest;
};
ChainStart chain_start(const OeExperiment& experiment, const PhysicalInputs& inputs,
                       const model::Parameters<Interval>& search,
                       const WindowedSetOptions& options);

// The recording over [t0_s, t1_s] (commands' clock) from `start`: its readings with their errors
// whose host times may show a state inside it, the duty's rate pieces, the lag and the pendulum's
// zero as the unknowns they are.
RecordingWindow recording_window(const OeExperiment& experiment, const PhysicalInputs& inputs,
                                 double t0_s, double t1_s, const interval::Box& start,
                                 const Interval& lag_s, const Interval& pendulum_zero_rad);

enum class WindowedSetVerdict {
  contracted,  // the set: every parameter of the search box explaining the windows inverted
  empty,       // no parameter of the search box explains some window
  unresolved,  // no window could be inverted (the first flows failed): nothing concluded
};

// One window as inverted.
struct WindowRecord {
  std::size_t recording = 0;  // index of its experiment
  std::size_t index = 0;      // its place in its recording's chain
  double t0_s = 0, t1_s = 0;  // as planned
  double reached_s = 0;       // where its flow stopped (t1_s when it carried the window)
  std::size_t readings = 0;
  WindowVerdict verdict = WindowVerdict::flow_failed;
  std::string reason;  // why its flow stopped, or which reading proved the box inconsistent
};

struct WindowedSet {
  WindowedSetVerdict verdict = WindowedSetVerdict::unresolved;
  model::Parameters<Interval> search;  // scaled, as given
  model::Parameters<Interval> set;     // scaled: the search box contracted by every window
  Interval lag_s;                      // the data path's lag, contracted with it
  Interval pendulum_zero_rad;          // the pendulum's zero, the same
  // Per step (the k-th windows of all chains together): the set after it.
  std::vector<model::Parameters<Interval>> set_after_step;
  std::vector<WindowRecord> windows;  // in the order inverted
  // Per recording, its chain's span [s]: from its first command to where its windows were
  // planned to end (its readings' end, the input's stop, or `windows` windows), and how far its
  // windows' flows carried: the set was tested against its readings up to reached_s only.
  struct Span {
    double from_s = 0, planned_end_s = 0, reached_s = 0;
  };
  std::vector<Span> spans;
  std::string finding;      // the empty set's window, or why a chain stopped
  double seconds = 0;       // wall time
  double flow_seconds = 0;  // the flows' own time, summed (several run at once)
  std::size_t flow_steps = 0, shrink_wraps = 0;
};

// Called after each step with the steps done and the most there can be.
using WindowedSetProgress = std::function<void(std::size_t done, std::size_t total)>;

// Inverts the recordings' chains over `search` (scaled parameters, physical_inputs.hpp). Throws
// what chain_start throws.
WindowedSet invert_recordings(const std::vector<OeExperiment>& experiments,
                              const PhysicalInputs& inputs,
                              const model::Parameters<Interval>& search,
                              const WindowedSetOptions& options,
                              const WindowedSetProgress& progress = {});

// The search box around an estimate of the rig's parameters: estimate +- k std_dev, scaled by
// the drive the estimate was made with (its gain g [N m per unit duty] and back-EMF damping k_w
// [N m s]: theta = mu / g, b = (fv1 + k_w) / g, fv2 / g), within the scaled prior.
model::Parameters<Interval> search_box(const model::Parameters<double>& estimate,
                                       const model::Parameters<double>& std_dev, double k,
                                       double gain_nm, double back_emf_nm_s,
                                       const PhysicalInputs& inputs);

}  // namespace furuta::identification
