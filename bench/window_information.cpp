// Which windows of a recording constrain which parameters, before any interval method: the
// readings' sensitivity to each scaled parameter and to the window's start, by finite differences
// of the model's trajectories (RK4 at 10 us), and the spread a least-squares fit of the window's
// readings alone would have with the encoders' rounding as its only error (a uniform count: sd of
// 1/sqrt(12) count). A guaranteed set cannot be narrower than what the readings resolve, so these
// figures say which windows a set inversion should take, and what it can reach at best.
//
//   window_information [WINDOW_S] [SECONDS] [SWITCH_S]
//
// Synthetic run: from rest, hanging, bang-bang +-0.3 switching every SWITCH_S (instantly), each
// joint read every 8 ms (the pendulum 3 ms after the arm), 26,624 and 4,096 counts a turn. For
// each window phase (its start after the last switch) prints the sd in % of each parameter from
// one window, then from every window of that phase in SECONDS together (the parameters shared,
// each window's start its own).
#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <vector>

#include "furuta/model/model.hpp"

namespace {

using namespace furuta;

constexpr double kArmResolution_rad = 2 * std::numbers::pi / (1024 * 26.0);
constexpr double kPendulumResolution_rad = 2 * std::numbers::pi / 4096;
constexpr double kDuty = 0.3;

double duty_at(double t, double switch_s) {
  return (static_cast<long>(std::floor(t / switch_s + 1e-12)) % 2 == 0) ? kDuty : -kDuty;
}

// The state at t_s from rest.
model::PendulumState state_at(const model::Parameters<double>& p, double t_s, double switch_s) {
  model::PendulumState x{0.0, 0.0, 0.0, 0.0};
  double t = 0.0;
  while (t < t_s - 1e-12) {
    const double next_switch = switch_s * (std::floor(t / switch_s + 1e-9) + 1);
    const double h = std::min({1e-5, t_s - t, next_switch - t});
    const double d = duty_at(t + h / 2, switch_s);
    x = model::rk4_step(p, x, h, [&](const model::PendulumState&) { return d; });
    t += h;
  }
  return x;
}

// The readings (in counts, unrounded) of the window [t0, t0 + length] from `start`.
std::vector<double> readings(const model::Parameters<double>& p, model::PendulumState x, double t0,
                             double length_s, double switch_s) {
  std::vector<std::pair<double, int>> times;
  for (long k = static_cast<long>(std::floor(t0 / 0.008)); 0.008 * k <= t0 + length_s; ++k) {
    if (0.008 * k > t0) times.push_back({0.008 * k, 0});
    if (0.003 + 0.008 * k > t0 && 0.003 + 0.008 * k <= t0 + length_s) {
      times.push_back({0.003 + 0.008 * k, 1});
    }
  }
  std::sort(times.begin(), times.end());
  std::vector<double> out;
  double t = t0;
  for (const auto& [at, joint] : times) {
    while (t < at - 1e-12) {
      const double next_switch = switch_s * (std::floor(t / switch_s + 1e-9) + 1);
      const double h = std::min({1e-5, at - t, next_switch - t});
      const double d = duty_at(t + h / 2, switch_s);
      x = model::rk4_step(p, x, h, [&](const model::PendulumState&) { return d; });
      t += h;
    }
    out.push_back(joint == 0 ? x.q1 / kArmResolution_rad : x.q2 / kPendulumResolution_rad);
  }
  return out;
}

std::array<double, 7> as_array(const model::Parameters<double>& p) {
  return {p.mu1, p.mu2, p.mu3, p.mu4, p.mug, p.fv1, p.fv2};
}
model::Parameters<double> from_array(const std::array<double, 7>& a) {
  return {a[0], a[1], a[2], a[3], a[4], a[5], a[6]};
}

// Columns: the 7 parameters (counts per 1 %), then q1, dq1, q2, dq2 of the start (counts per
// count, per 0.01 rad/s).
Eigen::MatrixXd sensitivity(const model::Parameters<double>& p, double t0, double length_s,
                            double switch_s) {
  const model::PendulumState start = state_at(p, t0, switch_s);
  const std::vector<double> base = readings(p, start, t0, length_s, switch_s);
  Eigen::MatrixXd j(static_cast<Eigen::Index>(base.size()), 11);
  const auto column = [&](int c, const std::vector<double>& plus, const std::vector<double>& minus,
                          double per) {
    for (std::size_t k = 0; k < base.size(); ++k) {
      j(static_cast<Eigen::Index>(k), c) = (plus[k] - minus[k]) / (2 * per);
    }
  };
  const std::array<double, 7> a = as_array(p);
  for (int i = 0; i < 7; ++i) {
    std::array<double, 7> up = a, down = a;
    up[i] *= 1.0001;
    down[i] *= 0.9999;
    column(i, readings(from_array(up), start, t0, length_s, switch_s),
           readings(from_array(down), start, t0, length_s, switch_s), 0.01);
  }
  const double steps[] = {kArmResolution_rad, 0.01, kPendulumResolution_rad, 0.01};
  for (int s = 0; s < 4; ++s) {
    model::PendulumState up = start, down = start;
    double* u[] = {&up.q1, &up.dq1, &up.q2, &up.dq2};
    double* d[] = {&down.q1, &down.dq1, &down.q2, &down.dq2};
    *u[s] += 1e-3 * steps[s];
    *d[s] -= 1e-3 * steps[s];
    column(7 + s, readings(p, up, t0, length_s, switch_s),
           readings(p, down, t0, length_s, switch_s), 1e-3);
  }
  return j;
}

// The parameters' sd in % from the information of the given windows (each its own start).
std::array<double, 7> spread(const std::vector<Eigen::MatrixXd>& windows) {
  const double variance = 1.0 / 12.0;  // a uniform count
  Eigen::MatrixXd info = Eigen::MatrixXd::Zero(7, 7);
  for (const Eigen::MatrixXd& j : windows) {
    // The start is each window's own: its information is taken out (the Schur complement).
    const Eigen::MatrixXd f = j.transpose() * j / variance;
    const Eigen::MatrixXd pp = f.topLeftCorner(7, 7);
    const Eigen::MatrixXd ps = f.topRightCorner(7, 4);
    const Eigen::MatrixXd ss = f.bottomRightCorner(4, 4);
    info += pp - ps * ss.ldlt().solve(ps.transpose());
  }
  const Eigen::MatrixXd covariance = info.inverse();
  std::array<double, 7> sd{};
  for (int i = 0; i < 7; ++i) sd[i] = std::sqrt(std::max(0.0, covariance(i, i)));
  return sd;
}

}  // namespace

