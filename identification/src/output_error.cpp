#include "furuta/identification/output_error.hpp"

#include <ceres/ceres.h>

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <memory>
#include <numbers>
#include <optional>
#include <span>
#include <sstream>
#include <stdexcept>

#include "furuta/model/duty_ramp.hpp"

namespace furuta::identification {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
// The continuity defect of a velocity is weighed as that of an angle over this time: an angle
// error of sigma grows from a velocity error of sigma / 10 ms within a few samples.
constexpr double kVelocityDefectTime_s = 0.01;
// How far from a segment's start the observations are that give its starting state.
constexpr double kStartFitHalfWidth_s = 0.04;

double scalar_of(double x) {
  return x;
}
template <class T, int N>
double scalar_of(const ceres::Jet<T, N>& x) {
  return x.a;
}

template <class T>
struct State {
  T q1{}, dq1{}, q2{}, dq2{};
};

// p from the unconstrained coordinates: mu1, mu2, mu4, mug = exp(theta), mu3 = sqrt(mu1 mu4)
// tanh(theta_2), so that mu1 mu4 > mu3^2 for every theta; fv1, fv2 are bounded at 0 in the solver.
template <class T>
model::Parameters<T> natural_from_theta(const T* theta) {
  using std::exp;
  using std::sqrt;
  using std::tanh;
  model::Parameters<T> p;
  p.mu1 = exp(theta[0]);
  p.mu2 = exp(theta[1]);
  p.mu4 = exp(theta[3]);
  p.mu3 = sqrt(p.mu1 * p.mu4) * tanh(theta[2]);
  p.mug = exp(theta[4]);
  p.fv1 = theta[5];
  p.fv2 = theta[6];
  return p;
}

// The start moved into the physical region (LSMI is unconstrained): what was moved is reported.
std::array<double, model::kParameterCount> theta_from_natural(
    const model::Parameters<double>& start, std::vector<std::string>& warnings) {
  model::Parameters<double> p = start;
  for (std::size_t i : {0u, 1u, 3u, 4u}) {
    if (!(p[i] > 0)) {
      warnings.push_back(std::string("output error: the start's ") + model::kParameterNames[i] +
                         " is not positive; started from its magnitude");
      p[i] = std::max(std::abs(p[i]), 1e-12);
    }
  }
  const double limit = std::sqrt(p.mu1 * p.mu4);
  double ratio = p.mu3 / limit;
  if (!(std::abs(ratio) < 1.0)) {
    // Not at the boundary: there det M nearly vanishes at q2 = 0, the arm's time constant shrinks
    // with it and the fixed RK4 step diverges. 0.7 is the paper's rig.
    warnings.push_back(
        "output error: the start's mass matrix is not positive definite (mu1 mu4 <= mu3^2); "
        "started from |mu3| = 0.7 sqrt(mu1 mu4)");
    ratio = std::copysign(0.7, ratio);
  }
  for (std::size_t i : {5u, 6u}) {
    if (!(p[i] >= 0)) {
      warnings.push_back(std::string("output error: the start's ") + model::kParameterNames[i] +
                         " is negative; started from 0");
      p[i] = 0;
    }
  }
  return {std::log(p.mu1),
          std::log(p.mu2),
          std::atanh(ratio),
          std::log(p.mu4),
          std::log(p.mug),
          p.fv1,
          p.fv2};
}

// The applied input on piece `piece` of the breakpoints at time t (the state's clock): linear from
// breakpoint piece - 1 to breakpoint piece, held before the first (piece 0) and after the last
// (piece = the breakpoints' count). The piece is chosen by the integrator, never from t, so that
// a step ending on a breakpoint keeps the piece it integrates (the input may jump there: a held
// CSV input, or braking at an exact zero).
template <class T>
T arm_torque(const OeExperiment& e, const model::MotorData& motor, std::size_t piece, const T& t,
             const T& dq1, const T& gain) {
  const auto& bt = e.input_t_s;
  const std::size_t n = bt.size();
  T value;
  bool exactly_zero = false;
  double braking = 0;
  const auto brake_at = [&](std::size_t i) {
    return e.braking_fraction.empty() ? 0.0 : e.braking_fraction[i];
  };
  if (piece == 0) {
    value = T(e.input.front());
    exactly_zero = e.input.front() == 0.0;
    braking = brake_at(0);
  } else if (piece >= n) {
    value = T(e.input.back());
    exactly_zero = e.input.back() == 0.0;
    braking = brake_at(n - 1);
  } else {
    const std::size_t j = piece - 1;
    const double a = e.input[j], b = e.input[j + 1];
    const double h = bt[j + 1] - bt[j];
    if (e.input_slope.empty()) {
      value = T(a) + (b - a) * (t - bt[j]) / h;
    } else {
      // Cubic Hermite: the samples and the slopes at both ends.
      const T s = (t - bt[j]) / h;
      const T s2 = s * s, s3 = s2 * s;
      value = (2.0 * s3 - 3.0 * s2 + 1.0) * a + (s3 - 2.0 * s2 + s) * (h * e.input_slope[j]) +
              (-2.0 * s3 + 3.0 * s2) * b + (s3 - s2) * (h * e.input_slope[j + 1]);
    }
    exactly_zero = a == 0.0 && b == 0.0;
    braking = brake_at(j);
  }
  switch (e.input_kind) {
    case InputKind::duty:
      if (exactly_zero) return braking * motor.arm_torque(T(0.0), dq1);
      return motor.arm_torque(T(value * gain * e.supply_scale), dq1);
    case InputKind::voltage: {
      const VoltageMotor& v = e.voltage_motor;
      return v.gear_ratio * v.efficiency * v.torque_constant_nm_per_a *
             (gain * value - v.back_emf_v_s_per_rad * v.gear_ratio * dq1) / v.resistance_ohm;
    }
    case InputKind::torque:
      return gain * value;
  }
  return value;
}

template <class T>
State<T> derivative(const OeExperiment& e, const model::MotorData& motor,
                    const model::Parameters<T>& p, const T& gain, std::size_t piece, const T& t,
                    const State<T>& x) {
  const T tau = arm_torque(e, motor, piece, t, x.dq1, gain);
  const model::JointAccelerations<T> a = model::accelerations(p, x.q2, x.dq1, x.dq2, tau);
  return {x.dq1, a.ddq1, x.dq2, a.ddq2};
}

template <class T>
State<T> axpy(const State<T>& x, const State<T>& d, const T& h) {
  return {x.q1 + h * d.q1, x.dq1 + h * d.dq1, x.q2 + h * d.q2, x.dq2 + h * d.dq2};
}

// RK4 from t0 to t1 (the observations' clock; the input's time is t - lag). The interval is cut
// at every input breakpoint (at breakpoint + lag, so the cuts move with the lag and carry its
// derivative) and each piece into equal substeps of at most max_step_s: RK4 is 4th order only
// where the input is smooth, and across a kink in a 1 ms step it errs by a fraction of the kink's
// duty change, at every kink (an input with many kinks, as a chirp, adds them up).
template <class T>
State<T> integrate(const OeExperiment& e, const model::MotorData& motor,
                   const model::Parameters<T>& p, const T& lag, const T& gain, State<T> x,
                   double t0, double t1, double max_step_s) {
  if (!(t1 > t0)) return x;
  const auto& bt = e.input_t_s;
  const double lag_s = scalar_of(lag);
  std::size_t piece =
      static_cast<std::size_t>(std::upper_bound(bt.begin(), bt.end(), t0 - lag_s) - bt.begin());
  T start(t0);
  for (;;) {
    const bool last = piece >= bt.size() || bt[piece] + lag_s >= t1;
    const T end = last ? T(t1) : T(bt[piece]) + lag;
    const double length = scalar_of(end) - scalar_of(start);
    if (length > 0) {
      const int n = std::max(1, static_cast<int>(std::ceil(length / max_step_s - 1e-9)));
      const T h = (end - start) / static_cast<double>(n);
      const T half = h / 2.0;
      for (int k = 0; k < n; ++k) {
        const T t = start + static_cast<double>(k) * h - lag;
        const State<T> k1 = derivative(e, motor, p, gain, piece, t, x);
        const State<T> k2 = derivative(e, motor, p, gain, piece, t + half, axpy(x, k1, half));
        const State<T> k3 = derivative(e, motor, p, gain, piece, t + half, axpy(x, k2, half));
        const State<T> k4 = derivative(e, motor, p, gain, piece, t + h, axpy(x, k3, h));
        const T w = h / 6.0;
        x.q1 += w * (k1.q1 + 2.0 * k2.q1 + 2.0 * k3.q1 + k4.q1);
        x.dq1 += w * (k1.dq1 + 2.0 * k2.dq1 + 2.0 * k3.dq1 + k4.dq1);
        x.q2 += w * (k1.q2 + 2.0 * k2.q2 + 2.0 * k3.q2 + k4.q2);
        x.dq2 += w * (k1.dq2 + 2.0 * k2.dq2 + 2.0 * k3.dq2 + k4.dq2);
      }
    }
    if (last) return x;
    start = end;
    ++piece;
  }
}

// Observations [first, end) of one experiment, simulated from the state x0 at the first one's time.
struct Segment {
  std::size_t experiment = 0;
  std::size_t first = 0, end = 0;
  double t_start_s = 0;
  double t_next_s = -1;  // the next segment's start (continuity), or < 0 for the last one
};

struct SegmentCost {
  const OeExperiment* experiment;
  const model::MotorData* motor;
  Segment segment;
  double substep_s;
  std::array<double, 4> continuity_sigma;

