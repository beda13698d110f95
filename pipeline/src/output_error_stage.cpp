// The output-error stage: the refinement from the combined LSMI estimate (or the CAD values), the
// diagnosis of recording mistakes, the held-out free runs.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "furuta/identification/physical.hpp"
#include "stages.hpp"

namespace furuta::pipeline {

namespace detail {

identification::OeExperiment oe_experiment(const Recording& r, const Batch& batch) {
  if (r.oe) return *r.oe;
  const identification::RawExperiment& e = r.experiment;
  // The angle noise from each encoder's resolution as the import spec states it; where it says
  // nothing, estimated from the readings themselves, and the misfit warning says so.
  std::array<double, 2> sigma{};
  std::array<identification::AngleNoiseSource, 2> source{};
  for (std::size_t j = 0; j < 2; ++j) {
    const double stated = batch.encoder_resolution_rad[j];
    if (stated > 0) {
      source[j] = identification::AngleNoiseSource::encoder_resolution;
      sigma[j] = stated / std::sqrt(12.0);
      continue;
    }
    const bool own = !e.recorded.empty();
    const std::vector<double>& q =
        j == 0 ? (own ? e.recorded.q1_rad : e.q1) : (own ? e.recorded.q2_rad : e.q2);
    source[j] = identification::AngleNoiseSource::estimated_from_readings;
    sigma[j] = identification::angle_noise_from_readings(q);
    // Readings that never change carry no noise to estimate; any positive weight fits them.
    if (!(sigma[j] > 0)) sigma[j] = 1e-3;
  }
  // As the import spec says (docs/csv-import.md, input_between_samples; linear unless it says).
  identification::OeExperiment out = identification::oe_experiment_from_raw(
      e, sigma, batch.input_between_samples, batch.voltage_motor,
      batch.rig.motor.nominal_voltage_v);
  out.angle_noise_source = source;
  return out;
}

}  // namespace detail

namespace {

using detail::oe_experiment;

// The index of the better of several fits of the same data: a converged one before one that is
// not, then the smaller residual sigma.
std::size_t better_fit(const std::vector<identification::OutputErrorResult>& fits) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < fits.size(); ++i) {
    const auto& a = fits[i];
    const auto& b = fits[best];
    if (a.converged != b.converged ? a.converged : a.residual_sigma < b.residual_sigma) best = i;
  }
  return best;
}

std::string short_sigma(const identification::OutputErrorResult& fit) {
  std::ostringstream s;
  s << std::setprecision(3) << fit.residual_sigma << (fit.converged ? "" : " not converged");
  return s.str();
}

