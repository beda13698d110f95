#pragma once
// A validated simulation of the balancing loop (docs/control.md, "What the verifier proves"): the
// nonlinear plant between samples for every parameter in a box, the encoders' readings within half
// a count, the balance law's filter and gain exactly as it computes them, its duty rounded to the
// board's step, the board taking each duty after a lag anywhere in an interval and ramping to it.
// From every start in a box it encloses the loop's state at each sample and over each period, and
// checks that the pendulum stays within a stated angle of upright, the arm within its limit, and
// the law's duty within its limit, so that the law runs as the enclosure assumes.
//
//   BalanceCertificate c = verify_balance(spec, loop, start, limits, options);
//   if (c.certified()) ... c.steps (every period's boxes)
//   else ... c.failure (what left which bound, when)
//
// Numbers in, numbers out: the command line and the report make the text.

#include <array>
#include <cstddef>
#include <optional>
#include <vector>

#include "furuta/control/balance_law.hpp"
#include "furuta/interval/interval.hpp"
#include "furuta/model/parameters.hpp"

namespace furuta::verification {

using interval::Interval;

// x = [q1, q2 - pi, dq1, dq2]: the arm's angle, the pendulum's from upright, their rates.
using StateBox = std::array<Interval, 4>;

// The loop as it runs, each uncertain quantity as an interval.
struct LoopModel {
  model::Parameters<Interval> parameters;  // the plant's, every one > 0 (frictions >= 0)
  Interval duty_torque_nm;                 // eq. 4 at the supply: torque = kd duty - kw dq1
  Interval back_emf_nm_s;
  // When the board takes each duty after its sample: anywhere in this interval, within
  // [0, period]; it then ramps its applied duty towards it at ramp_duty_per_s (0: at once).
  Interval lag_s;
  double ramp_duty_per_s = 0;
  // Each sample's angles were read this long before it (in [0, period]), and the law is told so.
  double reading_age_s = 0;
  // A reading is within half a count of the angle at its instant.
  double arm_count_rad = 0;
  double pendulum_count_rad = 0;
};

// The loop at t = 0: the law has just taken over (control::BalanceLaw::start_catch) with its
// filter's estimate off the plant's state by anything in `estimate_error` (the state anywhere in
// `state`); no duty is on its way, the board applies none.
struct LoopStart {
  StateBox state;
  StateBox estimate_error;
};

// What is proven over the horizon: |q2 - pi| < upright_rad and |q1| < arm_rad at every instant.
struct LoopLimits {
  double upright_rad = 0;
  double arm_rad = 0;
};

struct VerifyOptions {
  double horizon_s = 10.0;
  // The loop's state is carried as affine forms in shared noise symbols (a zonotope); beyond
  // this many symbols the smallest are merged into one per component (Girard's reduction).
  std::size_t max_symbols = 1000;
};

// One loop period, [t0_s, t1_s] from the start.
struct LoopStepBox {
  double t0_s = 0;
  double t1_s = 0;
  StateBox over;      // the plant's state at every instant of the period
  StateBox at_end;    // the plant's state at t1_s
  StateBox estimate;  // the filter's estimate at t1_s
  Interval duty;      // the duty the law sends at t1_s
};

enum class FailureKind {
  pendulum_limit,  // |q2 - pi| may reach upright_rad
  arm_limit,       // |q1| may reach arm_rad
  duty_limit,      // the law's duty may reach its limit (the enclosure assumes it does not)
  law_mode,        // a reading may leave the law's balance region (release or fall angle)
  // The enclosure of a period's motion did not close: the nonlinear and parametric remainder,
  // taken over the tube, grew it faster than the loop contracts it (the tube diverged).
  no_enclosure,
};

// Why the proof stopped: the quantity's enclosure against its bound, and when.
struct Failure {
  FailureKind kind = FailureKind::no_enclosure;
  double t_s = 0;
  Interval value;    // the enclosure that reached the bound (radians or duty)
  double limit = 0;  // the bound
};

struct BalanceCertificate {
  std::vector<LoopStepBox> steps;  // every period proven, in order
  std::optional<Failure> failure;  // none: certified to the horizon
  double horizon_s = 0;
  double seconds = 0;  // wall time
  std::size_t largest_symbol_count = 0;
  std::size_t pieces = 1;  // of the start and parameter boxes, each proven on its own
  // From this instant on (0: none) the tube is one run from the hull of the pieces' states there.
  double handover_s = 0;

  bool certified() const { return !failure.has_value(); }
};

// Throws std::invalid_argument for a law with more than one duty on its way, a lag or reading age
// outside [0, period], non-positive counts, unbounded boxes or a horizon that is not > 0.
BalanceCertificate verify_balance(const control::BalanceControllerSpec& law, const LoopModel& loop,
                                  const LoopStart& start, const LoopLimits& limits,
                                  const VerifyOptions& options);

// verify_balance over pieces of the start and parameter boxes: a piece that is not certified is
// halved, its start along the pendulum's angle or rate (the wider for its share of the start) while
// it is wider than an eighth of the start's, then the parameters and the start in turn; the
// parameters along the one that moves the plant most for its width (the mass matrix's: its inverse
// at upright changes by mu1 mu4 / det(M) per relative change of mu1 or mu4 and by 2 mu3^2 / det(M)
// of mu3; the arm's damping by fv1 / (kw + fv1) of fv1); until every piece is certified or
// max_pieces would be passed. The pieces run in parallel. Certified: every piece is, and the
// boxes are the pieces' hulls; else the failure of the piece that failed first.
struct SplitOptions {
  std::size_t max_pieces = 32;
  // > 0: the pieces run to 1, 2 and 3 times this instant (whole periods), and one run from the
  // hull of their states there, the loop's whole state (plant, filter, duties on their way) as a
  // box, proves the rest when it is certified (the loop is the same at every sample); else the
  // pieces run to the horizon. The box loses the pieces' correlations: it pays for long horizons
  // with a point-like parameter box, rarely otherwise. 0: the pieces run to the horizon.
  double handover_s = 0.0;
};
BalanceCertificate verify_balance_split(const control::BalanceControllerSpec& law,
                                        const LoopModel& loop, const LoopStart& start,
                                        const LoopLimits& limits, const VerifyOptions& options,
                                        const SplitOptions& split);

// The largest start certified (by verify_balance_split) among `start`'s plant box scaled about its
// centre (the filter's error as given):
// bisection on the scale in (0, max_scale] to `steps` halvings. scale 0 when even the smallest
// tried is not certified.
struct StartRegion {
  double scale = 0;
  LoopStart start;                 // `start` at that scale
  BalanceCertificate certificate;  // at that scale (the last failure when scale is 0)
  int verifications = 0;
};
StartRegion largest_start(const control::BalanceControllerSpec& law, const LoopModel& loop,
                          const LoopStart& start, const LoopLimits& limits,
                          const VerifyOptions& options, const SplitOptions& split, double max_scale,
                          int steps);

}  // namespace furuta::verification
