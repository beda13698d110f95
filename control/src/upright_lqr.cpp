// The design's three steps (upright_lqr.hpp). Written here rather than taken from a control
// library: Debian 12 packages none for C++ (no slycot, no control toolbox), and each step is a few
// lines over Eigen: the linearisation is the model's own algebra at q2 = pi, the sampling a matrix
// exponential (Eigen's unsupported MatrixFunctions), the LQR the Riccati recursion iterated to its
// fixed point.
#include "furuta/control/upright_lqr.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unsupported/Eigen/MatrixFunctions>

namespace furuta::control {

namespace {

// exp([[a, b], [0, 0]] t) = [[e^(a t), (integral of e^(a s) over [0, t]) b], [0, 1]]: the state's
// own motion over t and what a duty held over t adds to it.
struct Held {
  Eigen::Matrix4d transition;
  Eigen::Vector4d input;
};
Held held_over(const LinearPlant& plant, double t) {
  Eigen::Matrix<double, 5, 5> m = Eigen::Matrix<double, 5, 5>::Zero();
  m.topLeftCorner<4, 4>() = plant.a * t;
  m.topRightCorner<4, 1>() = plant.b * t;
  const Eigen::Matrix<double, 5, 5> e = m.exp();
  return {e.topLeftCorner<4, 4>(), e.topRightCorner<4, 1>()};
}

}  // namespace

DriveConstants drive_constants(const DesignPlant& plant) {
  // Eq. 4 is affine in the duty and the arm's speed, so its value at (1, 0) is kd at the nominal
  // voltage and minus its value at (0, 1) is kw.
  const double supply_scale = plant.supply_v / plant.motor.nominal_voltage_v;
  return {plant.motor.arm_torque(1.0, 0.0) * supply_scale, -plant.motor.arm_torque(0.0, 1.0)};
}

LinearPlant linearize_upright(const DesignPlant& plant) {
  return linearize_upright(plant.parameters, drive_constants(plant));
}

LinearPlant linearize_upright(const model::Parameters<double>& p, const DriveConstants& drive) {
  // tau = kd duty - kw dq1 (drive_constants).
  const auto [kd, kw] = drive;
  // At q2 = pi: sin = 0, cos = -1; the velocity products of B(q, dq) vanish to first order, and
  // gravity's mug sin(q2) becomes -mug (q2 - pi). M = [mu1, -mu3; -mu3, mu4].
  Eigen::Matrix2d mass;
  mass << p.mu1, -p.mu3, -p.mu3, p.mu4;
  const Eigen::Matrix2d inverse = mass.inverse();
  // M ddq = [kd u - (kw + fv1) dq1; mug (q2 - pi) - fv2 dq2]
  Eigen::Matrix<double, 2, 4> forces = Eigen::Matrix<double, 2, 4>::Zero();
  forces(0, 2) = -(kw + p.fv1);
  forces(1, 1) = p.mug;
  forces(1, 3) = -p.fv2;
  LinearPlant out;
  out.a(0, 2) = 1.0;
  out.a(1, 3) = 1.0;
  out.a.bottomRows<2>() = inverse * forces;
  out.b.tail<2>() = inverse * Eigen::Vector2d(kd, 0.0);
  return out;
}

int delayed_duties(double period_s, double lag_s) {
  if (!(period_s > 0) || !std::isfinite(period_s)) {
    throw std::invalid_argument("sample: the period must be a finite number > 0 s");
  }
  if (!(lag_s >= 0) || !std::isfinite(lag_s)) {
    throw std::invalid_argument("sample: the lag must be a finite number >= 0 s");
  }
  // The count must fit an int; a lag of that many periods is a mistake anyway.
  if (!(lag_s / period_s < 1e6)) {
    throw std::invalid_argument("sample: the lag must be less than a million periods");
  }
  const int whole = static_cast<int>(std::floor(lag_s / period_s));
  const double fraction = lag_s - whole * period_s;
  return whole + (fraction > 0 ? 1 : 0);
}

double ramp_lag_s(double acceleration_pct_per_s, double step_duty) {
  if (!(acceleration_pct_per_s >= 0) || !std::isfinite(acceleration_pct_per_s)) {
    throw std::invalid_argument("ramp_lag_s: the acceleration must be a finite number >= 0 %/s");
  }
  if (!(step_duty >= 0) || !std::isfinite(step_duty)) {
    throw std::invalid_argument("ramp_lag_s: the duty step must be a finite number >= 0");
  }
  if (acceleration_pct_per_s == 0) return 0.0;
  const double rate_duty_per_s = acceleration_pct_per_s / 100.0;
  return step_duty / (2.0 * rate_duty_per_s);
}

SampledPlant sample(const LinearPlant& plant, double period_s, double lag_s) {
  const int delayed = delayed_duties(period_s, lag_s);
  // A duty sent at sample k is applied from k T + lag until the next one is: over the period
  // [k T, (k + 1) T) the board holds, in turn, the duty of sample k - whole - 1 for `fraction`
  // and the duty of sample k - whole for the rest.
  const int whole = static_cast<int>(std::floor(lag_s / period_s));
  const double fraction = lag_s - whole * period_s;
  const int n = 4 + delayed;
  SampledPlant out;
  out.continuous = plant;
  out.period_s = period_s;
  out.lag_s = lag_s;
  out.delayed = delayed;
  out.phi = Eigen::MatrixXd::Zero(n, n);
  out.gamma = Eigen::VectorXd::Zero(n);
  const Held whole_period = held_over(plant, period_s);
  out.phi.topLeftCorner<4, 4>() = whole_period.transition;
  // Which duty reaches the state first and for how long, then the next for the rest.
  const Held late = held_over(plant, period_s - fraction);  // the newer duty, at the end
  const Held early = held_over(plant, fraction);            // the older one, at the start
  const Eigen::Vector4d older = late.transition * early.input;
  const Eigen::Vector4d newer = late.input;
  // z = [x; u[k - delayed], ..., u[k - 1]]: the oldest duty still on its way first.
  const auto add_input = [&](int age, const Eigen::Vector4d& effect) {
    // age 0 is this sample's duty, age a > 0 the one sent a samples ago.
    if (age == 0) {
      out.gamma.head<4>() += effect;
    } else {
      out.phi.block<4, 1>(0, 4 + delayed - age) += effect;
    }
  };
  if (fraction > 0) {
    add_input(whole + 1, older);
    add_input(whole, newer);
  } else {
    add_input(whole, whole_period.input);
  }
  // The duties move along: each sample the newest enters the last slot.
  for (int i = 0; i + 1 < delayed; ++i) out.phi(4 + i, 4 + i + 1) = 1.0;
  if (delayed > 0) out.gamma(n - 1) = 1.0;
  return out;
}

BalanceGain design_lqr(const SampledPlant& plant, const LqrWeights& weights) {
  for (const double w : weights.state) {
    if (!(w >= 0) || !std::isfinite(w)) {
      throw std::invalid_argument("design_lqr: state weights must be finite and >= 0");
    }
  }
  if (!(weights.duty > 0) || !std::isfinite(weights.duty)) {
    throw std::invalid_argument("design_lqr: the duty weight must be finite and > 0");
  }
  const Eigen::Index n = plant.phi.rows();
  Eigen::MatrixXd q = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < 4; ++i) q(i, i) = weights.state[static_cast<std::size_t>(i)];
  const Eigen::MatrixXd& a = plant.phi;
  const Eigen::VectorXd& b = plant.gamma;
  // P = Q + A'PA - A'Pb (r + b'Pb)^-1 b'PA, iterated from P = Q to its fixed point: it converges
  // for every plant the duty can stabilise, and a few thousand 5x5 steps cost nothing.
  Eigen::MatrixXd p = q;
  BalanceGain out;
  constexpr int kMaxIterations = 200000;
  for (int i = 1; i <= kMaxIterations; ++i) {
    const Eigen::RowVectorXd bp_a = b.transpose() * p * a;
    const double denominator = weights.duty + b.dot(p * b);
    Eigen::MatrixXd next = q + a.transpose() * p * a - bp_a.transpose() * bp_a / denominator;
    next = 0.5 * (next + next.transpose());
    const double change = (next - p).norm();
    p = std::move(next);
    if (!std::isfinite(change)) break;
    if (change <= 1e-11 * std::max(1.0, p.norm())) {
      out.riccati_iterations = i;
      break;
    }
  }
  if (out.riccati_iterations == 0) {
    throw std::runtime_error(
        "design_lqr: the Riccati recursion did not settle: the duty cannot stabilise this plant");
  }
  out.k = (b.transpose() * p * a) / (weights.duty + b.dot(p * b));
  const Eigen::MatrixXd closed = a - b * out.k;
  const Eigen::VectorXcd poles = closed.eigenvalues();
  for (Eigen::Index i = 0; i < poles.size(); ++i) {
    out.closed_loop_poles.push_back(poles(i));
    out.spectral_radius = std::max(out.spectral_radius, std::abs(poles(i)));
  }
  return out;
}

