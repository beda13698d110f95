// Measures, before choosing (issue 20), how narrow a guaranteed set set inversion through the ODE
// gives: windows of the recorded angles between the duty's changes, each integrated by the
// validated integrator from its start box with the scaled parameters carried as state; every
// measured angle is a linear constraint on (start, parameters) through the tube's affine form,
// and all windows together contract the parameters soundly (a left inverse in interval
// arithmetic), then the tubes are run again over the smaller box.
//
//   guaranteed_windows [PRIOR_PERCENT] [WINDOW_S] [START_VELOCITY_RAD_S] [ROUNDS] [SETTLE_S]
//
// Synthetic data (the model, RK4 at 0.1 ms, bang-bang +-0.3 with the board's ramp, both angles
// every 8 ms quantised to the default rig's counts). Parameters: the truth +- PRIOR_PERCENT; the
// windows start SETTLE_S after a ramp ends; their start velocities are the truth +- the given
// width (a measurement of the formulation at its most favourable, not of how starts are bounded).
// Prints, per round, the windows whose tube failed, the widest unexplained part of a measured
// angle (the affine form's offset) and the parameters' box against the truth.
#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <random>
#include <vector>

#include "furuta/interval/interval.hpp"
#include "furuta/model/model.hpp"
#include "furuta/validated/integrator.hpp"
#include "furuta/validated/ode.hpp"
#include "furuta/validated/research/affine_enclosure.hpp"

namespace {

using namespace furuta;
using interval::Box;
using interval::Interval;
using validated::FurutaDynamics;

constexpr double kArmRes = 2 * std::numbers::pi / (1024 * 26.0);
constexpr double kPendulumRes = 2 * std::numbers::pi / 4096;

struct Observation {
  double t = 0;
  double y1 = 0, y2 = 0;  // quantised (floor) angles
  model::PendulumState truth;
};

struct Stretch {
  double t0 = 0, t1 = 0;
  double duty = 0;
};

struct Data {
  std::vector<Observation> obs;
  std::vector<Stretch> stretches;  // constant duty
};

Data simulate(unsigned seed, double seconds, const model::Parameters<double>& p,
              const model::MotorData& motor) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(0.35, 0.65);
  Data d;
  model::PendulumState x{0, 0, 0, 0};
  const double dt = 1e-4, rate = 62.5, amplitude = 0.3;
  double target = amplitude, applied = 0, next_switch = jitter(rng), stretch_start = -1;
  int steps = 0;
  for (double t = 0; t < seconds; t = (++steps) * dt) {
    if (steps % 80 == 0) {
      d.obs.push_back({t, std::floor(x.q1 / kArmRes) * kArmRes,
                       std::floor(x.q2 / kPendulumRes) * kPendulumRes, x});
    }
    if (t >= next_switch || (x.q1 > 1.5 && target > 0) || (x.q1 < -1.5 && target < 0)) {
      target = -target;
      next_switch = t + jitter(rng);
    }
    const double before = applied;
    const double step = std::clamp(target - applied, -rate * dt, rate * dt);
    applied += step;
    if (applied == target && before != target) stretch_start = t + dt;
    if (applied != target && stretch_start >= 0) {
      d.stretches.push_back({stretch_start, t, before});
      stretch_start = -1;
    }
    x = model::rk4_step(p, x, dt, [&](const model::PendulumState& s, double fraction) {
      return motor.arm_torque_nm(before + fraction * step, s.dq1);
    });
  }
  if (stretch_start >= 0) d.stretches.push_back({stretch_start, seconds, applied});
  return d;
}

struct Window {
  double duty = 0;
  std::vector<const Observation*> obs;
  Box x0;  // q1, dq1, q2, dq2
};

// One row: a . rho in y (rho = [dx0 (4), dtheta (7)]).
struct Row {
  std::array<double, 11> a{};
  Interval y;
};

}  // namespace