  int residual_count() const {
    return static_cast<int>(segment.end - segment.first) + (segment.t_next_s >= 0 ? 4 : 0);
  }

  // Residuals of the angles; the state at the next segment's start into `end_state`.
  template <class T>
  void angles(const T* theta, const T* aux, const T* gain_ptr, const T* x0, T* r,
              State<T>& end_state) const {
    const T& gain = *gain_ptr;
    const model::Parameters<T> p = natural_from_theta(theta);
    const T& lag = aux[0];
    const T& q2_offset = aux[1];
    State<T> x{x0[0], x0[1], x0[2], x0[3]};
    double t = segment.t_start_s;
    const auto& obs = experiment->observations;
    for (std::size_t i = segment.first; i < segment.end; ++i) {
      const OeObservation& o = obs[i];
      x = integrate(*experiment, *motor, p, lag, gain, x, t, o.t_s, substep_s);
      t = std::max(t, o.t_s);
      const double sigma = experiment->angle_sigma_rad[o.joint];
      *r++ =
          o.joint == 0 ? (x.q1 - o.angle_rad) / sigma : (x.q2 - (o.angle_rad + q2_offset)) / sigma;
    }
    if (segment.t_next_s >= 0) {
      x = integrate(*experiment, *motor, p, lag, gain, x, t, segment.t_next_s, substep_s);
    }
    end_state = x;
  }