ObserverGain design_observer(const SampledPlant& plant, const ObserverWeights& weights) {
  for (const double w : {weights.arm_acceleration_sd, weights.pendulum_acceleration_sd,
                         weights.arm_count_rad, weights.pendulum_count_rad}) {
    if (!(w > 0) || !std::isfinite(w)) {
      throw std::invalid_argument(
          "design_observer: acceleration deviations and counts must be finite and > 0");
    }
  }
  const double t = plant.period_s;
  if (!(weights.reading_age_s >= 0 && weights.reading_age_s <= t)) {
    throw std::invalid_argument("design_observer: the reading age must be in [0, period]");
  }
  // The duties on their way are known to the law: only the four physical states are estimated,
  // and their own motion over a period is phi's top-left block.
  const Eigen::Matrix4d a = plant.phi.topLeftCorner<4, 4>();
  // An angle read `age` before a sample is the last sample's state carried T - age along the
  // model (the duties' share known, so left out here).
  const auto reading = [&](double age_s) {
    Eigen::Matrix<double, 2, 4> c = Eigen::Matrix<double, 2, 4>::Zero();
    c(0, 0) = 1.0;
    c(1, 1) = 1.0;
    return Eigen::Matrix<double, 2, 4>(c * held_over(plant.continuous, t - age_s).transition);
  };
  const Eigen::Matrix<double, 2, 4> c = reading(weights.reading_age_s);
  // An acceleration error w held over the period T moves (angle, speed) by (T^2 / 2, T) w.
  Eigen::Matrix4d w = Eigen::Matrix4d::Zero();
  const std::array<double, 2> sd = {weights.arm_acceleration_sd, weights.pendulum_acceleration_sd};
  for (int j = 0; j < 2; ++j) {
    const double var = sd[static_cast<std::size_t>(j)] * sd[static_cast<std::size_t>(j)];
    w(j, j) = var * t * t * t * t / 4;
    w(j, j + 2) = w(j + 2, j) = var * t * t * t / 2;
    w(j + 2, j + 2) = var * t * t;
  }
  Eigen::Matrix2d v = Eigen::Matrix2d::Zero();
  v(0, 0) = weights.arm_count_rad * weights.arm_count_rad / 12;
  v(1, 1) = weights.pendulum_count_rad * weights.pendulum_count_rad / 12;
  // The prior covariance P- = A P A' + W with P = (I - M C) P-, iterated to its fixed point.
  Eigen::Matrix4d prior = w;
  Eigen::Matrix<double, 4, 2> m = Eigen::Matrix<double, 4, 2>::Zero();
  bool settled = false;
  constexpr int kMaxIterations = 200000;
  for (int i = 0; i < kMaxIterations && !settled; ++i) {
    m = prior * c.transpose() * (c * prior * c.transpose() + v).inverse();
    const Eigen::Matrix4d posterior = (Eigen::Matrix4d::Identity() - m * c) * prior;
    Eigen::Matrix4d next = a * posterior * a.transpose() + w;
    next = 0.5 * (next + next.transpose());
    const double change = (next - prior).norm();
    if (!std::isfinite(change)) break;
    settled = change <= 1e-12 * std::max(1e-30, next.norm());
    prior = next;
  }
  if (!settled) {
    throw std::runtime_error("design_observer: the filter's Riccati recursion did not settle");
  }
  ObserverGain out;
  out.m = prior * c.transpose() * (c * prior * c.transpose() + v).inverse();
  out.reading_age_s = weights.reading_age_s;
  const auto radius = [&](double age_s) {
    const Eigen::Matrix4d error = a * (Eigen::Matrix4d::Identity() - out.m * reading(age_s));
    const Eigen::Vector4cd poles = error.eigenvalues();
    double r = 0;
    for (Eigen::Index i = 0; i < poles.size(); ++i) r = std::max(r, std::abs(poles(i)));
    return r;
  };
  out.spectral_radius = radius(weights.reading_age_s);
  constexpr int kAges = 32;
  for (int i = 0; i <= kAges; ++i) {
    out.worst_spectral_radius = std::max(out.worst_spectral_radius, radius(t * i / kAges));
  }
  return out;
}