// The refinement from the combined LSMI estimate, the held-out free runs, and the check that the
// result is physical. Nothing (with a warning) when a recording has no OeExperiment of its own.
std::optional<OutputError> refine(const OutputErrorSettings& settings,
                                  const identification::IdentifyOptions& identify_options,
                                  const Batch& batch, Run& run, Progress* progress) {
  const auto warn = [&](Warning::Kind kind, const std::string& text) {
    // In the plain list a warning names its stage in its text (the refinement's own warnings
    // already do); in the staged list the stage says it.
    const std::string prefix = "output error: ";
    const bool prefixed = text.rfind(prefix, 0) == 0;
    run.identification.warnings.push_back(prefixed ? text : prefix + text);
    run.warnings.push_back(
        {Warning::Stage::output_error, kind, prefixed ? text.substr(prefix.size()) : text});
  };
  using Kind = Warning::Kind;
  std::vector<const Recording*> fitted;
  for (const Recording& r : batch.fit) fitted.push_back(&r);
  const bool logs = batch.kind == InputKind::session_logs;
  const auto usable = [&](const Recording& r) { return !logs || r.oe.has_value(); };
  if (!std::all_of(fitted.begin(), fitted.end(), [&](const Recording* r) { return usable(*r); })) {
    warn(Kind::skipped,
         "skipped: a fitted log's recording has no output-error experiment (angles at their "
         "report times, the commands written)");
    return std::nullopt;
  }
  std::vector<identification::OeExperiment> experiments;
  for (const Recording* r : fitted) experiments.push_back(oe_experiment(*r, batch));
  if (progress != nullptr) progress->output_error_started(experiments.size());
  OutputError out;
  identification::OutputErrorOptions options = settings.options;
  // Another logger may stamp its input after the angles (docs/csv-import.md); a session log's
  // angles never lead the commands written.
  if (!logs) options.min_lag_s = -0.05;
  // LSMI is biased exactly where the refinement is needed (coarse sampling, a lag, closed-loop
  // input), so its verdict only adds starts: when it is not physical the fit also starts from the
  // CAD values, and the better fit is kept. A recording mistake shows in the fit's residuals.
  struct Start {
    const char* name;
    model::Parameters<double> parameters;
  };
  std::vector<Start> starts;
  const identification::Identification& id = run.identification;
  if (id.lsmi_ran()) starts.push_back({"the LSMI estimate", id.combined.estimate});
  const bool lsmi_suspect = !id.lsmi_ran() || run.physical.clear() ||
                            run.physical.cause != identification::LikelyCause::none;
  if (lsmi_suspect && batch.nominal) starts.push_back({"the CAD values", *batch.nominal});
  if (starts.empty()) {
    warn(Kind::skipped,
         "skipped: LSMI did not run and the configuration has no CAD values ([nominal]) to start "
         "from");
    return std::nullopt;
  }
  std::vector<identification::OutputErrorResult> fits;
  try {
    for (const Start& start : starts) {
      fits.push_back(identification::refine_output_error(experiments, start.parameters,
                                                         batch.rig.motor, options));
    }
  } catch (const std::invalid_argument& e) {
    warn(Kind::skipped, std::string("skipped: ") + e.what());
    return std::nullopt;
  }
  const std::size_t best = better_fit(fits);
  out.result = fits[best];
  if (!id.lsmi_ran()) {
    warn(Kind::note, "started from the CAD values, since LSMI did not run");
  } else if (starts.size() > 1) {
    std::ostringstream said;
    said << "LSMI is not physical (" << identification::cause_name(run.physical.cause)
         << "), so the refinement also started from " << starts[1].name << "; kept the fit from "
         << starts[best].name << " (residual sigma";
    for (std::size_t i = 0; i < fits.size(); ++i) {
      said << (i == 0 ? " " : ", ") << short_sigma(fits[i]) << " from " << starts[i].name;
    }
    said << ")";
    warn(Kind::note, said.str());
  }
  for (const auto& e : experiments) {
    for (const auto& w : e.warnings) warn(Kind::data, w);
  }
  for (const auto& w : out.result.warnings) warn(Kind::suspect, w);
  if (!out.result.converged) warn(Kind::failed, "did not converge: " + out.result.message);

  // The parametrisation keeps the inertias and mug positive and M positive definite, but lets mu3
  // take either sign and a parameter reach its bound: a sign-flipped pendulum fits exactly with
  // mu3 < 0. So the refined estimate is checked like LSMI's, and a violation names its cause.
  const identification::RecordingEvidence evidence =
      identification::recording_evidence(run.identification.raw);
  out.physical = identification::check_physical(out.result.estimate, out.result.std_dev,
                                                std::nullopt, &evidence);
  if (!out.physical.consistent()) {
    warn(Kind::suspect,
         identification::physical_warning(out.physical,
                                          logs ? identification::RecordingSource::session_log
                                               : identification::RecordingSource::csv,
                                          "the output-error estimate"));
  }

  // A fit that is no rig's answer is refitted with each candidate recording mistake undone; the
  // one the data support is named (a warning), with what to change.
  const identification::MistakeFit judged =
      identification::judge_fit(out.result, options, batch.nominal);
  if (settings.diagnose || identification::needs_diagnosis(judged)) {
    // Without CAD, each correction's fit starts from LSMI on the corrected data.
    const auto lsmi_start = [&](identification::Mistake mistake,
                                double value) -> std::optional<model::Parameters<double>> {
      std::vector<identification::RawExperiment> raws;
      for (const Recording* r : fitted) {
        raws.push_back(identification::corrected_raw(r->experiment, mistake, value));
      }
      try {
        const identification::Identification corrected = identification::identify(
            raws, std::nullopt, identify_options, batch.rig.motor, batch.voltage_motor);
        if (!corrected.lsmi_ran()) return batch.nominal;
        return corrected.combined.estimate;
      } catch (const std::exception&) {
        return std::nullopt;
      }
    };
    out.diagnosis = identification::diagnose_recording(experiments, out.result, batch.rig.motor,
                                                       options, batch.nominal, lsmi_start);
    out.counts_per_rev = logs ? std::array<double, 2>{batch.rig.arm_encoder.counts_per_rev,
                                                      batch.rig.pendulum_encoder.counts_per_rev}
                              : batch.counts_per_rev;
    if (!judged.plausible) {
      warn(Kind::suspect,
           identification::diagnosis_text(*out.diagnosis,
                                          logs ? identification::RecordingSource::session_log
                                               : identification::RecordingSource::csv,
                                          out.counts_per_rev));
    }
  }

  if (batch.held_out && usable(*batch.held_out)) {
    const identification::OeExperiment held = oe_experiment(*batch.held_out, batch);
    HeldOutFreeRuns runs;
    runs.name = held.name;
    const auto free_run = [&](const model::Parameters<double>& p) {
      return identification::simulate_free_run(held, p, batch.rig.motor, out.result.input_lag_s,
                                               out.result.q2_offset_rad, 1.0, settings.options);
    };
    try {
      if (id.lsmi_ran()) runs.lsmi = free_run(id.combined.estimate);
      runs.refined = free_run(out.result.estimate);
      out.held_out = std::move(runs);
    } catch (const std::invalid_argument& e) {
      warn(Kind::skipped, std::string("no held-out free run: ") + e.what());
    }
  } else if (batch.held_out) {
    warn(Kind::skipped,
         "no held-out free run: the held-out log's recording has no output-error experiment");
  }
  return out;
}

}  // namespace

namespace detail {

void run_output_error(const Batch& batch, const Settings& settings, Run& run, Progress* progress) {
  run.output_error = refine(settings.output_error, settings.identify, batch, run, progress);
}

}  // namespace detail
}  // namespace furuta::pipeline
