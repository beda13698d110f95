// pipeline::run: the stages (stages.hpp) in order over one batch, and what they share.
#include "furuta/pipeline/pipeline.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

#include "furuta/session_log/log_integrity.hpp"
#include "stages.hpp"

namespace furuta::pipeline {

std::string warning_text(const std::vector<Warning>& warnings, Warning::Stage stage,
                         Warning::Kind kind) {
  std::string text;
  for (const Warning& w : warnings) {
    if (w.stage == stage && w.kind == kind) text = w.text;
  }
  return text;
}

Recording log_recording(const session_log::SessionLog& log, Role role,
                        const config::RigConfig& rig) {
  Recording recording{identification::experiment_from_log(log),
                      summarize_session(log, role == Role::fit ? "fit" : "held out"),
                      identification::oe_experiment_from_log(log, rig), !log.control.empty()};
  for (const std::string& note : session_log::integrity_notes(log)) {
    recording.experiment.warnings.push_back(log.path.filename().string() + ": " + note);
  }
  return recording;
}

Settings settings_for(const config::RigConfig& rig) {
  Settings s;
  identification::PreprocessOptions& p = s.identify.preprocess;
  p.cutoff_hz = rig.identification.cutoff_hz;
  p.differentiator_passband_hz = rig.identification.cutoff_hz;
  p.differentiator_stopband_hz = 2 * rig.identification.cutoff_hz;
  p.butterworth_order = rig.identification.butterworth_order;
  p.differentiator_taps = rig.identification.differentiator_taps;
  s.identify.estimate_input_lag = !rig.identification.input_lag_ms.has_value();
  p.input_lag_s = rig.identification.input_lag_ms.value_or(0.0) * 1e-3;
  s.output_error.run = rig.output_error.enabled;
  identification::OutputErrorOptions& oe = s.output_error.options;
  oe.segment_s = rig.output_error.segment_s;
  oe.substep_s = rig.output_error.substep_s;
  oe.estimate_lag = rig.output_error.estimate_lag;
  oe.max_iterations = rig.output_error.max_iterations;
  s.sivia.config = rig.sivia;
  s.sivia.threads = rig.sivia.threads;
  s.windowed.search_sd = rig.guaranteed.search_sd;
  s.windowed.options.window_s = rig.guaranteed.window_s;
  s.windowed.options.windows = static_cast<std::size_t>(rig.guaranteed.windows);
  return s;
}

std::vector<EstimateOutsideSet> estimates_outside(const interval::Box& hull,
                                                  const model::Parameters<double>& estimate,
                                                  const model::Parameters<double>& std_dev) {
  std::vector<EstimateOutsideSet> out;
  for (std::size_t k = 0; k < model::kParameterCount && k < hull.size(); ++k) {
    const interval::Interval& set = hull[k];
    const double value = estimate[k];
    if (set.is_empty() || set.contains(value)) continue;
    const double gap = value < set.lo() ? set.lo() - value : value - set.hi();
    const double sd = std_dev[k];
    out.push_back({k, value, set, sd > 0.0 ? gap / sd : std::numeric_limits<double>::infinity()});
  }
  std::sort(out.begin(), out.end(), [](const EstimateOutsideSet& a, const EstimateOutsideSet& b) {
    return a.sd_away < b.sd_away;
  });
  return out;
}

Run run(const Batch& batch, const Settings& settings, Progress* progress) {
  Run out;
  out.kind = batch.kind;
  out.settings = settings;
  out.rig_name = batch.rig.name;
  out.config_file = batch.config_file;
  out.config_carried_by = batch.config_carried_by;
  out.simulated_rig = batch.truth.has_value();
  out.angle_resolution_rad = batch.angle_resolution_rad;
  if (has_data_error_bounds(settings.sivia.config)) {
    out.data_bounds = data_error_bounds(settings.sivia.config);
  }
  detail::run_lsmi(batch, settings, out, progress);
  if (settings.output_error.run) detail::run_output_error(batch, settings, out, progress);
  if (!out.identification.lsmi_ran() && !out.output_error) {
    const std::string why =
        warning_text(out.warnings, Warning::Stage::output_error, Warning::Kind::skipped);
    throw std::invalid_argument("nothing identified: LSMI did not run (" +
                                out.identification.lsmi_skipped +
                                "), and the output-error refinement: " + why);
  }
  if (progress != nullptr) {
    progress->fit_done(out.identification, out.output_error ? &out.output_error->result : nullptr);
  }
  if (settings.sivia.run) detail::run_sivia(batch, settings, out, progress);
  if (settings.windowed.run) detail::run_windowed(batch, settings, out, progress);
  if (settings.simulation.run) detail::run_simulation(batch, settings, out, progress);
  return out;
}

}  // namespace furuta::pipeline
