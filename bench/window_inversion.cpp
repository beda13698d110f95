// How wide a parameter box one window's set inversion through the Taylor-model flow carries, and
// what it costs: synthetic readings (the model, RK4 at 10 us, a constant duty, each joint every
// 8 ms quantised to the default rig's counts, the pendulum 3 ms after the arm) from the scaled
// truth, inverted from the truth +- PERCENT with the start box the truth +- the given widths.
//
//   window_inversion PERCENT WINDOW_S [COUNT] [EVERY_S] [DQ_WIDTH_RAD_S] [SPACE_ORDER] [DUTY]
//
// Environment: FURUTA_WRAP_DELTA (shrink wrapping's limit, 0: none), FURUTA_JACOBIAN_ORDER,
// FURUTA_TIME_ORDER, FURUTA_PASSES (flows re-run over each pass's contracted box), FURUTA_REST=1
// with FURUTA_FIRST_T0=0 (the first window from rest).
//
// Prints the verdict, the flow's steps and time, the widest prediction against its reading,
// and each parameter's box after contraction against the one given.
#include "furuta/identification/window_inversion.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <vector>

#include "furuta/model/model.hpp"

namespace {

using namespace furuta;
using identification::RecordingWindow;
using interval::Box;
using interval::Interval;

constexpr double kArmResolution_rad = 2 * std::numbers::pi / (1024 * 26.0);
constexpr double kPendulumResolution_rad = 2 * std::numbers::pi / 4096;

double first_t0_s() {
  const char* at = std::getenv("FURUTA_FIRST_T0");
  return at ? std::atof(at) : 0.05;
}

// A swinging start (FURUTA_REST=1: at rest, hanging), bang-bang +-DUTY switching every 0.15 s
// (instantly: the board's ramp is not modelled here), the readings of each joint every 8 ms;
// windows of `length_s` every `every_s`, each with its start box the truth +- the widths given (the
// start as a measurement would not give it: this measures the parameters' side alone).
std::vector<RecordingWindow> windows_from(const model::Parameters<double>& p,
                                          model::PendulumState x, double duty, double length_s,
                                          int count, double every_s, double dq_width) {
  std::vector<RecordingWindow> windows;
  double t = 0.0;
  const auto duty_at = [&](double time) {
    return (static_cast<int>(std::floor(time / 0.15)) % 2 == 0) ? duty : -duty;
  };
  const auto advance = [&](double to) {
    while (t < to - 1e-12) {
      const double next_switch = 0.15 * (std::floor(t / 0.15 + 1e-9) + 1);
      const double h = std::min({1e-5, to - t, next_switch - t});
      const double d = duty_at(t + h / 2);
      x = model::rk4_step(p, x, h, [&](const model::PendulumState&) { return d; });
      t += h;
    }
  };
  for (int i = 0; i < count; ++i) {
    const double t0 = first_t0_s() + i * every_s;
    advance(t0);
    RecordingWindow w;
    w.t0_s = t0;
    w.t1_s = t0 + length_s;
    w.start = Box{Interval(x.q1 - kArmResolution_rad, x.q1 + kArmResolution_rad),
                  Interval(x.dq1 - dq_width, x.dq1 + dq_width),
                  Interval(x.q2 - kPendulumResolution_rad, x.q2 + kPendulumResolution_rad),
                  Interval(x.dq2 - dq_width, x.dq2 + dq_width)};
    for (double s0 = 0.15 * std::floor(t0 / 0.15); s0 < w.t1_s; s0 += 0.15) {
      w.duty.push_back({std::max(s0, t0), Interval(duty_at(std::max(s0, t0) + 1e-9))});
    }
    std::vector<std::pair<double, int>> times;
    for (int k = static_cast<int>(std::floor(t0 / 0.008)) + 1; 0.008 * k <= w.t1_s; ++k) {
      if (0.008 * k > t0) times.push_back({0.008 * k, 0});
    }
    for (int k = static_cast<int>(std::floor(t0 / 0.008)); 0.003 + 0.008 * k <= w.t1_s; ++k) {
      if (0.003 + 0.008 * k > t0) times.push_back({0.003 + 0.008 * k, 1});
    }
    std::sort(times.begin(), times.end());
    for (const auto& [at, joint] : times) {
      advance(at);
      const double res = joint == 0 ? kArmResolution_rad : kPendulumResolution_rad;
      const double count_read = std::floor((joint == 0 ? x.q1 : x.q2) / res);
      w.readings.push_back({at, joint, Interval(count_read * res, (count_read + 1) * res)});
    }
    windows.push_back(std::move(w));
  }
  return windows;
}

}  // namespace