void set_continuous_plant(const LinearPlant& plant, BalanceControllerSpec& spec) {
  for (int i = 0; i < 4; ++i) {
    spec.b_continuous[static_cast<std::size_t>(i)] = plant.b(i);
    for (int j = 0; j < 4; ++j) {
      spec.a_continuous[static_cast<std::size_t>(i * 4 + j)] = plant.a(i, j);
    }
  }
}

BalanceControllerSpec balance_spec(const DesignPlant& plant, const SampledPlant& sampled,
                                   const BalanceGain& gain, const ObserverGain& observer,
                                   const DutyPath& duty_path, double max_duty, double duty_step) {
  if (sampled.delayed > kMaxDelayedDuties || gain.k.size() != 4 + sampled.delayed) {
    throw std::invalid_argument(
        "a lag of " + std::to_string(sampled.lag_s) + " s is " + std::to_string(sampled.delayed) +
        " duties on their way at a period of " + std::to_string(sampled.period_s) +
        " s; the balance law carries at most " + std::to_string(kMaxDelayedDuties));
  }
  BalanceControllerSpec spec;
  spec.period_s = sampled.period_s;
  spec.delayed = sampled.delayed;
  spec.duty_path = duty_path;
  for (Eigen::Index i = 0; i < gain.k.size(); ++i) {
    spec.gain[static_cast<std::size_t>(i)] = gain.k(i);
  }
  for (std::size_t i = 0; i < 4; ++i) {
    for (std::size_t j = 0; j < 2; ++j) {
      spec.observer_gain[i * 2 + j] =
          observer.m(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
    }
  }
  set_continuous_plant(sampled.continuous, spec);
  spec.max_duty = max_duty;
  spec.duty_step = duty_step;
  spec.parameters = plant.parameters;
  const DriveConstants drive = drive_constants(plant);
  spec.duty_torque_nm = drive.duty_torque_nm;
  spec.back_emf_nm_s = drive.back_emf_nm_s;
  spec.swing_up.max_duty = std::min(spec.swing_up.max_duty, max_duty);
  return spec;
}

}  // namespace furuta::control
