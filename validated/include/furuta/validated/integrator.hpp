#pragma once
// The validated (guaranteed) ODE integrator: interval Taylor series with a Picard-Lindelof a priori
// enclosure, the set carried in Lohner's doubleton form (parallelepiped or QR frame) with a
// second-order term against the wrapping effect (see validated/README.md).
//
//   IntegrationResult r = integrate(FurutaDynamics(tau), x0, options);
//   if (r.status != IntegrationResult::Status::ok) ... r.t_failed, r.reason
//   Box at_1s = r.tube.enclosure_at(1.0);
//
// Every solution starting in x0 (for every parameter in its box) is inside the tube at every
// time it covers. A failure (a step that cannot be validated, an enclosure past max_width) ends
// the run with a status, its time and the reason; the tube then covers [t_start, t_failed].

#include <cstddef>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "furuta/interval/box.hpp"
#include "furuta/interval/interval.hpp"
#include "furuta/validated/ode.hpp"
#include "furuta/validated/taylor.hpp"

namespace furuta::validated {

struct IntegratorOptions {
  int order = 10;            // Taylor order k (1..40)
  double tolerance = 1e-13;  // wanted width of each step's Lagrange remainder (absolute)
  double h_min = 1e-6;       // below this a step that cannot be validated ends the run
  double h_max = 0.5;        // the largest step
  double h_initial = 0.01;   // the first step tried
  double max_width = 1e3;    // an enclosure wider than this (any component) ends the run
  // The run ends (width_exceeded) when excess_ratio() of the set (its error part B r against the
  // part carried exactly, C r0) passes this: the tube then only grows (a split run bisects).
  double max_excess = std::numeric_limits<double>::infinity();
  // The parallelepiped frame is kept while it inflates the new errors at most this much (its
  // Skeel condition number), else the QR frame. The parallelepiped carries r without wrapping
  // (a rotation in an anisotropic metric stays exact: the pendulum); on a stiff flow (the Furuta
  // arm, damped at about 150 /s) it maps each step's errors through an ill-conditioned frame and
  // the tube grows much faster than with QR: use 1 there (QR unless the frame is diagonal).
  double max_inflation = 20.0;
  // The second-order term of the Taylor coefficients 0..quadratic_order is computed with
  // QuadJet (its products of first-order forms kept as a quadratic form: tight where the field's
  // terms cancel, at several times Jet2's cost), the higher ones with Jet2 (-1: all). Both are
  // sound; the low orders hold most of the term, so a low quadratic_order keeps the tightness for
  // much less work. With the quadratic model the forms of these orders are carried; the default
  // is the order that carried the Furuta scenarios furthest, higher ones cost more and reach no
  // further (docs/measurements/validated.md).
  int quadratic_order = 3;
  // The set is carried as a second-order model m + C r0 + P(r0) + B r (P: one quadratic form in
  // r0 per component, point coefficients): the second-order term of each step's Taylor map
  // (orders 0..quadratic_order) goes into P, only its variation over the set, the terms with
  // B r and the higher orders' second-order terms go into the error part. false: P = 0, the
  // whole second-order term goes into the error part (the doubleton of before).
  bool quadratic_model = true;
  double t_start = 0.0;
  double t_end = 1.0;
};

// One step of the tube, over [t0, t1].
struct TubeStep {
  double t0 = 0.0;
  double t1 = 0.0;
  Interval h;   // t1 - t0 (enclosed: the step is evaluated at every h in it)
  Box apriori;  // the Picard a priori enclosure over [t0, t1]
  Box over;     // a tighter enclosure over [t0, t1] (the Taylor form below over s in [0, h])
  Box end;      // the tight (Lohner) enclosure at t1
  // The Lohner set at t0: every solution is in m + C r0 + B r (doubleton form: r0 = the initial
  // box minus its midpoint, carried by the point matrix C without wrapping; B the frame of r,
  // the errors gathered so far), m = the centre (row 0 of `centre`).
  std::vector<double> c;  // n x n, row-major
  std::vector<double> b;  // n x n, row-major
  std::vector<Interval> r;
  // rho = x0 - origin lives in r0 (the doubleton's fixed box; a run restarted on a sub-box has
  // its own from its restart on).
  std::vector<Interval> r0;
  std::vector<double> origin;
  // The quadratic part P(rho) of the set at t0 (which is then m + C rho + P(rho) + B r): n forms
  // of n (n + 1) / 2 coefficients each (rho_a rho_b, a <= b, row by row); empty: none.
  std::vector<double> quad;
  // The Taylor form of the step: for s in [0, h], with V(s) = sum_i s^i V_i,
  //   x(t0 + s) in sum_i s^i (c_i + q_i) + V(s) C r0 + V(s) P(r0) + V(s) B r + s^(k+1) R,
  // c_i the Taylor coefficients at m, V_i their Jacobian there, q_i the second-order term (half
  // the second derivative of coefficient i along C r0 + B r, over the set) and R coefficient k+1
  // over the a priori box.
  std::vector<Interval> centre;     // (k+1) x n, row i = c_i
  std::vector<Interval> jacobian;   // (k+1) x n x n, block i = V_i (row-major)
  std::vector<Interval> second;     // (k+1) x n, row i = q_i
  std::vector<Interval> remainder;  // n

