#include "furuta/identification/lsmi.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace furuta::identification {

namespace {

// A number in a warning as a person writes it ("10", "2.35e+05"), not std::to_string's
// "10.000000".
std::string short_text(double v, int significant) {
  std::ostringstream s;
  s.precision(significant);
  s << v;
  return s.str();
}

}  // namespace

LsmiResult solve_lsmi(const std::vector<const JointSeries*>& experiments,
                      const LsmiOptions& options) {
  std::size_t samples = 0;
  for (const JointSeries* e : experiments) {
    if (e->size() > 2 * options.trim_samples) samples += e->size() - 2 * options.trim_samples;
  }
  const auto rows = static_cast<Eigen::Index>(2 * samples);
  if (rows < static_cast<Eigen::Index>(model::kParameterCount)) {
    throw std::invalid_argument("LSMI: " + std::to_string(rows) + " equations for " +
                                std::to_string(model::kParameterCount) + " parameters");
  }
  Eigen::MatrixXd W(rows, model::kParameterCount);
  Eigen::VectorXd Y(rows);
  Eigen::Index r = 0;
  for (const JointSeries* e : experiments) {
    for (std::size_t i = options.trim_samples; i + options.trim_samples < e->size(); ++i) {
      const model::RegressorRows d =
          model::regressor(e->q2[i], e->dq1[i], e->dq2[i], e->ddq1[i], e->ddq2[i]);
      for (std::size_t j = 0; j < model::kParameterCount; ++j) {
        W(r, j) = d.row1[static_cast<std::size_t>(j)];
        W(r + 1, j) = d.row2[static_cast<std::size_t>(j)];
      }
      Y(r) = e->tau[i];
      Y(r + 1) = 0.0;
      r += 2;
    }
  }

  // Columns scaled to unit norm: the parameters span five orders of magnitude, and both the
  // factorisation's rank decision and the condition number should not depend on units.
  Eigen::VectorXd scale = W.colwise().norm().transpose();
  for (Eigen::Index j = 0; j < scale.size(); ++j) {
    if (scale(j) == 0.0) scale(j) = 1.0;
  }
  const Eigen::MatrixXd Ws = W * scale.cwiseInverse().asDiagonal();
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(Ws);
  const Eigen::VectorXd ps = qr.solve(Y);
  const Eigen::VectorXd p = ps.cwiseQuotient(scale);

  LsmiResult result;
  result.rows = static_cast<std::size_t>(rows);
  result.rank = static_cast<int>(qr.rank());
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Ws);
  const auto& sv = svd.singularValues();
  result.condition_number =
      sv(sv.size() - 1) > 0 ? sv(0) / sv(sv.size() - 1) : std::numeric_limits<double>::infinity();
  const Eigen::VectorXd residual = Y - W * p;
  const double dof = static_cast<double>(rows - static_cast<Eigen::Index>(model::kParameterCount));
  result.sigma = std::sqrt(residual.squaredNorm() / dof);
  // Cov(p) = sigma^2 (W^T W)^-1 = S^-1 sigma^2 (Ws^T Ws)^-1 S^-1.
  const Eigen::MatrixXd cov_scaled =
      result.sigma * result.sigma *
      (Ws.transpose() * Ws)
          .ldlt()
          .solve(Eigen::MatrixXd::Identity(model::kParameterCount, model::kParameterCount));
  for (std::size_t j = 0; j < model::kParameterCount; ++j) {
    const auto k = static_cast<std::size_t>(j);
    result.estimate[k] = p(j);
    result.std_dev[k] = std::sqrt(std::max(0.0, cov_scaled(j, j))) / scale(j);
    result.relative_sd[k] =
        p(j) != 0.0 ? result.std_dev[k] / std::abs(p(j)) : std::numeric_limits<double>::infinity();
    if (result.relative_sd[k] > options.poorly_excited_relative_sd) {
      result.poorly_excited.emplace_back(model::kParameterNames[k]);
    }
  }
  if (result.rank < static_cast<int>(model::kParameterCount)) {
    result.warnings.push_back("W has rank " + std::to_string(result.rank) + " of " +
                              std::to_string(model::kParameterCount) +
                              ": some parameters are not identifiable from these experiments");
  }
  if (result.condition_number > options.condition_warning) {
    result.warnings.push_back("W is ill-conditioned (condition number " +
                              short_text(result.condition_number, 3) +
                              "): the excitation is too poor for a reliable estimate");
  }
  if (!result.poorly_excited.empty()) {
    std::string names;
    for (const auto& n : result.poorly_excited) names += (names.empty() ? "" : ", ") + n;
    result.warnings.push_back("poorly excited (relative standard deviation above " +
                              short_text(options.poorly_excited_relative_sd * 100, 6) +
                              " %): " + names);
  }
  return result;
}

std::vector<double> predicted_torque(const JointSeries& s, const model::Parameters<double>& p) {
  std::vector<double> tau(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    const model::RegressorRows d =
        model::regressor(s.q2[i], s.dq1[i], s.dq2[i], s.ddq1[i], s.ddq2[i]);
    double y = 0;
    for (std::size_t j = 0; j < p.size(); ++j) y += d.row1[j] * p[j];
    tau[i] = y;
  }
  return tau;
}

TorqueFit torque_fit(const JointSeries& s, const model::Parameters<double>& p, std::size_t trim) {
  TorqueFit fit;
  fit.predicted = predicted_torque(s, p);
  double sum = 0, lo = 0, hi = 0;
  std::size_t n = 0;
  bool first = true;
  for (std::size_t i = trim; i + trim < s.size(); ++i) {
    const double e = s.tau[i] - fit.predicted[i];
    sum += e * e;
    ++n;
    lo = first ? s.tau[i] : std::min(lo, s.tau[i]);
    hi = first ? s.tau[i] : std::max(hi, s.tau[i]);
    first = false;
  }
  fit.samples = n;
  fit.rmse_nm = n > 0 ? std::sqrt(sum / static_cast<double>(n)) : 0.0;
  fit.rmse_percent_of_range = hi > lo ? fit.rmse_nm / (hi - lo) * 100.0 : 0.0;
  return fit;
}

}  // namespace furuta::identification