  template <class T>
  bool operator()(const T* theta, const T* aux, const T* gain, const T* x0, const T* x1,
                  T* r) const {
    State<T> end;
    angles(theta, aux, gain, x0, r, end);
    r += segment.end - segment.first;
    r[0] = (end.q1 - x1[0]) / continuity_sigma[0];
    r[1] = (end.dq1 - x1[1]) / continuity_sigma[1];
    r[2] = (end.q2 - x1[2]) / continuity_sigma[2];
    r[3] = (end.dq2 - x1[3]) / continuity_sigma[3];
    return finite(r - (segment.end - segment.first), residual_count());
  }
  template <class T>
  bool operator()(const T* theta, const T* aux, const T* gain, const T* x0, T* r) const {
    State<T> end;
    angles(theta, aux, gain, x0, r, end);
    return finite(r, residual_count());
  }
  // A trial step whose simulation diverged is a failed evaluation: Ceres shrinks its trust region.
  template <class T>
  static bool finite(const T* r, int n) {
    for (int i = 0; i < n; ++i) {
      if (!std::isfinite(scalar_of(r[i]))) return false;
    }
    return true;
  }
};

// The prior on an input's gain: (gain - 1) / sigma.
struct GainPrior {
  double sigma;
  template <class T>
  bool operator()(const T* gain, T* r) const {
    r[0] = (gain[0] - 1.0) / sigma;
    return true;
  }
};

// A starting state at t from the observations nearby: a quadratic through each joint's angles
// within kStartFitHalfWidth_s, least squares, its value and slope at t.
std::array<double, 4> start_state(const OeExperiment& e, double t) {
  std::array<double, 4> x{};
  for (int joint = 0; joint < 2; ++joint) {
    // Normal equations of a + b u + c u^2, u = time from t.
    double s[5] = {0, 0, 0, 0, 0}, y[3] = {0, 0, 0};
    double nearest = 0, nearest_dt = 1e300;
    for (const OeObservation& o : e.observations) {
      if (o.joint != joint) continue;
      const double u = o.t_s - t;
      if (std::abs(u) < nearest_dt) {
        nearest_dt = std::abs(u);
        nearest = o.angle_rad;
      }
      if (std::abs(u) > kStartFitHalfWidth_s) continue;
      double pw = 1;
      for (double& sk : s) {
        sk += pw;
        pw *= u;
      }
      y[0] += o.angle_rad;
      y[1] += o.angle_rad * u;
      y[2] += o.angle_rad * u * u;
    }
    double value = nearest, slope = 0;
    if (s[0] >= 4) {
      Eigen::Matrix3d a;
      a << s[0], s[1], s[2], s[1], s[2], s[3], s[2], s[3], s[4];
      const Eigen::Vector3d c = a.ldlt().solve(Eigen::Vector3d(y[0], y[1], y[2]));
      if (c.allFinite()) {
        value = c[0];
        slope = c[1];
      }
    }
    x[2 * joint] = value;
    x[2 * joint + 1] = slope;
  }
  return x;
}

std::vector<Segment> cut_segments(const OeExperiment& e, std::size_t index, double segment_s) {
  std::vector<Segment> out;
  const auto& obs = e.observations;
  std::size_t first = 0;
  while (first < obs.size()) {
    const double boundary = obs[first].t_s + segment_s;
    std::size_t end = first;
    while (end < obs.size() && obs[end].t_s < boundary) ++end;
    // A short tail joins the segment before it rather than making one with too few angles.
    if (end < obs.size() && obs.back().t_s < boundary + segment_s / 2) end = obs.size();
    out.push_back({index, first, end, obs[first].t_s, -1});
    first = end;
  }
  for (std::size_t k = 0; k + 1 < out.size(); ++k) out[k].t_next_s = out[k + 1].t_start_s;
  return out;
}

void check_experiment(const OeExperiment& e) {
  if (e.observations.empty() || e.input.empty() || e.input.size() != e.input_t_s.size()) {
    throw std::invalid_argument(e.name + ": output error needs angles and an input");
  }
  if (!(e.angle_sigma_rad[0] > 0) || !(e.angle_sigma_rad[1] > 0)) {
    throw std::invalid_argument(e.name + ": output error needs each angle's noise sigma (> 0)");
  }
}

// The covariance of the first `leading` free coordinates, two ways, from the Jacobian J and the
// residuals r at the optimum (A = J^T J over every free coordinate, sparse):
// - local: A^-1, for residuals weighted by independent errors of the assumed sigma;
// - robust: White's sandwich over clusters, A^-1 (sum_c g_c g_c^T) A^-1 C / (C - 1) with
//   g_c = J_c^T r_c of cluster c (a segment, or a prior): right also where the errors are
//   correlated within a segment (an encoder's quantisation of a slow joint, a model that misses
//   something), which the local one counts as independent.
// Nothing when the problem cannot be evaluated or A is singular.
struct LeadingCovariance {
  Eigen::MatrixXd local, robust;
};
std::optional<LeadingCovariance> leading_covariance(
    ceres::Problem& problem, const std::vector<double*>& free_blocks,
    const std::vector<ceres::ResidualBlockId>& clusters, int leading) {
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks = free_blocks;
  evaluate.residual_blocks = clusters;
  std::vector<double> residuals;
  ceres::CRSMatrix jacobian;
  if (!problem.Evaluate(evaluate, nullptr, &residuals, nullptr, &jacobian)) return std::nullopt;
  const int columns = jacobian.num_cols;
  if (columns < leading || clusters.size() < 2) return std::nullopt;
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(jacobian.values.size());
  for (int row = 0; row < jacobian.num_rows; ++row) {
    for (int a = jacobian.rows[static_cast<std::size_t>(row)];
         a < jacobian.rows[static_cast<std::size_t>(row) + 1]; ++a) {
      entries.emplace_back(row, jacobian.cols[static_cast<std::size_t>(a)],
                           jacobian.values[static_cast<std::size_t>(a)]);
    }
  }
  Eigen::SparseMatrix<double> j(jacobian.num_rows, columns);
  j.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SparseMatrix<double> normal = Eigen::SparseMatrix<double>(j.transpose() * j);
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> factor(normal);
  if (factor.info() != Eigen::Success) return std::nullopt;
  // Rows of A^-1 for the leading coordinates (A is symmetric: its first columns).
  const Eigen::MatrixXd unit = Eigen::MatrixXd::Identity(columns, leading);
  const Eigen::MatrixXd inverse_columns = factor.solve(unit);
  if (factor.info() != Eigen::Success || !inverse_columns.allFinite()) return std::nullopt;
  LeadingCovariance out;
  out.local = inverse_columns.topRows(leading);
  out.robust = Eigen::MatrixXd::Zero(leading, leading);
  const Eigen::Map<const Eigen::VectorXd> r(residuals.data(),
                                            static_cast<Eigen::Index>(residuals.size()));
  int row = 0;
  for (ceres::ResidualBlockId id : clusters) {
    const int rows = problem.GetCostFunctionForResidualBlock(id)->num_residuals();
    const Eigen::VectorXd g = j.middleRows(row, rows).transpose() * r.segment(row, rows);
    const Eigen::VectorXd h = inverse_columns.transpose() * g;
    out.robust += h * h.transpose();
    row += rows;
  }
  const double c = static_cast<double>(clusters.size());
  out.robust *= c / (c - 1.0);
  return out;
}

// The angle noise the fit assumed, per joint: the largest over the experiments, and estimated from
// the readings when any experiment's was.
void assumed_angle_noise(OutputErrorResult& result, const std::vector<OeExperiment>& experiments) {
  result.angle_noise_rad = {0, 0};
  result.angle_noise_source = {AngleNoiseSource::encoder_resolution,
                               AngleNoiseSource::encoder_resolution};
  for (const OeExperiment& e : experiments) {
    for (int j = 0; j < 2; ++j) {
      result.angle_noise_rad[j] = std::max(result.angle_noise_rad[j], e.angle_sigma_rad[j]);
      if (e.angle_noise_source[j] == AngleNoiseSource::estimated_from_readings) {
        result.angle_noise_source[j] = AngleNoiseSource::estimated_from_readings;
      }
    }
  }
}

// Whose times each joint's observations carry, and how late the host's stamps were where a
// board's clock replaced them.
void time_stamps(OutputErrorResult& result, const std::vector<OeExperiment>& experiments) {
  for (int j = 0; j < 2; ++j) {
    std::size_t mapped = 0;
    double delay_sum = 0;
    for (const OeExperiment& e : experiments) {
      if (!e.board_clock[j]) continue;
      ++mapped;
      delay_sum += e.board_clock[j]->host_delay_mean_s;
      result.host_delay_max_s[j] =
          std::max(result.host_delay_max_s[j], e.board_clock[j]->host_delay_max_s);
    }
    result.time_stamps[j] = mapped == 0                    ? TimeStamps::host
                            : mapped == experiments.size() ? TimeStamps::board_clock
                                                           : TimeStamps::mixed;
    if (mapped > 0) result.host_delay_mean_s[j] = delay_sum / static_cast<double>(mapped);
  }
}

// The fit against what its noise model predicts: angles much further from the model than their
// assumed noise, or segments that do not join, say the model does not describe the data as
// recorded, and name what usually causes it.
void misfit_warnings(OutputErrorResult& result, const OutputErrorOptions& options) {
  const auto g = [](double v) {
    std::ostringstream s;
    s << std::setprecision(3) << v;
    return s.str();
  };
  const auto estimated = [&](int j) {
    return result.angle_noise_source[j] == AngleNoiseSource::estimated_from_readings;
  };
  const auto noise = [&](int j) {
    return g(result.angle_noise_rad[j]) + " rad (" +
           (estimated(j) ? "estimated from its readings' scatter: the recording states no "
                           "resolution"
                         : "the encoder's resolution / sqrt(12)") +
           ")";
  };
  if (result.residual_sigma > options.misfit_sigma) {
    result.warnings.push_back(
        "output error: the angles lie " + g(result.residual_sigma) +
        " times further from the fitted model than their assumed noise (residual RMS q1 " +
        g(result.angle_rms_rad[0]) + ", q2 " + g(result.angle_rms_rad[1]) +
        " rad against an angle noise of q1 " + noise(0) + ", q2 " + noise(1) +
        "): the model does not describe these data as recorded; likely causes: an angle's or "
        "the input's unit, sign, scale or zero, time stamps that are late or jittered, dynamics "
        "the model lacks" +
        (estimated(0) || estimated(1)
             ? ", or an angle noise the readings understate (state arm_resolution and "
               "pendulum_resolution in the import spec)"
             : "") +
        "; the standard deviations are scaled by it");
  }
  if (result.continuity_rms > options.continuity_weight) {
    result.warnings.push_back(
        "output error: the segments do not join into one trajectory (continuity RMS " +
        g(result.continuity_rms) + ", above " + g(options.continuity_weight) +
        ": the state jumps between segments by more than the angle noise): the model cannot "
        "follow these data over a segment");
  }
}

ceres::Solver::Options solver_options(int max_iterations, int threads) {
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  o.max_num_iterations = max_iterations;
  o.num_threads = std::max(1, threads);
  o.function_tolerance = 1e-9;
  o.parameter_tolerance = 1e-10;
  o.logging_type = ceres::SILENT;
  return o;
}

// A duty's torque scales with the supply: the experiment's supply_scale from every reading of it,
// and the input gain's prior from how well they fix it. The mean, with a tenth cut at each end
// against glitches, resolves the supply below the reading's step when the reading is noisy;
// readings that never change resolve it to one step (`step_v`; 0: unknown, and the gain is held).
void scale_duty_by_supply(OeExperiment& e, std::vector<double> supply_v, double nominal_v,
                          double step_v) {
  e.supply_readings_v = supply_v;
  std::sort(supply_v.begin(), supply_v.end());
  const std::size_t cut = supply_v.size() / 10;
  const std::span<const double> kept(supply_v.data() + cut, supply_v.size() - 2 * cut);
  if (kept.empty() || !(nominal_v > 0)) return;
  double mean = 0, spread = 0;
  for (double v : kept) mean += v;
  mean /= static_cast<double>(kept.size());
  for (double v : kept) spread += (v - mean) * (v - mean);
  spread = std::sqrt(spread / static_cast<double>(std::max<std::size_t>(1, kept.size() - 1)));
  if (!(mean > 0)) return;
  e.supply_scale = mean / nominal_v;
  // Without half a step of noise to dither it, the supply is known to a step, uniform; with it, to
  // the mean's own spread.
  const double sigma_v = spread < step_v / 2 ? step_v / std::sqrt(12.0)
                                             : spread / std::sqrt(static_cast<double>(kept.size()));
  e.input_gain_sigma = sigma_v / mean;
}

// The input as the motor board applies it (model::DutyRamp): from each command's time it moves
// towards the command at the command's rate. Appends the breakpoints of the piecewise-linear
// result to the experiment's input, from a second before `t` (at `applied`) to a second after the
// last observation.
class RampedInput {
 public:
  RampedInput(OeExperiment& e, double t, double applied, double braking)
      : e_(e), t_(t), duty_(applied), braking_(braking) {
    add(t - 1.0, applied, braking);
  }
  // A command at `at` (ignored when earlier than the previous one).
  void command(double at, double target, double rate_per_s, double braking) {
    if (at < t_) return;
    ramp_until(at);
    duty_.command(target, rate_per_s);
    braking_ = braking;
    add(at, duty_.applied(), braking_);
  }
  void finish(double last_observation_s) {
    ramp_until(std::max(t_, last_observation_s) + 1.0);
    add(t_, duty_.applied(), braking_);
  }

