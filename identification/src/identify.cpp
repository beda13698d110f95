#include "furuta/identification/identify.hpp"

#include <glib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "furuta/identification/guaranteed.hpp"

namespace furuta::identification {

namespace {

std::size_t trim_samples(const IdentifyOptions& options) {
  return options.lsmi.trim_samples != 0 ? options.lsmi.trim_samples
                                        : edge_samples(options.preprocess);
}

// Before any filtering: a short experiment would otherwise surface as "LSMI: 0 equations for 7
// parameters", naming neither the recording nor what it lacks.
void check_length(const RawExperiment& e, const IdentifyOptions& options) {
  const std::string problem = length_problem(e, options);
  if (!problem.empty()) throw std::invalid_argument(e.name + ": " + problem);
}

std::string shortest(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

// Equations whose input never moves are homogeneous in the parameters: LSMI answers every one 0 +-
// 0, which looks like a result. One such experiment among excited ones is harmless.
void check_excited(const std::vector<RawExperiment>& experiments) {
  std::string names;
  for (const RawExperiment& e : experiments) {
    const auto [lo, hi] = std::minmax_element(e.input.begin(), e.input.end());
    if (lo != e.input.end() && *lo != *hi) return;
    names += (names.empty() ? "" : ", ") + e.name + " (" +
             (lo == e.input.end() ? std::string("no input") : "input " + shortest(*lo)) + ")";
  }
  throw std::invalid_argument(
      "nothing to identify: the input is constant in every fitted "
      "recording (" +
      names +
      "); without an input that moves the rig every parameter would come "
      "out 0 +- 0. Fit sessions with an excitation (e.g. bang_bang)");
}

}  // namespace

std::size_t minimum_samples(const IdentifyOptions& options) {
  return 2 * trim_samples(options) + (model::kParameterCount + 1) / 2;
}

std::string length_problem(const RawExperiment& e, const IdentifyOptions& options) {
  const std::size_t needed = minimum_samples(options);
  if (e.t_s.size() >= needed) return "";
  std::ostringstream text;
  text << std::setprecision(3) << "too short for LSMI: " << e.t_s.size() << " samples";
  if (e.sample_period_s > 0) {
    text << " (" << static_cast<double>(e.t_s.size()) * e.sample_period_s << " s)";
  }
  text << "; its fit needs at least " << needed << " samples";
  if (e.sample_period_s > 0) {
    text << " (" << static_cast<double>(needed) * e.sample_period_s << " s at "
         << e.sample_period_s * 1e3 << " ms)";
  }
  text << ": " << trim_samples(options) << " at each end for the filters' transient and "
       << needed - 2 * trim_samples(options) << " between for " << model::kParameterCount
       << " parameters";
  return text.str();
}

Identification identify(const std::vector<RawExperiment>& experiments,
                        const std::optional<RawExperiment>& validation,
                        const IdentifyOptions& options, const model::MotorData& motor,
                        const VoltageMotor& voltage_motor) {
  if (experiments.empty()) throw std::invalid_argument("identify: no experiment given");
  Identification id;
  for (const RawExperiment& e : experiments) {
    if (!options.lsmi_optional) check_length(e, options);
    const std::string problem = length_problem(e, options);
    if (!problem.empty() && id.lsmi_ran()) id.lsmi_skipped = e.name + ": " + problem;
  }
  check_excited(experiments);
  if (validation && !options.lsmi_optional) check_length(*validation, options);
  id.raw = experiments;
  LsmiOptions lsmi = options.lsmi;
  if (lsmi.trim_samples == 0) lsmi.trim_samples = edge_samples(options.preprocess);
  for (const RawExperiment& e : experiments) {
    for (const auto& w : e.warnings) id.warnings.push_back(w);
    id.processed.push_back(preprocess(e, options.preprocess, motor, voltage_motor));
  }
  std::vector<const JointSeries*> all;
  for (const JointSeries& s : id.processed) all.push_back(&s);
  id.input_lag_s = options.preprocess.input_lag_s;
  if (!id.lsmi_ran()) {
    id.warnings.push_back("LSMI did not run: " + id.lsmi_skipped);
    if (validation) {
      for (const auto& w : validation->warnings) id.warnings.push_back(w);
    }
    return id;
  }
  if (options.estimate_input_lag) {
    // Golden-section search of the residual over the lag: the residual is smooth and has one
    // minimum within a sample period (as measured on simulated sessions:
    // docs/measurements/identification.md, "LSMI against the simulated truth").
    const auto residual = [&](double lag) {
      for (std::size_t i = 0; i < id.processed.size(); ++i) {
        torque_with_input_lag(id.processed[i], lag, experiments[i].input_kind, motor,
                              voltage_motor);
      }
      return solve_lsmi(all, lsmi).sigma;
    };
    const double period = id.processed.front().sample_period_s;
    const double golden = (std::sqrt(5.0) - 1) / 2;
    double a = id.input_lag_s - period, b = id.input_lag_s + period;
    double c = b - golden * (b - a), d = a + golden * (b - a);
    double fc = residual(c), fd = residual(d);
    while (b - a > 1e-6) {
      if (fc < fd) {
        b = d;
        d = c;
        fd = fc;
        c = b - golden * (b - a);
        fc = residual(c);
      } else {
        a = c;
        c = d;
        fc = fd;
        d = a + golden * (b - a);
        fd = residual(d);
      }
    }
    id.input_lag_s = (a + b) / 2;
    for (std::size_t i = 0; i < id.processed.size(); ++i) {
      torque_with_input_lag(id.processed[i], id.input_lag_s, experiments[i].input_kind, motor,
                            voltage_motor);
    }
    // Kept, not refused: a lag near zero can come out slightly negative from noise alone, and the
    // fit with it is still the best the data allow. But a reader must know it is not physical.
    if (id.input_lag_s < 0) {
      std::ostringstream w;
      w << std::setprecision(3) << "the estimated input lag is negative (" << id.input_lag_s * 1e3
        << " ms): the angles would move before the input that drives them, which no rig does; "
           "likely the input's sign or scale, the time stamps, or a lag the recording already "
           "removed is wrong. Check them, or give the lag (--input-lag-ms)";
      id.warnings.push_back(w.str());
    }
  }
  for (const JointSeries& s : id.processed) id.per_experiment.push_back(solve_lsmi({&s}, lsmi));
  id.combined = solve_lsmi(all, lsmi);
  for (std::size_t i = 0; i < id.per_experiment.size(); ++i) {
    for (const auto& w : id.per_experiment[i].warnings) {
      id.warnings.push_back(id.processed[i].name + ": " + w);
    }
  }
  for (const auto& w : id.combined.warnings) id.warnings.push_back("all experiments: " + w);
  const std::string held_out_short = validation ? length_problem(*validation, options) : "";
  if (validation && !held_out_short.empty()) {
    for (const auto& w : validation->warnings) id.warnings.push_back(w);
    id.warnings.push_back("held-out " + validation->name +
                          ": no LSMI torque check: " + held_out_short);
  } else if (validation) {
    for (const auto& w : validation->warnings) id.warnings.push_back(w);
    ValidationResult v;
    v.name = validation->name;
    PreprocessOptions preprocess = options.preprocess;
    preprocess.input_lag_s = id.input_lag_s;
    v.series = identification::preprocess(*validation, preprocess, motor, voltage_motor);
    v.fit = torque_fit(v.series, id.combined.estimate, lsmi.trim_samples);
    // A held-out figure from a few samples is one pendulum swing's, not the recording's.
    if (v.fit.samples < kFewValidationSamples) {
      id.warnings.push_back("held-out " + v.name + ": its torque RMSE rests on " +
                            std::to_string(v.fit.samples) +
                            " samples after the filters' edges are trimmed (fewer than " +
                            std::to_string(kFewValidationSamples) +
                            "): a longer held-out session makes it a figure to compare");
    }
    id.validation = std::move(v);
  }
  return id;
}

std::string sha256_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path);
  // GLib (already linked through LCM) provides the checksum: no hand-written SHA-256.
  std::unique_ptr<GChecksum, decltype(&g_checksum_free)> sum(g_checksum_new(G_CHECKSUM_SHA256),
                                                             &g_checksum_free);
  char buffer[65536];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
    g_checksum_update(sum.get(), reinterpret_cast<const guchar*>(buffer),
                      static_cast<gssize>(in.gcount()));
  }
  return g_checksum_get_string(sum.get());
}

}  // namespace furuta::identification
