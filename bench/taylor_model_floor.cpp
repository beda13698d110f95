// Measures the floor under any Taylor-model tube of the Furuta benchmarks' interval-parameter box
// (issue 22): the flow's step (taylor_model_flow_core.hpp) run with its error part thrown away
// after every step and no shrink wrapping, so that each step starts from the polynomial alone.
// What is left is the models' own truncation, the error that the field's evaluation on the
// polynomial adds whatever is done with the errors before it. NOT a sound tube: a diagnostic.
//
//   taylor_model_floor [SCENARIO 0-3] [SCALE] [ORDER] [T_END_S] [EVERY]
//
// The box is validated_bench's BM_FurutaTaylorModels box times SCALE (1: mu's +-2 %, fv1 +-10 %,
// fv2 +-50 %; the state +-1e-3, q2 +-1.6e-3). Prints every EVERY-th step: the time, the step, the
// polynomial's q2 width, the step's new error in q2 and dq2, that dq2 error per second of step
// (the field's remainder, rad/s^2), and the q2 error that the new errors would build up if they
// were only carried by the kinematics (dq2 errors summed, integrated into q2): an estimate of what
// a tube must add to the spread, not a bound. Then, at every 0.25 s reached, that estimate
// against the spread of q2 over 400 sampled solutions (parameters drawn in their intervals, the
// corners among them, starts in the state box; RK4 at 0.25 ms), and where the field's truncation
// comes from at that time: the range of the mass matrix's determinant over the set, its
// reciprocal's remainder against the reciprocal's magnitude, and the accelerations' remainders.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "furuta/model/model.hpp"
#include "furuta/validated/integrator.hpp"
#include "furuta/validated/ode.hpp"
#include "furuta/validated/taylor_model_flow.hpp"
#include "interval_matrix.hpp"
#include "taylor_model_flow_core.hpp"

namespace {

using furuta::interval::Box;
using furuta::interval::Interval;
namespace v = furuta::validated;

struct Scenario {
  double q2_deg;
  double tau_nm;
};
constexpr Scenario kScenarios[] = {{-100.0, 0.0}, {50.0, 0.0}, {-90.0, 0.17}, {-45.0, -0.1}};

double argument(int argc, char** argv, int i, double fallback, const char* name) {
  if (argc <= i) return fallback;
  char* end = nullptr;
  const double x = std::strtod(argv[i], &end);
  if (end == argv[i] || *end != '\0') {
    std::fprintf(stderr, "taylor_model_floor: argument %d (%s): not a number: '%s'\n", i, name,
                 argv[i]);
    std::exit(2);
  }
  return x;
}

// The spread (max - min) of q2 at t = dt_s, 2 dt_s, ... up to t_end_s.
std::vector<double> sampled_q2_spread(const furuta::model::Parameters<Interval>& p,
                                      const Box& state, double tau_nm, double dt_s,
                                      double t_end_s) {
  constexpr int kDraws = 400;
  constexpr double kStepS = 2.5e-4;
  const auto marks = static_cast<std::size_t>(std::floor(t_end_s / dt_s + 1e-9));
  std::vector<double> lo(marks, HUGE_VAL), hi(marks, -HUGE_VAL);
  std::mt19937_64 rng(22);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto in = [&](const Interval& x, double u) { return x.lo() + u * (x.hi() - x.lo()); };
  for (int d = 0; d < kDraws; ++d) {
    furuta::model::Parameters<double> pd;
    for (std::size_t i = 0; i < pd.size(); ++i) {
      // The first 128 draws are the parameter box's corners.
      pd[i] = in(p[i], d < 128 ? static_cast<double>((d >> i) & 1) : unit(rng));
    }
    furuta::model::PendulumState x{in(state[0], unit(rng)), in(state[1], unit(rng)),
                                   in(state[2], unit(rng)), in(state[3], unit(rng))};
    const auto steps_per_mark = static_cast<int>(std::lround(dt_s / kStepS));
    for (std::size_t m = 0; m < marks; ++m) {
      for (int k = 0; k < steps_per_mark; ++k) {
        x = furuta::model::rk4_step(pd, x, kStepS, [&](const auto&) { return tau_nm; });
      }
      lo[m] = std::min(lo[m], x.q2);
      hi[m] = std::max(hi[m], x.q2);
    }
  }
  std::vector<double> spread(marks);
  for (std::size_t m = 0; m < marks; ++m) spread[m] = hi[m] - lo[m];
  return spread;
}

struct FieldTruncation {
  Interval det;                     // the mass matrix's determinant over the set
  double reciprocal_remainder = 0;  // 1/det's remainder over 1/det's magnitude
  double ddq1_remainder = 0;        // rad/s^2
  double ddq2_remainder = 0;        // rad/s^2
};

// The field on the polynomial p (FurutaDynamics' components), the determinant as the model
// forms it (model/dynamics.hpp: m11 mu4 - m12^2).
FieldTruncation field_truncation(const std::vector<v::TaylorModel>& p, double tau_nm) {
  using C = v::FurutaDynamics::Component;
  const v::TaylorModel s = sin(p[C::q2]);
  const v::TaylorModel m11 = p[C::mu1] + p[C::mu2] * s * s;
  const v::TaylorModel m12 = p[C::mu3] * cos(p[C::q2]);
  const v::TaylorModel det = m11 * p[C::mu4] - m12 * m12;
  const v::TaylorModel inverse = reciprocal(det);
  const furuta::model::Parameters<v::TaylorModel> params{p[C::mu1], p[C::mu2], p[C::mu3], p[C::mu4],
                                                         p[C::mug], p[C::fv1], p[C::fv2]};
  const auto a =
      furuta::model::accelerations(params, p[C::q2], p[C::dq1], p[C::dq2], v::TaylorModel(tau_nm));
  return {det.bound(), inverse.remainder().mag() / inverse.polynomial_bound().mag(),
          a.ddq1.remainder().mag(), a.ddq2.remainder().mag()};
}

}  // namespace