 private:
  void add(double at, double value, double brake) {
    if (!e_.input_t_s.empty() && at <= e_.input_t_s.back()) {
      e_.input.back() = value;
      e_.braking_fraction.back() = brake;
      return;
    }
    e_.input_t_s.push_back(at);
    e_.input.push_back(value);
    e_.braking_fraction.push_back(brake);
  }
  // The ramp's end, where it ends before `until`, is a breakpoint.
  void ramp_until(double until) {
    const double reach = t_ + duty_.seconds_to_target();
    if (reach < until && duty_.applied() != duty_.target()) add(reach, duty_.target(), braking_);
    duty_.advance(until - t_);
    t_ = until;
  }

  OeExperiment& e_;
  double t_;
  model::DutyRamp duty_;
  double braking_;
};

}  // namespace

OeExperiment oe_experiment_from_log(const session_log::SessionLog& log,
                                    const config::RigConfig& rig) {
  OeExperiment e;
  e.name = log.start ? log.start->session : log.path.filename().string();
  e.input_kind = InputKind::duty;
  if (log.samples.empty()) throw std::invalid_argument(e.name + ": no samples");
  const std::int64_t t0 = log.samples.front().monotonic_ns;
  const auto seconds = [t0](std::int64_t ns) { return static_cast<double>(ns - t0) * 1e-9; };

  // Every report of both boards, not one per cycle: the boards report every 8 ms, and an arm
  // angle 8 ms after a command change still shows the arm's 4.4 ms transient that separates its
  // inertia from the data path's lag. The sample lists the decodable reports of its cycle, oldest
  // first, and its angles are those of the newest; the older encoder board reports' angles follow
  // from their deltas, the older motor board reports' from their positions in the raw reports of
  // the log.
  const std::vector<session_log::MotorInputReport> arm_positions =
      session_log::motor_input_reports(log, rig.motor_board.model);
  std::size_t cursor = 0;
  const auto position_at = [&](std::int64_t host_ns) -> const session_log::MotorInputReport* {
    while (cursor < arm_positions.size() && arm_positions[cursor].time_ns < host_ns) ++cursor;
    if (cursor < arm_positions.size() && arm_positions[cursor].time_ns == host_ns) {
      return &arm_positions[cursor++];
    }
    return nullptr;
  };
  const double arm_rad_per_count =
      rig.arm_encoder.sign * kTwoPi / rig.arm_encoder.counts_per_joint_rev();
  const double pendulum_rad_per_count =
      rig.pendulum_encoder.sign * kTwoPi / rig.pendulum_encoder.counts_per_joint_rev();

  // Each joint's readings with the host's time and the board's own (the motor board's report
  // counter, the encoder board's accumulated packet ticks); a reading whose host time does not
  // move on is dropped.
  std::array<std::vector<double>, 2> host_s, board, angle;
  const auto observe = [&](int joint, std::int64_t host_ns, double board_time, double angle_rad) {
    const double t = seconds(host_ns);
    if (!host_s[joint].empty() && !(t > host_s[joint].back())) return;
    host_s[joint].push_back(t);
    board[joint].push_back(board_time);
    angle[joint].push_back(angle_rad);
  };
  session_log::BoardTimeline board_time;
  std::vector<const session_log::MotorInputReport*> cycle;
  std::vector<double> cycle_board;
  for (const auto& s : log.samples) {
    if (s.n_motor_reports > 0) {
      cycle.clear();
      cycle_board.clear();
      for (std::int16_t k = 0; k < s.n_motor_reports; ++k) {
        cycle.push_back(position_at(s.motor_report_host_ns[k]));
        cycle_board.push_back(board_time.motor_report(s.motor_packet_counter[k]));
      }
      const session_log::MotorInputReport* newest = cycle.back();
      for (std::int16_t k = 0; k + 1 < s.n_motor_reports; ++k) {
        if (cycle[k] == nullptr || newest == nullptr) continue;
        // The board's position is an i32 that wraps: the difference is taken in 32 bits.
        const auto behind =
            static_cast<std::int32_t>(static_cast<std::uint32_t>(cycle[k]->encoder_position) -
                                      static_cast<std::uint32_t>(newest->encoder_position));
        observe(0, s.motor_report_host_ns[k], cycle_board[k],
                s.arm_angle_rad + behind * arm_rad_per_count);
      }
      observe(0, s.motor_report_host_ns[s.n_motor_reports - 1], cycle_board.back(),
              s.arm_angle_rad);
    }
    std::int64_t after = 0;  // counts of the cycle's reports after report k
    for (std::int16_t k = 0; k < s.n_encoder_reports; ++k) after += s.encoder_delta_counts[k];
    for (std::int16_t k = 0; k < s.n_encoder_reports; ++k) {
      after -= s.encoder_delta_counts[k];
      observe(1, s.encoder_report_host_ns[k], board_time.encoder_report(s.encoder_packet_ticks[k]),
              s.pendulum_angle_rad - after * pendulum_rad_per_count);
    }
  }
  const bool pendulum_ticks_whole = log.samples.back().encoder_lost_reports == 0;
  for (int j = 0; j < 2; ++j) {
    const std::optional<BoardClock> clock =
        j == 1 && !pendulum_ticks_whole
            ? std::nullopt
            : fit_board_clock(host_s[j], board[j], kBoardClockMaxDelay_s);
    e.board_clock[j] = clock;
    for (std::size_t i = 0; i < host_s[j].size(); ++i) {
      e.observations.push_back(
          {clock ? clock->host_time(board[j][i]) : host_s[j][i], j, angle[j][i]});
    }
  }
  std::stable_sort(e.observations.begin(), e.observations.end(),
                   [](const OeObservation& a, const OeObservation& b) { return a.t_s < b.t_s; });
  if (e.observations.empty()) throw std::invalid_argument(e.name + ": no board reports");

  std::vector<double> supply_v;
  for (const auto& r : arm_positions) supply_v.push_back(r.supply_v);
  scale_duty_by_supply(e, supply_v, rig.motor.nominal_voltage_v,
                       config::motor_resolution(rig).supply_step_v);

  // The board ramps its applied duty towards the newest command at the command's rate, from the
  // moment the command is written (model::DutyRamp, which the simulated rig uses too).
  const std::vector<session_log::MotorCommandWrite> writes =
      session_log::motor_command_writes(log, rig.motor_board.model);
  RampedInput ramp(
      e, std::min(e.observations.front().t_s, writes.empty() ? 0.0 : seconds(writes[0].time_ns)),
      log.samples.front().applied_duty, rig.safety.stop_braking_fraction);
  for (const auto& w : writes) {
    ramp.command(seconds(w.time_ns), w.duty, w.acceleration_pct_per_s / 100.0, w.braking_fraction);
  }
  ramp.finish(e.observations.back().t_s);

  const double arm_counts = rig.arm_encoder.counts_per_joint_rev();
  const double pendulum_counts = rig.pendulum_encoder.counts_per_joint_rev();
  if (!(arm_counts > 0) || !(pendulum_counts > 0)) {
    throw std::invalid_argument(e.name + ": the configuration's encoders have no counts");
  }
  e.angle_sigma_rad = {kTwoPi / arm_counts / std::sqrt(12.0),
                       kTwoPi / pendulum_counts / std::sqrt(12.0)};
  e.warnings = {};
  if (writes.empty()) {
    e.warnings.push_back(e.name + ": no motor commands in the log; the input is the first echo");
  }
  return e;
}