int main(int argc, char** argv) {
  const double prior_percent = argc > 1 ? std::atof(argv[1]) : 10;
  const double window_s = argc > 2 ? std::atof(argv[2]) : 0.1;
  const double v_width = argc > 3 ? std::atof(argv[3]) : 0.5;
  const int rounds = argc > 4 ? std::atoi(argv[4]) : 3;
  const double settle_s = argc > 5 ? std::atof(argv[5]) : 0.03;

  const model::Parameters<double> p = model::paper_run1();
  const model::MotorData motor;
  // Scaled parameters: the model divided by the drive gain g (tau = g d - k_w dq1), so the input
  // is the duty itself and the arm's damping b = (fv1 + k_w) / g.
  const double g = motor.arm_torque_nm(1.0, 0.0);
  const double kw = -motor.arm_torque_nm(0.0, 1.0);
  const std::array<double, 7> theta_true = {p.mu1 / g, p.mu2 / g,        p.mu3 / g, p.mu4 / g,
                                            p.mug / g, (p.fv1 + kw) / g, p.fv2 / g};
  std::printf("g %.4f N m, k_w %.4f N m s\n", g, kw);

  Box theta(7);
  for (int k = 0; k < 7; ++k) {
    theta[k] = Interval(theta_true[k] * (1 - prior_percent / 100),
                        theta_true[k] * (1 + prior_percent / 100));
  }

  std::vector<Data> sessions = {simulate(1, 10, p, motor), simulate(2, 10, p, motor)};
  {
    // What "the next derivative bounded by the model over the prior box" gives: the accelerations
    // over the prior box (the truth +- PRIOR_PERCENT) at one state of the data, known to its
    // counts and to +-START_VELOCITY.
    const Observation& o = sessions[0].obs[60];
    model::Parameters<Interval> box;
    const auto around = [&](double v) {
      return Interval(v * (1 - prior_percent / 100), v * (1 + prior_percent / 100));
    };
    box = {around(theta_true[0]), around(theta_true[1]), around(theta_true[2]),
           around(theta_true[3]), around(theta_true[4]), around(theta_true[5]),
           around(theta_true[6])};
    double duty = 0;
    for (const Stretch& st : sessions[0].stretches) {
      if (o.t >= st.t0 && o.t <= st.t1) duty = st.duty;
    }
    const model::JointAccelerations<Interval> a = model::accelerations(
        box, Interval(o.y2, o.y2 + kPendulumRes),
        Interval(o.truth.dq1 - v_width, o.truth.dq1 + v_width),
        Interval(o.truth.dq2 - v_width, o.truth.dq2 + v_width), Interval(duty));
    const model::JointAccelerations<double> truth =
        model::forward_dynamics(p, o.truth, motor.arm_torque_nm(duty, o.truth.dq1));
    std::printf(
        "at t = %.3f s (duty %.2f): ddq1 %.1f in [%.1f, %.1f], ddq2 %.1f in [%.1f, %.1f] rad/s^2\n",
        o.t, duty, truth.ddq1, a.ddq1.lo(), a.ddq1.hi(), truth.ddq2, a.ddq2.lo(), a.ddq2.hi());
  }
  std::vector<Window> windows;
  for (const Data& d : sessions) {
    for (const Stretch& s : d.stretches) {
      Window w;
      w.duty = s.duty;
      for (const Observation& o : d.obs) {
        if (o.t < s.t0 + settle_s || o.t > s.t1 - 1e-3) continue;
        if (!w.obs.empty() && o.t - w.obs.front()->t > window_s + 1e-9) {
          if (w.obs.size() >= 4) windows.push_back(w);
          w.obs.clear();
        }
        w.obs.push_back(&o);
      }
      if (w.obs.size() >= 4) windows.push_back(w);
    }
  }
  for (Window& w : windows) {
    const Observation& o = *w.obs.front();
    w.x0 =
        Box({Interval(o.y1, o.y1 + kArmRes), Interval(o.truth.dq1 - v_width, o.truth.dq1 + v_width),
             Interval(o.y2, o.y2 + kPendulumRes),
             Interval(o.truth.dq2 - v_width, o.truth.dq2 + v_width)});
  }
  std::printf("%zu windows of up to %.3f s\n", windows.size(), window_s);

  validated::IntegratorOptions options;
  options.tolerance = 1e-10;
  options.order = 12;
  options.max_inflation = 1.0;

  for (int round = 0; round < rounds; ++round) {
    const auto started = std::chrono::steady_clock::now();
    const std::vector<double> theta_mid = theta.mid();
    // Per window: T (rows x 7), X (rows x 4), Y (rows).
    Eigen::MatrixXd G = Eigen::MatrixXd::Zero(7, 7);
    struct Solved {
      Eigen::MatrixXd T, X, W;      // weighted
      std::vector<Interval> y;      // weighted
      Eigen::MatrixXd Lx;           // X^+ (4 x rows)
      Eigen::MatrixXd Pt;           // P T
      std::array<Interval, 4> dx0;  // the start's deviation from its box's midpoint
    };
    std::vector<Solved> solved;
    std::size_t failed = 0, steps = 0;
    double offset_width = 0;
    for (Window& w : windows) {
      Box x0(11);
      for (int k = 0; k < 4; ++k) x0[k] = w.x0[k];
      for (int k = 0; k < 7; ++k) x0[4 + k] = theta[k];
      options.t_start = w.obs.front()->t;
      options.t_end = w.obs.back()->t;
      const validated::IntegrationResult r =
          validated::integrate(FurutaDynamics(Interval(w.duty)), x0, options);
      if (!r.ok()) {
        if (failed == 0) {
          std::printf("first failure: %s at %.4f (window %.4f-%.4f, %zu steps)\n", r.reason.c_str(),
                      r.t_failed, options.t_start, options.t_end, r.steps);
        }
        ++failed;
        continue;
      }
      steps += r.steps;
      std::vector<Row> rows;
      for (const Observation* o : w.obs) {
        const validated::research::AffineEnclosure e = validated::research::affine_at(r.tube, o->t);
        for (int joint = 0; joint < 2; ++joint) {
          const int c = joint == 0 ? 0 : 2;
          const double res = joint == 0 ? kArmRes : kPendulumRes;
          const double y = joint == 0 ? o->y1 : o->y2;
          Row row;
          for (int k = 0; k < 11; ++k) row.a[k] = e.a[c * 11 + k];
          // rho is relative to the box's midpoint: the same theta_mid for every window.
          row.y = Interval(y, y + res) - e.offset[c];
          offset_width = std::max(offset_width, e.offset[c].width());
          rows.push_back(row);
        }
      }
      Solved s;
      const auto n = static_cast<Eigen::Index>(rows.size());
      s.T.resize(n, 7);
      s.X.resize(n, 4);
      s.W.resize(n, 1);
      for (Eigen::Index i = 0; i < n; ++i) {
        const double weight = 1.0 / std::max(rows[i].y.rad(), 1e-12);
        s.W(i, 0) = weight;
        for (int k = 0; k < 4; ++k) s.X(i, k) = weight * rows[i].a[k];
        for (int k = 0; k < 7; ++k) s.T(i, k) = weight * rows[i].a[4 + k];
        s.y.push_back(Interval(weight) * rows[i].y);
      }
      for (int k = 0; k < 4; ++k) s.dx0[k] = w.x0[k] - Interval(w.x0[k].mid());
      s.Lx = s.X.completeOrthogonalDecomposition().pseudoInverse();
      s.Pt = s.T - s.X * (s.Lx * s.T);
      G += s.T.transpose() * s.Pt;
      solved.push_back(std::move(s));
    }
    const Eigen::MatrixXd Ginv = G.inverse();
    // dtheta in sum_w L_w y_w + (I - sum_w L_w T_w) dtheta - sum_w (L_w X_w) dx_w.
    std::array<Interval, 7> acc{};
    for (auto& v : acc) v = Interval(0.0);
    Eigen::MatrixXd LT = Eigen::MatrixXd::Zero(7, 7);
    for (const Solved& s : solved) {
      const Eigen::MatrixXd L = Ginv * s.Pt.transpose();  // 7 x rows
      LT += L * s.T;
      // L X is zero up to rounding; its product with the start's deviation keeps the sum sound.
      const Eigen::MatrixXd LX = L * s.X;
      for (int k = 0; k < 7; ++k) {
        for (Eigen::Index i = 0; i < L.cols(); ++i) acc[k] += Interval(L(k, i)) * s.y[i];
        for (int j = 0; j < 4; ++j) acc[k] -= Interval(LX(k, j)) * s.dx0[j];
      }
    }
    Box next = theta;
    for (int k = 0; k < 7; ++k) {
      Interval v = acc[k];
      for (int j = 0; j < 7; ++j) {
        v += (Interval(k == j ? 1.0 : 0.0) - Interval(LT(k, j))) *
             (theta[j] - Interval(theta_mid[j]));
      }
      next[k] = theta[k] & (Interval(theta_mid[k]) + v);
    }
    theta = next;
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    std::printf("round %d: %zu windows failed, %zu steps, widest offset %.2e, %.1f s\n", round,
                failed, steps, offset_width, seconds);
    const char* names[7] = {"mu1", "mu2", "mu3", "mu4", "mug", "b", "fv2"};
    for (int k = 0; k < 7; ++k) {
      std::printf("  %-4s [%+8.3f %%, %+8.3f %%] %s\n", names[k],
                  100 * (theta[k].lo() / theta_true[k] - 1),
                  100 * (theta[k].hi() / theta_true[k] - 1),
                  theta[k].contains(theta_true[k]) ? "" : "TRUTH OUTSIDE");
    }
    if (theta.is_empty()) break;
  }
}