int main(int argc, char** argv) {
  const double percent = argc > 1 ? std::atof(argv[1]) : 1.0;
  const double length_s = argc > 2 ? std::atof(argv[2]) : 0.05;
  const int count = argc > 3 ? std::atoi(argv[3]) : 1;
  const double every_s = argc > 4 ? std::atof(argv[4]) : 0.1;
  const double dq_width = argc > 5 ? std::atof(argv[5]) : 0.02;
  const int order = argc > 6 ? std::atoi(argv[6]) : 3;
  const double duty = argc > 7 ? std::atof(argv[7]) : 0.3;
  const model::PendulumState s = std::getenv("FURUTA_REST")
                                     ? model::PendulumState{}
                                     : model::PendulumState{0.0, 0.0, 0.6, -4.0};
  const model::Parameters<double> p = model::paper_run1();
  const double g = 7.3;
  const model::Parameters<double> truth{p.mu1 / g, p.mu2 / g,           p.mu3 / g, p.mu4 / g,
                                        p.mug / g, (p.fv1 + 0.155) / g, p.fv2 / g};
  const std::vector<RecordingWindow> windows =
      windows_from(truth, s, duty, length_s, count, every_s, dq_width);
  const model::Parameters<Interval> box = truth.map(
      [&](double v) { return Interval(v * (1 - percent / 100), v * (1 + percent / 100)); });
  identification::WindowOptions o;
  o.flow.integrator.order = 8;
  o.flow.integrator.tolerance = 1e-8;
  o.flow.integrator.max_inflation = 1.0;
  o.flow.integrator.max_width = 2 * std::numbers::pi;
  o.flow.space_order = order;
  o.flow.wrap_without_collapsed = true;
  o.flow.wrap_at_base_point = true;
  o.flow.shrink_wrap_max_delta = 1.0;  // the wraps tie the start variables (FURUTA_WRAP_DELTA)
  if (const char* wrap = std::getenv("FURUTA_WRAP_DELTA"))
    o.flow.shrink_wrap_max_delta = std::atof(wrap);
  if (const char* jo = std::getenv("FURUTA_JACOBIAN_ORDER")) o.flow.jacobian_order = std::atoi(jo);
  if (const char* to = std::getenv("FURUTA_TIME_ORDER")) o.flow.integrator.order = std::atoi(to);
  // FURUTA_PASSES=N: the flows run again over each pass's contracted box (narrower models).
  if (const char* passes = std::getenv("FURUTA_PASSES")) o.max_passes = std::atoi(passes);
  const identification::WindowOutcome out = identification::invert_windows(windows, box, o);
  const char* verdicts[] = {"inconsistent", "contracted", "flow_failed"};
  std::printf(
      "+-%g %%, %d windows of %g s every %g s, dq +-%g, order %d: %s; %zu steps in "
      "%.2f s, %zu passes, %zu sweeps, widest prediction %.3g readings%s%s\n",
      percent, count, length_s, every_s, dq_width, order, verdicts[static_cast<int>(out.verdict)],
      out.flow_steps, out.flow_seconds, out.passes, out.sweeps, out.widest_prediction,
      out.reason.empty() ? "" : "; ", out.reason.c_str());
  const char* names[] = {"mu1", "mu2", "mu3", "mu4", "mug", "b", "fv2"};
  const Interval got[] = {out.parameters.mu1, out.parameters.mu2, out.parameters.mu3,
                          out.parameters.mu4, out.parameters.mug, out.parameters.fv1,
                          out.parameters.fv2};
  const double truths[] = {truth.mu1, truth.mu2, truth.mu3, truth.mu4,
                           truth.mug, truth.fv1, truth.fv2};
  for (int i = 0; i < 7; ++i) {
    std::printf("  %-4s +-%6.3f %% of the truth (given +-%g %%), truth inside: %s\n", names[i],
                100 * got[i].rad() / truths[i], percent, got[i].contains(truths[i]) ? "yes" : "NO");
  }
  return 0;
}
