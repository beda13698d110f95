#pragma once
// Least-squares identification of the model's seven parameters (paper section III.B): the regressor
// of docs/model.md stacked over samples and experiments, solved by a rank-revealing factorisation.

#include <string>
#include <vector>

#include "furuta/model/model.hpp"

namespace furuta::identification {

// Joint positions, velocities, accelerations and the arm torque at each sample of one experiment,
// after preprocessing.
struct JointSeries {
  std::string name;
  double sample_period_s = 0;
  std::vector<double> t_s, q1, q2, dq1, dq2, ddq1, ddq2, tau;
  std::vector<double> input;  // the filtered input (duty, voltage or torque) tau was formed from
  std::size_t size() const { return t_s.size(); }
};

struct LsmiOptions {
  std::size_t trim_samples = 0;  // dropped at each end of every experiment (filter edge effects)
  // W is called ill-conditioned above this 2-norm condition number (of W with columns scaled to
  // unit norm, so units do not count).
  double condition_warning = 1e4;
  // A parameter is called poorly excited when its relative standard deviation exceeds this.
  double poorly_excited_relative_sd = 0.1;
};

struct LsmiResult {
  model::Parameters<double> estimate{};
  model::Parameters<double> std_dev{};      // sqrt(diag(sigma^2 (W^T W)^-1))
  model::Parameters<double> relative_sd{};  // std_dev / |estimate|
  double sigma = 0;                         // residual standard deviation, N m
  double condition_number = 0;              // of the column-scaled W
  int rank = 0;
  std::size_t rows = 0;  // 2 per sample used
  std::vector<std::string> warnings;
  std::vector<std::string> poorly_excited;  // parameter names
};

// Throws std::invalid_argument when there are fewer rows than parameters.
LsmiResult solve_lsmi(const std::vector<const JointSeries*>& experiments,
                      const LsmiOptions& options = {});

// Predicted arm torque (row 1 of D p) at each sample.
std::vector<double> predicted_torque(const JointSeries& series, const model::Parameters<double>& p);

struct TorqueFit {
  double rmse_nm = 0;                // eq. 12
  double rmse_percent_of_range = 0;  // RMSE / (max tau - min tau) * 100
  std::size_t samples = 0;           // the samples compared (the trimmed edges left out)
  std::vector<double> predicted;
};
TorqueFit torque_fit(const JointSeries& series, const model::Parameters<double>& p,
                     std::size_t trim = 0);

}  // namespace furuta::identification