double angle_noise_from_readings(std::span<const double> q) {
  double step = HUGE_VAL;
  for (std::size_t i = 1; i < q.size(); ++i) {
    const double d = std::abs(q[i] - q[i - 1]);
    if (d > 0) step = std::min(step, d);
  }
  if (!std::isfinite(step)) return 0.0;  // no reading ever changed: nothing to say
  const double floor = step / std::sqrt(12.0);
  if (q.size() < 5) return floor;
  std::vector<double> d4(q.size() - 4);
  for (std::size_t i = 0; i + 4 < q.size(); ++i) {
    d4[i] = q[i] - 4 * q[i + 1] + 6 * q[i + 2] - 4 * q[i + 3] + q[i + 4];
  }
  const auto median = [](std::vector<double>& v) {
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
  };
  const double centre = median(d4);
  for (double& v : d4) v = std::abs(v - centre);
  // 1.4826 MAD is a normal sample's standard deviation.
  const double spread = 1.4826 * median(d4) / std::sqrt(70.0);
  return std::max(spread, floor);
}

OeExperiment oe_experiment_from_raw(const RawExperiment& raw, std::array<double, 2> angle_sigma_rad,
                                    InputBetweenSamples between, const VoltageMotor& voltage_motor,
                                    double nominal_supply_v) {
  OeExperiment e;
  e.name = raw.name;
  e.input_kind = raw.input_kind;
  e.voltage_motor = voltage_motor;
  e.angle_sigma_rad = angle_sigma_rad;
  e.warnings = raw.warnings;
  const std::size_t n = raw.t_s.size();
  if (n == 0 || raw.q1.size() != n || raw.q2.size() != n || raw.input.size() != n) {
    throw std::invalid_argument(raw.name + ": angles, input and times differ in length");
  }
  RecordedSeries r = raw.recorded;
  if (r.empty()) {
    r.q1_t_s = r.q2_t_s = r.input_t_s = raw.t_s;
    r.q1_rad = raw.q1;
    r.q2_rad = raw.q2;
    r.input = raw.input;
  }
  if (r.q1_t_s.empty() || r.q2_t_s.empty() || r.input_t_s.empty()) {
    throw std::invalid_argument(raw.name + ": an angle or the input has no readings");
  }
  for (std::size_t j = 0; j < 2; ++j) {
    const std::vector<double>& t = j == 0 ? r.q1_t_s : r.q2_t_s;
    const std::vector<double>& x = j == 0 ? r.q1_rad : r.q2_rad;
    for (std::size_t i = 0; i < t.size(); ++i)
      e.observations.push_back({t[i], static_cast<int>(j), x[i]});
  }
  std::stable_sort(e.observations.begin(), e.observations.end(),
                   [](const OeObservation& a, const OeObservation& b) { return a.t_s < b.t_s; });
  e.board_clock = r.board_clock;

  const std::size_t m = r.input_t_s.size();
  if (raw.input_rate_limit_per_s > 0) {
    // Braking at zero: a recorded duty of 0 is taken as eq. 4 at zero duty (the board braking).
    RampedInput ramp(e, std::min(r.input_t_s.front(), e.observations.front().t_s),
                     r.input_at_start.value_or(r.input.front()), 1.0);
    for (std::size_t i = 0; i < m; ++i) {
      ramp.command(r.input_t_s[i], r.input[i], raw.input_rate_limit_per_s, 1.0);
    }
    ramp.finish(e.observations.back().t_s);
  } else {
    if (r.input_at_start) {
      // Held up to (just before) the first recorded input.
      e.input_t_s.push_back(std::nextafter(r.input_t_s.front(), -1e300));
      e.input.push_back(*r.input_at_start);
    }
    for (std::size_t i = 0; i < m; ++i) {
      if (between == InputBetweenSamples::held && i > 0) {
        // A step: the previous value up to (just before) this sample.
        e.input_t_s.push_back(std::nextafter(r.input_t_s[i], -1e300));
        e.input.push_back(r.input[i - 1]);
      }
      e.input_t_s.push_back(r.input_t_s[i]);
      e.input.push_back(r.input[i]);
    }
    e.braking_fraction.assign(e.input.size(), 1.0);
    if (between == InputBetweenSamples::cubic && m >= 2) {
      // Catmull-Rom slopes: the centred difference inside, the one-sided one at the ends.
      // The held start, when there is one, is flat.
      if (r.input_at_start) e.input_slope.push_back(0.0);
      for (std::size_t i = 0; i < m; ++i) {
        const std::size_t lo = i == 0 ? 0 : i - 1, hi = i + 1 == m ? i : i + 1;
        e.input_slope.push_back((r.input[hi] - r.input[lo]) / (r.input_t_s[hi] - r.input_t_s[lo]));
      }
    }
  }
  if (!r.supply_v.empty() && raw.input_kind == InputKind::duty) {
    // A logger's supply reading has no known step: the gain is held unless the readings vary.
    scale_duty_by_supply(e, r.supply_v, nominal_supply_v, 0.0);
  }
  // A stated uncertainty of the input's scale adds to the supply's.
  e.input_gain_sigma = std::hypot(e.input_gain_sigma, raw.input_scale_sd);
  return e;
}