int main(int argc, char** argv) {
  const int scenario = static_cast<int>(argument(argc, argv, 1, 0, "SCENARIO"));
  const double scale = argument(argc, argv, 2, 1.0, "SCALE");
  const int order = static_cast<int>(argument(argc, argv, 3, 3, "ORDER"));
  const double t_end = argument(argc, argv, 4, 2.0, "T_END_S");
  const int every = static_cast<int>(argument(argc, argv, 5, 10, "EVERY"));
  if (scenario < 0 || scenario > 3 || !(scale > 0.0) || order < 1 || order > 4 || !(t_end > 0.0) ||
      every < 1) {
    std::fprintf(stderr,
                 "taylor_model_floor: SCENARIO 0-3, SCALE > 0, ORDER 1-4, T_END_S > 0, "
                 "EVERY >= 1\n");
    return 2;
  }
  const Scenario& s = kScenarios[scenario];
  const auto truth = furuta::model::paper_run1();
  auto p = v::parameters_around(truth, 0.02 * scale);
  p.fv1 = Interval(truth.fv1) * (Interval(1.0) + Interval(-0.1 * scale, 0.1 * scale));
  p.fv2 = Interval(truth.fv2) * (Interval(1.0) + Interval(-0.5 * scale, 0.5 * scale));
  const double q2 = s.q2_deg * std::numbers::pi / 180.0;
  const Box state{Interval(-1e-3, 1e-3), Interval(-1e-3, 1e-3), Interval(q2 - 1.6e-3, q2 + 1.6e-3),
                  Interval(-1e-3, 1e-3)};
  const Box x0 = v::FurutaDynamics::initial_box(state, p);

  // validated_bench's options for the Taylor-model tubes, without the wrap.
  v::TaylorModelFlowOptions o;
  o.integrator.t_end = t_end;
  o.integrator.tolerance = 1e-8;
  o.integrator.max_inflation = 1.0;
  o.integrator.order = 8;
  o.integrator.max_width = 2.0 * std::numbers::pi;
  o.space_order = order;
  o.shrink_wrap_max_delta = 0.0;

  const v::FurutaDynamics system(Interval(s.tau_nm));
  const std::vector<v::Tape> tapes = v::record_system(system);
  const std::vector<double> switches = v::switch_times(system);
  const v::detail::TaylorModelFlowSetup setup(tapes, switches, x0, o);
  v::detail::TaylorModelFlowState flow = v::detail::initial_flow_state(setup, x0);
  v::detail::TaylorModelFlowRunners runners;
  v::TaylorModelFlowResult result;
  result.initial = x0;

  using C = v::FurutaDynamics::Component;
  double dq2_error = 0.0;  // the new errors in dq2, summed
  double q2_error = 0.0;   // ... and integrated into q2, with q2's own
  double largest_rate = 0.0;
  constexpr double kMarkS = 0.25;
  const std::vector<double> spread = sampled_q2_spread(p, state, s.tau_nm, kMarkS, t_end);
  std::vector<double> estimate_at_mark;
  std::vector<FieldTruncation> field_at_mark;
  std::printf("%8s %9s %10s %10s %10s %12s %10s\n", "t_s", "h_s", "q2_width", "new_q2", "new_dq2",
              "dq2_rate", "q2_est");
  for (int step = 0; flow.t < t_end; ++step) {
    const double t0 = flow.t;
    if (auto failure = v::detail::taylor_model_flow_step(setup, runners, flow, result)) {
      std::printf("failed at t = %.4f s: %s\n", flow.t, failure->reason.c_str());
      break;
    }
    const double h = flow.t - t0;
    // The error part after the step: the new error alone (the one before was zero).
    const std::vector<Interval> error = v::detail::from_point(flow.b) * flow.r;
    const double new_q2 = error[C::q2].width();
    const double new_dq2 = error[C::dq2].width();
    q2_error += new_q2 + dq2_error * h;
    dq2_error += new_dq2;
    largest_rate = std::max(largest_rate, new_dq2 / h);
    if (step % every == 0) {
      std::printf("%8.4f %9.2e %10.3e %10.3e %10.3e %12.3e %10.3e\n", flow.t, h,
                  result.steps.back().end[C::q2].width(), new_q2, new_dq2, new_dq2 / h, q2_error);
    }
    while (estimate_at_mark.size() < spread.size() &&
           flow.t >= kMarkS * static_cast<double>(estimate_at_mark.size() + 1) - 1e-12) {
      estimate_at_mark.push_back(q2_error);
      field_at_mark.push_back(field_truncation(flow.p, s.tau_nm));
    }
    for (Interval& r : flow.r) r = Interval(0.0);  // not sound: the point of the measurement
  }
  std::printf("\n%6s %13s %10s %8s %10s %8s %8s %8s\n", "t_s", "q2_spread_rad", "q2_est_rad",
              "ratio", "det_lo", "det_x", "1/det_r", "ddq_r");
  for (std::size_t m = 0; m < estimate_at_mark.size(); ++m) {
    const FieldTruncation& f = field_at_mark[m];
    std::printf("%6.2f %13.3e %10.3e %8.2f %10.3e %8.2f %8.4f %4.2g/%.2g\n",
                kMarkS * static_cast<double>(m + 1), spread[m], estimate_at_mark[m],
                (spread[m] + estimate_at_mark[m]) / spread[m], f.det.lo(), f.det.hi() / f.det.lo(),
                f.reciprocal_remainder, f.ddq1_remainder, f.ddq2_remainder);
  }
  std::printf(
      "(ratio: (spread + est) / spread; det_x: det's largest over its smallest on the set; "
      "1/det_r: the reciprocal's remainder over its magnitude; ddq_r: the accelerations' "
      "remainders, rad/s^2)\n");
  std::printf("reached %.4f s; largest dq2 rate %.3e rad/s^2; q2 estimate %.3e rad\n", flow.t,
              largest_rate, q2_error);
  return 0;
}
