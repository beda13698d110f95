#pragma once
// The whole LSMI identification of one or more experiments, plus held-out validation: what
// `furuta identify` prints and writes (Table I, results.json, figures).

#include <optional>
#include <string>
#include <vector>

#include "furuta/identification/lsmi.hpp"
#include "furuta/identification/preprocessing.hpp"

namespace furuta::identification {

struct IdentifyOptions {
  PreprocessOptions preprocess;
  LsmiOptions lsmi;  // trim_samples 0 here means: the filters' edge length
  // Estimate the lag between the recorded input and the angles (USB and board latencies the log
  // cannot see) as the one, within +- one sample period, that minimises the combined fit's
  // residual; preprocess.input_lag_s is then only the starting point. See torque_with_input_lag.
  bool estimate_input_lag = true;
};

// Fewer held-out samples than this (two pendulum periods at 16 ms) make its RMSE a warning.
inline constexpr std::size_t kFewValidationSamples = 100;

struct ValidationResult {
  std::string name;
  TorqueFit fit;  // with the combined LSMI estimate
  JointSeries series;
};

struct Identification {
  std::vector<RawExperiment> raw;
  std::vector<JointSeries> processed;
  std::vector<LsmiResult> per_experiment;            // Table I: one column each
  LsmiResult combined;                               // and all together
  std::optional<model::Parameters<double>> nominal;  // CAD values, from the configuration
  std::optional<model::Parameters<double>>
      truth;  // simulated sessions: the simulated rig's parameters
  std::optional<ValidationResult> validation;
  double input_lag_s = 0;  // as used (estimated or given)
  std::vector<std::string> warnings;
};

// The fewest samples one experiment (fitted or held out) needs: the filters' edge at each end,
// trimmed before fitting (edge_samples, or lsmi.trim_samples when given), and enough samples
// between for as many equations (two per sample) as there are parameters.
std::size_t minimum_samples(const IdentifyOptions& options);

// Why an experiment is too short to identify ("too short to identify: 62 samples (0.992 s); the
// fit needs at least 82 ..."), or "" when it is long enough.
std::string length_problem(const RawExperiment& experiment, const IdentifyOptions& options);

// Throws std::invalid_argument naming the experiment, its length and the length needed when one
// has fewer than minimum_samples (length_problem).
Identification identify(const std::vector<RawExperiment>& experiments,
                        const std::optional<RawExperiment>& validation,
                        const IdentifyOptions& options, const model::MotorData& motor,
                        const VoltageMotor& voltage_motor = {});

struct InputFile {
  std::string path;
  std::string sha256;
};
// Hex SHA-256 of a file (inputs are identified by content in results.json).
std::string sha256_file(const std::string& path);

}  // namespace furuta::identification