OutputErrorResult refine_output_error(const std::vector<OeExperiment>& experiments,
                                      const model::Parameters<double>& start,
                                      const model::MotorData& motor,
                                      const OutputErrorOptions& options) {
  if (experiments.empty()) throw std::invalid_argument("output error: no experiments");
  for (const auto& e : experiments) check_experiment(e);
  for (double v : start) {
    if (!std::isfinite(v)) throw std::invalid_argument("output error: the start is not finite");
  }
  OutputErrorResult result;
  std::array<double, model::kParameterCount> theta = theta_from_natural(start, result.warnings);
  std::array<double, 2> aux = {options.input_lag_s, 0.0};

  std::vector<Segment> segments;
  for (std::size_t i = 0; i < experiments.size(); ++i) {
    const std::vector<Segment> s = cut_segments(experiments[i], i, options.segment_s);
    segments.insert(segments.end(), s.begin(), s.end());
    result.observations += experiments[i].observations.size();
  }
  std::vector<double> gains(experiments.size(), 1.0);
  std::vector<std::array<double, 4>> states(segments.size());
  for (std::size_t k = 0; k < segments.size(); ++k) {
    states[k] = start_state(experiments[segments[k].experiment], segments[k].t_start_s);
  }

  ceres::Problem problem;
  problem.AddParameterBlock(theta.data(), model::kParameterCount);
  problem.SetParameterLowerBound(theta.data(), 5, 0.0);
  problem.SetParameterLowerBound(theta.data(), 6, 0.0);
  problem.AddParameterBlock(aux.data(), 2);
  std::vector<int> held;
  if (!options.estimate_lag) held.push_back(0);
  if (!options.estimate_q2_offset) held.push_back(1);
  if (held.size() == 2) {
    problem.SetParameterBlockConstant(aux.data());
  } else if (!held.empty()) {
    problem.SetManifold(aux.data(), new ceres::SubsetManifold(2, held));
  }
  if (options.estimate_lag) {
    problem.SetParameterLowerBound(aux.data(), 0, std::min(options.min_lag_s, 0.0));
    problem.SetParameterUpperBound(aux.data(), 0, 0.05);
  }
  // The residual blocks in clusters for the robust covariance: each segment's, each prior's.
  std::vector<ceres::ResidualBlockId> clusters;
  std::vector<double*> free_blocks = {theta.data()};
  if (held.size() < 2) free_blocks.push_back(aux.data());
  for (std::size_t i = 0; i < experiments.size(); ++i) {
    problem.AddParameterBlock(&gains[i], 1);
    if (experiments[i].input_gain_sigma > 0) {
      clusters.push_back(
          problem.AddResidualBlock(new ceres::AutoDiffCostFunction<GainPrior, 1, 1>(
                                       new GainPrior{experiments[i].input_gain_sigma}),
                                   nullptr, &gains[i]));
      free_blocks.push_back(&gains[i]);
    } else {
      problem.SetParameterBlockConstant(&gains[i]);
    }
  }
  for (std::size_t k = 0; k < segments.size(); ++k) {
    const OeExperiment& e = experiments[segments[k].experiment];
    double* gain = &gains[segments[k].experiment];
    const double w = options.continuity_weight;
    SegmentCost cost{&e,
                     &motor,
                     segments[k],
                     options.substep_s,
                     {e.angle_sigma_rad[0] / w, e.angle_sigma_rad[0] / w / kVelocityDefectTime_s,
                      e.angle_sigma_rad[1] / w, e.angle_sigma_rad[1] / w / kVelocityDefectTime_s}};
    const int residuals = cost.residual_count();
    if (segments[k].t_next_s >= 0) {
      clusters.push_back(problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<SegmentCost, ceres::DYNAMIC, 7, 2, 1, 4, 4>(
              new SegmentCost(cost), residuals),
          nullptr, theta.data(), aux.data(), gain, states[k].data(), states[k + 1].data()));
    } else {
      clusters.push_back(problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<SegmentCost, ceres::DYNAMIC, 7, 2, 1, 4>(
              new SegmentCost(cost), residuals),
          nullptr, theta.data(), aux.data(), gain, states[k].data()));
    }
  }
  for (auto& x : states) free_blocks.push_back(x.data());

  ceres::Solver::Summary summary;
  ceres::Solve(solver_options(options.max_iterations, options.num_threads), &problem, &summary);
  result.iterations = static_cast<int>(summary.iterations.size()) - 1;
  result.converged = summary.termination_type == ceres::CONVERGENCE;
  result.message = summary.BriefReport();
  result.segments = segments.size();
  result.estimate = natural_from_theta(theta.data());
  result.input_lag_s = aux[0];
  result.q2_offset_rad = aux[1];
  result.input_gain = gains;

  // Residuals at the optimum: angle RMS per joint (unweighted), continuity defects (weighted).
  {
    std::array<double, 2> sum = {0, 0};
    std::array<std::size_t, 2> count = {0, 0};
    double continuity = 0;
    std::size_t continuity_count = 0;
    for (std::size_t k = 0; k < segments.size(); ++k) {
      const OeExperiment& e = experiments[segments[k].experiment];
      const double w = options.continuity_weight;
      SegmentCost cost{
          &e,
          &motor,
          segments[k],
          options.substep_s,
          {e.angle_sigma_rad[0] / w, e.angle_sigma_rad[0] / w / kVelocityDefectTime_s,
           e.angle_sigma_rad[1] / w, e.angle_sigma_rad[1] / w / kVelocityDefectTime_s}};
      std::vector<double> r(static_cast<std::size_t>(cost.residual_count()));
      if (segments[k].t_next_s >= 0) {
        cost(theta.data(), aux.data(), &gains[segments[k].experiment], states[k].data(),
             states[k + 1].data(), r.data());
      } else {
        cost(theta.data(), aux.data(), &gains[segments[k].experiment], states[k].data(), r.data());
      }
      for (std::size_t i = segments[k].first; i < segments[k].end; ++i) {
        const int j = e.observations[i].joint;
        const double rad = r[i - segments[k].first] * e.angle_sigma_rad[j];
        sum[j] += rad * rad;
        ++count[j];
      }
      for (std::size_t i = segments[k].end - segments[k].first; i < r.size(); ++i) {
        continuity += r[i] * r[i];
        ++continuity_count;
      }
    }
    for (int j = 0; j < 2; ++j) {
      result.angle_rms_rad[j] = count[j] ? std::sqrt(sum[j] / static_cast<double>(count[j])) : 0;
    }
    result.continuity_rms =
        continuity_count ? std::sqrt(continuity / static_cast<double>(continuity_count)) : 0;
  }

  // Every residual (angles and continuity) against every free parameter: the continuity rows
  // tie consecutive states, so the degrees of freedom are those of one state per experiment.
  const double dof = static_cast<double>(summary.num_residuals - summary.num_effective_parameters);
  result.residual_sigma = dof > 0 ? std::sqrt(2.0 * summary.final_cost / dof) : 0.0;
  assumed_angle_noise(result, experiments);
  time_stamps(result, experiments);
  misfit_warnings(result, options);

  const int lag_column = options.estimate_lag ? 7 : -1;
  const std::optional<LeadingCovariance> covariance =
      leading_covariance(problem, free_blocks, clusters, options.estimate_lag ? 8 : 7);
  if (covariance) {
    // Each coordinate's larger variance: the robust one where the angle errors are correlated,
    // the local one where few segments make the robust one a poor estimate of itself.
    const Eigen::MatrixXd local =
        covariance->local * (result.residual_sigma * result.residual_sigma);
    Eigen::MatrixXd combined = local;
    for (int i = 0; i < combined.rows(); ++i) {
      const double robust = covariance->robust(i, i);
      if (robust > combined(i, i) && combined(i, i) > 0) {
        const double scale = std::sqrt(robust / combined(i, i));
        combined.row(i) *= scale;
        combined.col(i) *= scale;
      }
    }
    // The chain rule: d p / d theta at the optimum, by the same automatic differentiation.
    using Jet = ceres::Jet<double, 7>;
    std::array<Jet, 7> theta_jet;
    for (int i = 0; i < 7; ++i) theta_jet[i] = Jet(theta[i], i);
    const model::Parameters<Jet> p = natural_from_theta(theta_jet.data());
    Eigen::Matrix<double, 7, 7> jac;
    for (int i = 0; i < 7; ++i) jac.row(i) = p[static_cast<std::size_t>(i)].v.transpose();
    const Eigen::Matrix<double, 7, 7> natural =
        jac * combined.topLeftCorner(7, 7) * jac.transpose();
    const Eigen::Matrix<double, 7, 7> natural_local =
        jac * local.topLeftCorner(7, 7) * jac.transpose();
    for (std::size_t i = 0; i < 7; ++i) {
      const auto k = static_cast<int>(i);
      result.std_dev[i] = std::sqrt(std::max(0.0, natural(k, k)));
      result.local_std_dev[i] = std::sqrt(std::max(0.0, natural_local(k, k)));
    }
    result.input_lag_std_s =
        lag_column < 0 ? 0.0 : std::sqrt(std::max(0.0, combined(lag_column, lag_column)));
  } else {
    result.warnings.push_back(
        "output error: the covariance could not be computed (a direction the data leave free)");
    for (double& v : result.std_dev) v = std::numeric_limits<double>::quiet_NaN();
    result.local_std_dev = result.std_dev;
  }
  if (!result.converged) {
    result.warnings.push_back("output error: no convergence: " + result.message);
  }
  if (result.input_lag_s < 0) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "output error: the angles lead the recorded input by %.2f ms (a negative lag): "
                  "the logger stamps the input after the angles it drives?",
                  -result.input_lag_s * 1e3);
    result.warnings.push_back(text);
  }
  return result;
}

