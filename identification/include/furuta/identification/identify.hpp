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
  // A fitted experiment too short for the filters (length_problem) leaves LSMI out
  // (Identification::lsmi_skipped) instead of refusing: for a caller whose own estimator needs
  // no derivatives (the output-error refinement).
  bool lsmi_optional = false;
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
  // Why LSMI did not run, or "" when it did (IdentifyOptions::lsmi_optional). per_experiment is
  // then empty, combined all zero, there is no held-out torque fit, and input_lag_s is the one
  // given.
  std::string lsmi_skipped;
  bool lsmi_ran() const { return lsmi_skipped.empty(); }
};

// The fewest samples one experiment (fitted or held out) needs: the filters' edge at each end,
// trimmed before fitting (edge_samples, or lsmi.trim_samples when given), and enough samples
// between for as many equations (two per sample) as there are parameters.
std::size_t minimum_samples(const IdentifyOptions& options);

// Why an experiment is too short for LSMI ("too short for LSMI: 62 samples (0.992 s); its fit
// needs at least 82 ..."), or "" when it is long enough.
std::string length_problem(const RawExperiment& experiment, const IdentifyOptions& options);

// Throws std::invalid_argument naming the experiment, its length and the length needed when one
// has fewer than minimum_samples (length_problem), unless options.lsmi_optional: then a fitted
// experiment that short leaves LSMI out, and a held-out one its torque fit (a warning each).
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
