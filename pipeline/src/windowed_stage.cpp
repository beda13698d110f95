// The guaranteed stage: the windowed set inversion over the converged refinement's estimate +- k
// sd, in the parameters the data determine, and the rig's parameters it allows.
#include "furuta/identification/physical_inputs.hpp"
#include "stages.hpp"

namespace furuta::pipeline {

namespace {

using detail::oe_experiment;

// The windowed set inversion over the converged refinement's estimate +- k sd (pipeline.hpp).
std::optional<WindowedGuaranteed> invert_windows(const WindowedSettings& settings,
                                                 const Batch& batch, Run& run, Progress* progress) {
  const auto warn = [&](Warning::Kind kind, const std::string& text) {
    run.warnings.push_back({Warning::Stage::guaranteed, kind, "guaranteed: " + text});
  };
  using Kind = Warning::Kind;
  if (!run.output_error || !run.output_error->result.converged) {
    warn(Kind::skipped,
         "skipped: the windows search around the output-error estimate, and the refinement did "
         "not run or did not converge");
    return std::nullopt;
  }
  std::vector<identification::OeExperiment> experiments;
  std::vector<double> supply;
  for (const Recording& r : batch.fit) {
    experiments.push_back(oe_experiment(r, batch));
    supply.insert(supply.end(), experiments.back().supply_readings_v.begin(),
                  experiments.back().supply_readings_v.end());
  }
  const bool logs = batch.kind == InputKind::session_logs;
  if (!logs && !batch.recording_bounds) {
    warn(Kind::skipped,
         "skipped: a CSV recording's bounds (encoders, zero, lag, supply) are its import spec's "
         "[guaranteed] table, and the spec has none");
    return std::nullopt;
  }
  const identification::RecordingBounds bounds =
      logs ? identification::session_log_bounds(batch.rig) : *batch.recording_bounds;
  if (supply.empty() && !bounds.supply) {
    warn(Kind::skipped,
         "skipped: the recordings carry no supply readings (the drive's gain needs them)");
    return std::nullopt;
  }
  identification::WindowedSetOptions options = settings.options;
  options.arm_rest_speed_rad_s = bounds.arm_rest_speed_rad_s;
  WindowedGuaranteed out;
  const identification::OutputErrorResult& oe = run.output_error->result;
  try {
    out.inputs = identification::physical_inputs(batch.rig, supply, bounds);
    // The estimate's scale: the nominal motor at the sessions' supply, times the fitted gains.
    double scale = 0;
    for (std::size_t i = 0; i < experiments.size(); ++i) {
      const double gain = i < oe.input_gain.size() ? oe.input_gain[i] : 1.0;
      scale += experiments[i].supply_scale * gain / static_cast<double>(experiments.size());
    }
    out.gain_nm = batch.rig.motor.arm_torque_nm(1.0, 0.0) * scale;
    out.back_emf_nm_s = -batch.rig.motor.arm_torque_nm(0.0, 1.0);
    out.search_sd = settings.search_sd;
    const model::Parameters<interval::Interval> search = identification::search_box(
        oe.estimate, oe.std_dev, settings.search_sd, out.gain_nm, out.back_emf_nm_s, out.inputs);
    for (std::size_t k = 0; k < model::kParameterCount; ++k) {
      const double shift = k == 5 ? out.back_emf_nm_s : 0.0;
      out.estimate_scaled[k] = (oe.estimate[k] + shift) / out.gain_nm;
      out.std_dev_scaled[k] = oe.std_dev[k] / out.gain_nm;
    }
    if (batch.truth) {
      model::Parameters<double> t{};
      for (std::size_t k = 0; k < model::kParameterCount; ++k) {
        t[k] = ((*batch.truth)[k] + (k == 5 ? out.back_emf_nm_s : 0.0)) / out.gain_nm;
      }
      out.truth_scaled = t;
    }
    const auto step = [progress](std::size_t done, std::size_t total) {
      if (progress != nullptr) progress->windows(done, total);
    };
    out.result = identification::invert_recordings(experiments, out.inputs, search, options, step);
  } catch (const std::invalid_argument& e) {
    if (progress != nullptr) progress->windows_done();
    warn(Kind::skipped, std::string("skipped: ") + e.what());
    return std::nullopt;
  }
  if (progress != nullptr) progress->windows_done();
  const identification::WindowedSet& r = out.result;
  if (r.verdict == identification::WindowedSetVerdict::empty) {
    warn(Kind::failed, "empty set: " + r.finding);
  } else {
    out.rig_set = identification::rig_parameters(r.set, out.inputs.drive);
    const model::Parameters<interval::Interval> point_rig = identification::rig_parameters(
        r.set.map([](const interval::Interval& x) { return interval::Interval(x.mid()); }),
        out.inputs.drive);
    for (std::size_t k = 0; k < model::kParameterCount; ++k) {
      const double width = out.rig_set[k].width();
      out.drive_share[k] = width > 0 ? point_rig[k].width() / width : 0.0;
    }
    if (r.verdict == identification::WindowedSetVerdict::unresolved) {
      warn(Kind::failed, "nothing concluded: " + r.finding);
    }
    interval::Box hull(model::kParameterCount);
    for (std::size_t k = 0; k < model::kParameterCount; ++k) hull[k] = r.set[k];
    run.windowed_excludes_output_error =
        estimates_outside(hull, out.estimate_scaled, out.std_dev_scaled);
  }
  return out;
}

}  // namespace

namespace detail {

void run_windowed(const Batch& batch, const Settings& settings, Run& run, Progress* progress) {
  run.windowed = invert_windows(settings.windowed, batch, run, progress);
}

}  // namespace detail
}  // namespace furuta::pipeline
