// pipeline::run: LSMI, the held-out check, the output-error refinement, SIVIA and the scenarios
// over one batch.
#include "furuta/pipeline/pipeline.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "furuta/identification/physical.hpp"

namespace furuta::pipeline {

namespace {

identification::InnerTest inner_test(config::SiviaInnerTest test) {
  using identification::InnerTest;
  switch (test) {
    case config::SiviaInnerTest::witness:
      return InnerTest::witness;
    case config::SiviaInnerTest::intermediate_value:
      return InnerTest::intermediate_value;
    case config::SiviaInnerTest::for_all_data:
      return InnerTest::for_all_data;
    case config::SiviaInnerTest::none:
      break;
  }
  return InnerTest::none;
}

// SIVIA over the fitted sessions: the mu's around the combined LSMI estimate (Table II style), the
// frictions' priors, the data bounds and the paver settings from [sivia].
Guaranteed run_guaranteed(const SiviaSettings& settings, const identification::Identification& id,
                          const identification::IdentifyOptions& identify, Progress* progress) {
  using namespace identification;
  const config::SiviaConfig& cfg = settings.config;
  GuaranteedOptions g;
  g.prior = sivia_prior(cfg, id.combined.estimate);
  g.unknown.fill(false);
  for (const std::string& name : cfg.unknowns) {
    for (std::size_t k = 0; k < model::kParameterCount; ++k) {
      if (name == model::kParameterNames[k]) g.unknown[k] = true;
    }
  }
  g.epsilon = cfg.epsilon;
  g.epsilon_relative = cfg.epsilon_relative;
  g.contract = cfg.contract;
  g.inner = inner_test(cfg.inner_test);
  g.q = cfg.q;
  g.threads = settings.threads;
  if (progress != nullptr) {
    g.progress = [progress](std::size_t tested, std::size_t pending) {
      progress->sivia(tested, pending);
    };
  }
  Guaranteed out;
  out.bounds = data_error_bounds(cfg);
  std::vector<const JointSeries*> series;
  for (const JointSeries& s : id.processed) series.push_back(&s);
  const std::size_t trim = identify.lsmi.trim_samples != 0 ? identify.lsmi.trim_samples
                                                           : edge_samples(identify.preprocess);
  out.samples = interval_samples(series, out.bounds, trim);
  const SampleConstraints constraints(out.samples, g.prior, g.unknown);
  out.result = guaranteed_identification(constraints, g);
  if (progress != nullptr) progress->sivia_done();
  return out;
}

// The paper's scenarios with the fitted parameters: SIVIA's outer hull when it found a set (the
// carried mu's as their Table II intervals), the LSMI estimate as points. The measurements come
// from the simulated rig: the truth when the sessions were simulated, else the configuration's
// simulated-rig parameters.
Simulation run_simulation(const SimulationSettings& settings, const Run& run, const Batch& batch,
                          Progress* progress) {
  std::vector<validated::ParameterSet> sets;
  if (run.sivia && !run.sivia->result.empty) {
    const interval::Box h = run.sivia->result.paving.outer_hull();
    sets.push_back(
        {"SIVIA", model::Parameters<interval::Interval>{h[0], h[1], h[2], h[3], h[4], h[5], h[6]}});
  }
  if (run.identification.lsmi_ran()) {
    sets.push_back(validated::point_parameters("LSMI", run.identification.combined.estimate));
  }
  // A fit that did not converge is not an answer to simulate.
  if (run.output_error && run.output_error->result.converged) {
    sets.push_back(
        validated::point_parameters(kOutputErrorSetName, run.output_error->result.estimate));
  }
  if (run.windowed && run.windowed->result.verdict != identification::WindowedSetVerdict::empty) {
    // The scaled set as the rig's parameters per unit of gain under the torque per unit of gain:
    // the drive's tolerance then stays in one variable instead of widening all seven.
    const identification::DriveData& drive = run.windowed->inputs.drive;
    validated::ParameterSet set;
    set.name = kWindowedSetName;
    set.parameters = identification::rig_parameters_per_gain(run.windowed->result.set, drive);
    set.torque_scale = interval::Interval(1.0) / drive.gain_nm();
    set.taylor_models = true;
    sets.push_back(std::move(set));
  }
  MeasurementSource source;
  source.kind = batch.truth ? MeasurementSource::Kind::sessions_truth
                            : MeasurementSource::Kind::configured_rig;
  return simulate(settings.scenarios, sets, batch.truth.value_or(batch.rig.simulation.parameters),
                  source, settings.pieces, progress, settings.taylor_model_pieces);
}

}  // namespace

std::vector<Warning> identification_warnings(const identification::Identification& id) {
  std::set<std::string> lsmi;
  for (std::size_t i = 0; i < id.per_experiment.size() && i < id.processed.size(); ++i) {
    for (const auto& w : id.per_experiment[i].warnings)
      lsmi.insert(id.processed[i].name + ": " + w);
  }
  for (const auto& w : id.combined.warnings) lsmi.insert("all experiments: " + w);
  std::vector<Warning> out;
  for (const auto& w : id.warnings) {
    out.push_back({lsmi.contains(w) ? Warning::Stage::lsmi : Warning::Stage::data, w});
  }
  return out;
}

namespace {

// LSMI is unconstrained (the paper's reference), so its answer may be no rig at all: the combined
// estimate is checked, and each experiment's when that one is clearly outside while the combined
// is not (one recording of several made differently). Returns the combined estimate's check.
identification::PhysicalCheck check_physical(identification::Identification& id, InputKind kind,
                                             std::vector<Warning>& warnings) {
  using namespace identification;
  const RecordingSource source =
      kind == InputKind::csv_recordings ? RecordingSource::csv : RecordingSource::session_log;
  const auto add = [&](const std::string& text) {
    if (text.empty()) return;
    id.warnings.push_back(text);
    warnings.push_back({Warning::Stage::physical, text});
  };
  if (!id.lsmi_ran()) return {};
  const PhysicalCheck combined =
      identification::check_physical(id.combined.estimate, id.combined.std_dev, id.nominal);
  add(physical_warning(combined, source, "the LSMI estimate of all experiments"));
  if (combined.consistent() && combined.cause == LikelyCause::none) {
    for (std::size_t i = 0; i < id.per_experiment.size() && i < id.processed.size(); ++i) {
      const LsmiResult& r = id.per_experiment[i];
      const PhysicalCheck one = identification::check_physical(r.estimate, r.std_dev, id.nominal);
      if (one.clear())
        add(physical_warning(one, source, "the LSMI estimate of " + id.processed[i].name));
    }
  }
  return combined;
}

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

// The refinement from the combined LSMI estimate, the held-out free runs, and the check that the
// result is physical. Nothing (with a warning) when a recording has no OeExperiment of its own.
std::optional<OutputError> run_output_error(const OutputErrorSettings& settings,
                                            const identification::IdentifyOptions& identify_options,
                                            const Batch& batch, Run& run, Progress* progress) {
  const auto warn = [&](const std::string& text) {
    // In the plain list a warning names its stage in its text (the refinement's own warnings
    // already do); in the staged list the stage says it.
    const std::string prefix = "output error: ";
    const bool prefixed = text.rfind(prefix, 0) == 0;
    run.identification.warnings.push_back(prefixed ? text : prefix + text);
    run.warnings.push_back(
        {Warning::Stage::output_error, prefixed ? text.substr(prefix.size()) : text});
  };
  std::vector<const Recording*> fitted;
  for (const Recording& r : batch.fit) fitted.push_back(&r);
  const bool logs = batch.kind == InputKind::session_logs;
  const auto usable = [&](const Recording& r) { return !logs || r.oe.has_value(); };
  if (!std::all_of(fitted.begin(), fitted.end(), [&](const Recording* r) { return usable(*r); })) {
    warn(
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
    warn(
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
    warn(std::string("skipped: ") + e.what());
    return std::nullopt;
  }
  const std::size_t best = better_fit(fits);
  out.result = fits[best];
  if (!id.lsmi_ran()) {
    warn("started from the CAD values, since LSMI did not run");
  } else if (starts.size() > 1) {
    std::ostringstream said;
    said << "LSMI is not physical (" << identification::cause_name(run.physical.cause)
         << "), so the refinement also started from " << starts[1].name << "; kept the fit from "
         << starts[best].name << " (residual sigma";
    for (std::size_t i = 0; i < fits.size(); ++i) {
      said << (i == 0 ? " " : ", ") << short_sigma(fits[i]) << " from " << starts[i].name;
    }
    said << ")";
    warn(said.str());
  }
  for (const auto& e : experiments) {
    for (const auto& w : e.warnings) warn(w);
  }
  for (const auto& w : out.result.warnings) warn(w);
  if (!out.result.converged) warn("did not converge: " + out.result.message);

  // The parametrisation keeps the inertias and mug positive and M positive definite, but lets mu3
  // take either sign and a parameter reach its bound: a sign-flipped pendulum fits exactly with
  // mu3 < 0. So the refined estimate is checked like LSMI's, and a violation names its cause.
  out.physical = identification::check_physical(out.result.estimate, out.result.std_dev);
  if (!out.physical.consistent()) {
    warn(identification::physical_warning(
        out.physical,
        logs ? identification::RecordingSource::session_log : identification::RecordingSource::csv,
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
      warn(identification::diagnosis_text(*out.diagnosis,
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
      warn(std::string("no held-out free run: ") + e.what());
    }
  } else if (batch.held_out) {
    warn("no held-out free run: the held-out log's recording has no output-error experiment");
  }
  return out;
}

}  // namespace

Recording log_recording(const session_log::SessionLog& log, Role role,
                        const config::RigConfig& rig) {
  return Recording{identification::experiment_from_log(log),
                   summarize_session(log, role == Role::fit ? "fit" : "held out"),
                   identification::oe_experiment_from_log(log, rig)};
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

identification::DataErrorBounds data_error_bounds(const config::SiviaConfig& cfg) {
  const auto bound = [](const std::array<double, 2>& b) {
    return identification::ChannelErrorBound{b[0], b[1]};
  };
  identification::DataErrorBounds bounds;
  bounds.q2 = bound(cfg.q2_bound);
  bounds.dq1 = bound(cfg.dq1_bound);
  bounds.dq2 = bound(cfg.dq2_bound);
  bounds.ddq1 = bound(cfg.ddq1_bound);
  bounds.ddq2 = bound(cfg.ddq2_bound);
  bounds.tau = bound(cfg.tau_bound);
  return bounds;
}

interval::Box sivia_prior(const config::SiviaConfig& sivia, const model::Parameters<double>& lsmi) {
  interval::Box prior = identification::paper_prior(lsmi, sivia.mu_uncertainty_pct, 1.0);
  prior[5] = interval::Interval(sivia.fv1_prior[0], sivia.fv1_prior[1]);
  prior[6] = interval::Interval(sivia.fv2_prior[0], sivia.fv2_prior[1]);
  return prior;
}

bool has_data_error_bounds(const config::SiviaConfig& cfg) {
  for (const auto* b : {&cfg.q2_bound, &cfg.dq1_bound, &cfg.dq2_bound, &cfg.ddq1_bound,
                        &cfg.ddq2_bound, &cfg.tau_bound}) {
    if ((*b)[0] > 0 || (*b)[1] > 0) return true;
  }
  return false;
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

// The windowed set inversion over the converged refinement's estimate +- k sd (pipeline.hpp).
std::optional<WindowedGuaranteed> run_windowed(const WindowedSettings& settings, const Batch& batch,
                                               Run& run, Progress* progress) {
  const auto warn = [&](const std::string& text) {
    run.warnings.push_back({Warning::Stage::guaranteed, "guaranteed: " + text});
  };
  if (!run.output_error || !run.output_error->result.converged) {
    warn(
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
    warn(
        "skipped: a CSV recording's bounds (encoders, zero, lag, supply) are its import spec's "
        "[guaranteed] table, and the spec has none");
    return std::nullopt;
  }
  const identification::RecordingBounds bounds =
      logs ? identification::session_log_bounds(batch.rig) : *batch.recording_bounds;
  if (supply.empty() && !bounds.supply) {
    warn("skipped: the recordings carry no supply readings (the drive's gain needs them)");
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
    warn(std::string("skipped: ") + e.what());
    return std::nullopt;
  }
  if (progress != nullptr) progress->windows_done();
  const identification::WindowedSet& r = out.result;
  if (r.verdict == identification::WindowedSetVerdict::empty) {
    warn("empty set: " + r.finding);
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
      warn("nothing concluded: " + r.finding);
    }
    interval::Box hull(model::kParameterCount);
    for (std::size_t k = 0; k < model::kParameterCount; ++k) hull[k] = r.set[k];
    run.windowed_excludes_output_error =
        estimates_outside(hull, out.estimate_scaled, out.std_dev_scaled);
  }
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
  std::vector<identification::RawExperiment> experiments;
  for (const Recording& r : batch.fit) {
    experiments.push_back(r.experiment);
    if (r.session) out.sessions.push_back(*r.session);
  }
  std::optional<identification::RawExperiment> held_out;
  if (batch.held_out) {
    held_out = batch.held_out->experiment;
    if (batch.held_out->session) out.sessions.push_back(*batch.held_out->session);
  }
  // The refinement needs no derivatives: with the CAD values to start from, a recording too short
  // for LSMI's filters is fitted by it alone.
  identification::IdentifyOptions identify = settings.identify;
  identify.lsmi_optional = settings.output_error.run && batch.nominal.has_value();
  out.identification = identification::identify(experiments, held_out, identify, batch.rig.motor,
                                                batch.voltage_motor);
  if (batch.nominal) out.identification.nominal = *batch.nominal;
  if (batch.truth) out.identification.truth = *batch.truth;
  for (const auto& path : batch.files) {
    const std::filesystem::path listed =
        batch.files_listed_in.empty() ? path : batch.files_listed_in / path.filename();
    out.inputs.push_back({listed.string(), identification::sha256_file(path.string())});
  }
  out.warnings = identification_warnings(out.identification);
  out.physical = check_physical(out.identification, batch.kind, out.warnings);
  if (progress != nullptr) progress->lsmi_done(out.identification);
  if (settings.output_error.run) {
    out.output_error =
        run_output_error(settings.output_error, settings.identify, batch, out, progress);
  }
  if (!out.identification.lsmi_ran() && !out.output_error) {
    std::string why;
    for (const Warning& w : out.warnings) {
      if (w.stage == Warning::Stage::output_error) why = w.text;
    }
    throw std::invalid_argument("nothing identified: LSMI did not run (" +
                                out.identification.lsmi_skipped +
                                "), and the output-error refinement: " + why);
  }
  if (progress != nullptr) {
    progress->fit_done(out.identification, out.output_error ? &out.output_error->result : nullptr);
  }

  if (settings.sivia.run && !out.identification.lsmi_ran()) {
    out.warnings.push_back(
        {Warning::Stage::sivia,
         "SIVIA skipped: it starts from LSMI's estimate and bounds the derivatives LSMI's filters "
         "form, and LSMI did not run"});
  } else if (settings.sivia.run) {
    out.sivia = run_guaranteed(settings.sivia, out.identification, settings.identify, progress);
    const identification::GuaranteedResult& r = out.sivia->result;
    if (r.empty) out.warnings.push_back({Warning::Stage::sivia, "empty set: " + r.finding});
    if (r.paving.truncated) out.warnings.push_back({Warning::Stage::sivia, "paving truncated"});
    if (!r.empty && out.output_error && out.output_error->result.converged) {
      out.sivia_excludes_output_error =
          estimates_outside(r.paving.outer_hull(), out.output_error->result.estimate,
                            out.output_error->result.std_dev);
    }
  }
  if (settings.windowed.run) out.windowed = run_windowed(settings.windowed, batch, out, progress);
  if (settings.simulation.run) {
    out.simulation = run_simulation(settings.simulation, out, batch, progress);
    if (out.sivia && out.sivia->result.empty) {
      out.warnings.push_back({Warning::Stage::simulation, "SIVIA's set is empty: no SIVIA tubes"});
    }
  }
  return out;
}

}  // namespace furuta::pipeline