  // A step of another flow (the Taylor-model flow's as a Tube, taylor_model_flow.hpp) holds only
  // t0, t1, h, over and end: its enclosure inside [t0, t1] is `over`.
  bool has_form() const { return !centre.empty(); }
};

class Tube {
 public:
  std::size_t dimension = 0;
  int order = 0;
  double t_start = 0.0;
  Box initial;
  std::vector<Interval> r0;  // initial minus its midpoint (for steps without their own r0)
  std::vector<TubeStep> steps;

  // The last time covered (t_start if no step).
  double t_end() const { return steps.empty() ? t_start : steps.back().t1; }
  // An enclosure of every solution at time t: the tight enclosure at a step's end, the step's
  // Taylor form inside it. A box of empty intervals outside [t_start, t_end()].
  Box enclosure_at(double t) const;
  // An enclosure of every solution over [ta, tb] (the hull of the steps' enclosures over their
  // parts of it). Empty outside [t_start, t_end()] or when ta > tb.
  Box enclosure_over(double ta, double tb) const;
  // The Taylor form of step i over s (a part of [0, h]), not intersected with anything; a step
  // without a form gives its box over the step.
  Box step_form(std::size_t i, const Interval& s) const;
};

// An enclosure wider than max_width, which ended a run: the widest component (its index in the
// state), its width and the limit, in that component's own unit, and the time [s]. The numbers
// the reason's text gives, for callers that write them in units of their own.
struct WidthStop {
  std::size_t component = 0;
  double width = 0.0;
  double max_width = 0.0;
  double t = 0.0;
};

// The widest component of `x` (an unbounded one is infinitely wide) against `max_width` at `t`.
WidthStop widest_component(const Box& x, double max_width, double t);

struct IntegrationResult {
  enum class Status { ok, step_not_validated, width_exceeded };

  Tube tube;
  Status status = Status::ok;
  double t_failed = std::numeric_limits<double>::quiet_NaN();  // where the run ended, on failure
  std::string reason;                                          // why, on failure
  std::optional<WidthStop> width_stop;  // with width_exceeded by max_width: its numbers
  std::size_t steps = 0;                // accepted steps
  std::size_t rejected = 0;  // attempts rejected (Picard not validated, remainder too wide)
  std::size_t qr_steps = 0;  // steps that used the QR frame (the others: the parallelepiped)
  double seconds = 0.0;      // wall time of the integration

  bool ok() const { return status == Status::ok; }
};

const char* to_string(IntegrationResult::Status status);

// How much the error part of a doubleton outgrows its exact part: the largest ratio of the
// widths error[v] / exact[v] over the components whose exact width is at least 5 % of the
// widest one (0 when all are 0).
double excess_ratio(const std::vector<double>& exact, const std::vector<double>& error);

// The integrator on recorded fields: tapes[k] is the field of piece k (switches.size() + 1 of
// them; see ode.hpp for pieces). x0 has tapes' dimension (1..16), bounded non-empty components.
// Invalid arguments throw std::invalid_argument; integration failures are a status.
IntegrationResult integrate_tapes(const std::vector<Tape>& tapes,
                                  const std::vector<double>& switches, const Box& x0,
                                  const IntegratorOptions& options);

// Continues `tube` (a run from tube.initial, same tapes, switches and order) for the solutions
// from `piece`, a sub-box of tube.initial, from the start of tube.steps[step] on: the result's
// tube holds copies of steps 0..step-1 (they enclose the piece's solutions as well), then its own
// steps from the doubleton of step `step`, re-centred on the piece (every solution from x0 =
// origin + rho is in m + C rho + B r, so a piece of r0 gives a doubleton of its own, whose
// second-order terms shrink with the piece). options.t_start is ignored (tube.t_start holds).
// std::invalid_argument for a piece outside tube.initial, a bad step or options.
IntegrationResult integrate_sub_box(const std::vector<Tape>& tapes,
                                    const std::vector<double>& switches, const Tube& tube,
                                    std::size_t step, const Box& piece,
                                    const IntegratorOptions& options);

// The fields of a system (ode.hpp), one tape per piece of its input.
template <class System>
std::vector<Tape> record_system(const System& system) {
  const std::vector<double> switches = switch_times(system);
  std::vector<Tape> tapes;
  for (std::size_t piece = 0; piece <= switches.size(); ++piece) {
    tapes.push_back(record([&](std::span<const Recorder> x,
                               std::span<Recorder> dx) { evaluate_field(system, piece, x, dx); },
                           System::dimension));
  }
  return tapes;
}

// Validated integration of a system (ode.hpp) from the box x0 over [t_start, t_end].
template <class System>
IntegrationResult integrate(const System& system, const Box& x0, const IntegratorOptions& options) {
  return integrate_tapes(record_system(system), switch_times(system), x0, options);
}

}  // namespace furuta::validated