FreeRun simulate_free_run(const OeExperiment& e, const model::Parameters<double>& p,
                          const model::MotorData& motor, double input_lag_s, double q2_offset_rad,
                          double input_gain, const OutputErrorOptions& options) {
  check_experiment(e);
  std::vector<std::string> unused;
  std::array<double, model::kParameterCount> theta = theta_from_natural(p, unused);
  std::array<double, 2> aux = {input_lag_s, q2_offset_rad};
  const std::vector<Segment> segments = cut_segments(e, 0, options.segment_s);
  std::array<double, 4> x0 = start_state(e, segments.front().t_start_s);
  {
    // The first state fitted with the parameters held, so that both parameter sets compared start
    // from the state that suits them.
    Segment first = segments.front();
    first.t_next_s = -1;
    SegmentCost cost{&e, &motor, first, options.substep_s, {1, 1, 1, 1}};
    ceres::Problem problem;
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<SegmentCost, ceres::DYNAMIC, 7, 2, 1, 4>(
            new SegmentCost(cost), cost.residual_count()),
        nullptr, theta.data(), aux.data(), &input_gain, x0.data());
    problem.SetParameterBlockConstant(theta.data());
    problem.SetParameterBlockConstant(aux.data());
    problem.SetParameterBlockConstant(&input_gain);
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options(options.max_iterations, 1), &problem, &summary);
  }
  // The whole experiment as one segment from that state, with the input's own model.
  Segment all{0, 0, e.observations.size(), e.observations.front().t_s, -1};
  const model::Parameters<double> natural = natural_from_theta(theta.data());
  State<double> x{x0[0], x0[1], x0[2], x0[3]};
  double t = all.t_start_s;
  FreeRun run;
  std::array<double, 2> sum = {0, 0};
  std::array<std::size_t, 2> count = {0, 0};
  for (const OeObservation& o : e.observations) {
    x = integrate(e, motor, natural, input_lag_s, input_gain, x, t, o.t_s, options.substep_s);
    t = std::max(t, o.t_s);
    const double measured = o.joint == 0 ? o.angle_rad : o.angle_rad + q2_offset_rad;
    const double simulated = o.joint == 0 ? x.q1 : x.q2;
    run.t_s.push_back(o.t_s);
    run.joint.push_back(o.joint);
    run.measured.push_back(measured);
    run.simulated.push_back(simulated);
    sum[o.joint] += (simulated - measured) * (simulated - measured);
    ++count[o.joint];
  }
  std::array<double, 2> mean = {0, 0};
  for (std::size_t i = 0; i < run.measured.size(); ++i) {
    mean[run.joint[i]] += run.measured[i] / static_cast<double>(count[run.joint[i]]);
  }
  std::array<double, 2> spread = {0, 0};
  for (std::size_t i = 0; i < run.measured.size(); ++i) {
    const double d = run.measured[i] - mean[run.joint[i]];
    spread[run.joint[i]] += d * d;
  }
  for (int j = 0; j < 2; ++j) {
    run.rmse_rad[j] = count[j] ? std::sqrt(sum[j] / static_cast<double>(count[j])) : 0.0;
    run.measured_sd_rad[j] = count[j] ? std::sqrt(spread[j] / static_cast<double>(count[j])) : 0.0;
  }
  return run;
}

}  // namespace furuta::identification