int main(int argc, char** argv) {
  const double length_s = argc > 1 ? std::atof(argv[1]) : 0.1;
  const double seconds = argc > 2 ? std::atof(argv[2]) : 10.0;
  const double switch_s = argc > 3 ? std::atof(argv[3]) : 0.3;
  const model::Parameters<double> p = model::paper_run1();
  const double g = 7.3;
  const model::Parameters<double> truth{p.mu1 / g, p.mu2 / g,           p.mu3 / g, p.mu4 / g,
                                        p.mug / g, (p.fv1 + 0.155) / g, p.fv2 / g};
  std::printf(
      "windows of %g s, switches every %g s, %g s of data; sd in %% (counts' rounding "
      "alone)\n",
      length_s, switch_s, seconds);
  std::printf("%-24s %8s %8s %8s %8s %8s %8s %8s\n", "window start", "mu1", "mu2", "mu3", "mu4",
              "mug", "b", "fv2");
  for (const double phase : {0.0, 0.02, 0.05, 0.1, 0.2}) {
    if (phase + length_s > switch_s * 2) continue;
    std::vector<Eigen::MatrixXd> all;
    for (double t0 = switch_s + phase; t0 + length_s <= seconds; t0 += switch_s) {
      all.push_back(sensitivity(truth, t0, length_s, switch_s));
    }
    if (all.empty()) continue;
    const std::array<double, 7> one = spread({all.front()});
    const std::array<double, 7> every = spread(all);
    std::printf("%4.2f s after a switch, one  ", phase);
    for (double v : one) std::printf(" %8.3g", v);
    std::printf("\n%4.2f s after a switch, %3zu  ", phase, all.size());
    for (double v : every) std::printf(" %8.3g", v);
    std::printf("\n");
  }
  return 0;
}
