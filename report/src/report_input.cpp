// The report's content from the domain results: sessions, Table I, Table II, SIVIA, warnings.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "format.hpp"
#include "furuta/common/text_format.hpp"
#include "furuta/identification/physical.hpp"
#include "furuta/report/report.hpp"
#include "furuta/report/svg.hpp"
#include "furuta/report/tables.hpp"

namespace furuta::report {

std::string escape_html(const std::string& text) {
  return text::xml_escape(text);
}

std::string torque_source(identification::InputKind input, bool csv) {
  switch (input) {
    case identification::InputKind::voltage:
      return "from the recorded voltage via the import spec's [motor] (a DC motor)";
    case identification::InputKind::torque:
      return "as recorded";
    case identification::InputKind::duty:
      break;
  }
  return csv ? "by eq. 4 from the recorded duty cycle (the configuration's motor)"
             : "by eq. 4 from the logged duty cycle";
}

ReportInput report_input(const identification::Identification& id) {
  ReportInput r;
  if (!id.raw.empty()) r.torque_source = torque_source(id.raw.front().input_kind, false);
  for (const auto& s : id.processed) r.experiment_names.push_back(s.name);
  r.per_experiment = id.per_experiment;
  r.combined = id.combined;
  r.lsmi_skipped = id.lsmi_skipped;
  r.nominal = id.nominal;
  r.truth = id.truth;
  r.input_lag_s = id.input_lag_s;
  if (id.validation) {
    r.validation = ValidationSummary{
        id.validation->name, id.validation->fit.rmse_nm, id.validation->fit.rmse_percent_of_range,
        id.validation->fit.samples, svg_torque_validation(*id.validation)};
  }
  r.warnings = pipeline::identification_warnings(id);
  return r;
}

namespace {

std::string interval_cell(const interval::Interval& x) {
  return "[" + sci(x.lo(), 5) + ", " + sci(x.hi(), 5) + "]";
}

}  // namespace

GuaranteedSummary guaranteed_summary(const pipeline::WindowedGuaranteed& w,
                                     const std::vector<pipeline::EstimateOutsideSet>& excluded) {
  const identification::WindowedSet& r = w.result;
  GuaranteedSummary g;
  g.set_svg = svg_windowed_set(w);
  std::size_t carried = 0;
  for (const identification::WindowRecord& record : r.windows) {
    carried += record.verdict == identification::WindowVerdict::contracted;
  }
  g.headline = std::to_string(r.windows.size()) + " windows (" + std::to_string(carried) +
               " carried whole) in " + short_number(r.seconds, 3) +
               " s; the search box is the output-error estimate +- " +
               short_number(w.search_sd, 3) +
               " sd: every parameter in it that explains every reading of the windows is in the "
               "set, and parameters outside it are neither kept nor excluded.";
  if (r.verdict == identification::WindowedSetVerdict::empty) {
    g.notes.push_back("The set is empty: " + readable_numbers(r.finding));
  } else if (r.verdict == identification::WindowedSetVerdict::unresolved) {
    g.notes.push_back("Nothing was concluded: " + readable_numbers(r.finding));
  }
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const double centre = w.estimate_scaled[k];
    std::string truth = "-";
    if (w.truth_scaled) {
      truth = r.set[k].contains((*w.truth_scaled)[k]) ? "inside" + tested_span_text(r) : "OUTSIDE";
    }
    g.scaled_rows.push_back({identification::kScaledParameterNames[k], interval_cell(r.search[k]),
                             interval_cell(r.set[k]), half_width_percent(r.set[k].rad(), centre),
                             truth});
  }
  if (r.verdict != identification::WindowedSetVerdict::empty) {
    for (std::size_t k = 0; k < model::kParameterCount; ++k) {
      g.rig_rows.push_back({model::kParameterNames[k], model::kParameterUnits[k],
                            interval_cell(w.rig_set[k]),
                            short_number(100.0 * w.drive_share[k], 3) + " %"});
    }
  }
  for (const identification::WindowRecord& record : r.windows) {
    const bool carried_whole = record.verdict == identification::WindowVerdict::contracted;
    g.window_rows.push_back({std::to_string(record.recording), std::to_string(record.index),
                             short_number(record.t0_s, 4) + " - " + short_number(record.t1_s, 4),
                             short_number(record.reached_s, 4), std::to_string(record.readings),
                             std::string(window_verdict_name(record.verdict)) +
                                 (carried_whole ? "" : ": " + readable_numbers(record.reason))});
  }
  g.notes.push_back("The data path's lag is in [" + short_number(r.lag_s.lo() * 1e3, 4) + ", " +
                    short_number(r.lag_s.hi() * 1e3, 4) + "] ms; the pendulum's zero in [" +
                    short_number(r.pendulum_zero_rad.lo(), 3) + ", " +
                    short_number(r.pendulum_zero_rad.hi(), 3) + "] rad.");
  for (const pipeline::EstimateOutsideSet& e : excluded) {
    g.notes.push_back("Warning: " + windowed_excluded_text(e) + ".");
  }
  return g;
}

ReportInput report_page(const pipeline::Run& run, const std::string& software_version,
                        const std::vector<std::string>& signals_svg,
                        const std::string& paving_svg) {
  const identification::Identification& id = run.identification;
  ReportInput page = report_input(id);
  page.warnings = run.warnings;  // each with the stage that made it
  page.software_version = software_version;
  const auto number = [](double v, const char* unit) {
    std::ostringstream s;
    s << v << " " << unit;
    return s.str();
  };
  if (run.output_error) {
    const identification::OutputErrorResult& r = run.output_error->result;
    OutputErrorSummary oe;
    oe.estimate = r.estimate;
    oe.std_dev = r.std_dev;
    oe.input_lag_s = r.input_lag_s;
    oe.angle_rms_rad = r.angle_rms_rad;
    oe.segments = r.segments;
    oe.iterations = r.iterations;
    oe.converged = r.converged;
    oe.time_stamps = time_stamps_text(r);
    if (run.output_error->held_out) {
      const pipeline::HeldOutFreeRuns& h = *run.output_error->held_out;
      oe.held_out_name = h.name;
      if (h.lsmi) oe.lsmi_rmse_rad = h.lsmi->rmse_rad;
      oe.refined_rmse_rad = h.refined.rmse_rad;
      oe.measured_sd_rad = h.refined.measured_sd_rad;
      oe.svg = svg_free_runs(h.name, h.lsmi ? &*h.lsmi : nullptr, h.refined);
    }
    page.output_error = std::move(oe);
  }
  const bool csv = run.kind == pipeline::InputKind::csv_recordings;
  if (!id.raw.empty()) page.torque_source = torque_source(id.raw.front().input_kind, csv);
  // Where the configuration came from, not only its name (every shipped one is "furuta").
  const std::string named = run.rig_name.empty() ? "" : " (named \"" + run.rig_name + "\")";
  std::string configuration = "none (the import spec gives the fit all it needs)";
  if (!run.config_file.empty()) {
    configuration = run.config_file.string() + named;
  } else if (!run.config_carried_by.empty()) {
    configuration = "carried by " + run.config_carried_by.filename().string() + named;
  } else if (!run.rig_name.empty() && !csv) {
    configuration = run.rig_name;
  }
  page.rig = {{"configuration", configuration},
              {"inputs", csv ? "CSV recordings" : "session logs"},
              {"torque", page.torque_source},
              {"sample period", number(id.processed.front().sample_period_s * 1e3, "ms")},
              {"low-pass cut-off", number(run.settings.identify.preprocess.cutoff_hz, "Hz")}};
  if (run.simulated_rig) page.rig.push_back({"rig", "simulated (its true parameters are known)"});
  page.sessions = run.sessions;
  for (const auto& file : run.inputs) page.inputs.push_back(file.path);
  page.signals_svg = signals_svg;
  page.signals_bands = run.data_bounds
                           ? "the bands are the data error bounds of [sivia] (SIVIA's data boxes)"
                           : "the band is the pendulum encoder's quantisation";
  // SIVIA starts from LSMI's mu's: without LSMI it has no prior.
  if (id.lsmi_ran()) {
    page.table_two = table_two(id.combined.estimate, run.settings.sivia.config,
                               run.sivia ? &run.sivia->result : nullptr);
  }
  if (run.sivia) {
    page.sivia = sivia_summary(run.sivia->result, paving_svg);
    for (const pipeline::EstimateOutsideSet& e : run.sivia_excludes_output_error) {
      page.sivia->excludes_output_error.push_back(excluded_estimate_text(e));
    }
  }
  if (run.windowed) {
    page.guaranteed = guaranteed_summary(*run.windowed, run.windowed_excludes_output_error);
  } else if (run.settings.windowed.run) {
    GuaranteedSummary skipped;
    skipped.headline = "The windowed set inversion did not run.";
    for (const pipeline::Warning& w : run.warnings) {
      if (w.stage == pipeline::Warning::Stage::guaranteed) skipped.notes.push_back(w.text);
    }
    page.guaranteed = std::move(skipped);
  }
  if (run.simulation) {
    page.simulation =
        SimulationSummary{measurement_source_text(run.simulation->source), run.simulation->results};
  }
  return page;
}

std::vector<IntervalRow> table_two(const model::Parameters<double>& lsmi,
                                   const config::SiviaConfig& sivia,
                                   const identification::GuaranteedResult* result) {
  interval::Box prior;
  if (result) {
    prior = result->paving.prior;  // what the paver was given
  } else {
    prior = pipeline::sivia_prior(sivia, lsmi);
  }
  std::optional<interval::Box> hull;
  if (result && !result->empty) hull = result->paving.outer_hull();
  std::vector<IntervalRow> rows;
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const auto i = static_cast<std::size_t>(k);
    IntervalRow row;
    row.parameter = model::kParameterNames[i];
    row.unit = model::kParameterUnits[i];
    const bool unknown = std::find(sivia.unknowns.begin(), sivia.unknowns.end(), row.parameter) !=
                         sivia.unknowns.end();
    row.lo = prior[i].lo();
    row.hi = prior[i].hi();
    if (unknown) {
      row.origin = "prior (unknown, bisected)";
    } else if (k < 5) {
      std::ostringstream s;
      s << "LSMI \u00b1 " << sivia.mu_uncertainty_pct[i] << " % (carried)";
      row.origin = s.str();
    } else {
      row.origin = "prior (carried)";
    }
    if (hull) row.outer_hull = std::array<double, 2>{(*hull)[i].lo(), (*hull)[i].hi()};
    rows.push_back(row);
  }
  return rows;
}

SiviaSummary sivia_summary(const identification::GuaranteedResult& result, std::string svg) {
  SiviaSummary s;
  s.samples = result.samples;
  s.q = result.q;
  s.inner = result.paving.inner.size();
  s.boundary = result.paving.boundary.size();
  s.outer = result.paving.outer_count;
  s.tested = result.paving.boxes_tested;
  s.seconds = result.paving.seconds;
  s.truncated = result.paving.truncated;
  s.empty = result.empty;
  s.finding = result.finding;
  s.inconsistent_samples = result.inconsistent_samples.size();
  s.svg = std::move(svg);
  return s;
}

std::string topic(Warning::Stage stage) {
  switch (stage) {
    case Warning::Stage::lsmi:
      return "LSMI";
    case Warning::Stage::physical:
      return "physical";
    case Warning::Stage::output_error:
      return "output error";
    case Warning::Stage::sivia:
      return "SIVIA";
    case Warning::Stage::guaranteed:
      return "guaranteed";
    case Warning::Stage::simulation:
      return "simulation";
    case Warning::Stage::data:
      break;
  }
  return "session";
}

std::string kind_name(Warning::Kind kind) {
  switch (kind) {
    case Warning::Kind::data:
      return "data";
    case Warning::Kind::skipped:
      return "skipped";
    case Warning::Kind::failed:
      return "failed";
    case Warning::Kind::suspect:
      return "suspect";
    case Warning::Kind::note:
      break;
  }
  return "note";
}

std::vector<Warning> derived_warnings(const ReportInput& input) {
  std::vector<Warning> out;
  for (const SessionSummary& s : input.sessions) {
    if (s.damaged_regions > 0) {
      out.push_back({Warning::Stage::data, Warning::Kind::data,
                     s.file + ": " + std::to_string(s.damaged_regions) +
                         " damaged regions of the log skipped"});
    }
    if (s.truncated_tail) {
      out.push_back(
          {Warning::Stage::data, Warning::Kind::data, s.file + ": the log's tail is truncated"});
    }
    for (const auto& f : s.fatal_faults) {
      out.push_back({Warning::Stage::data, Warning::Kind::data, s.file + ": fatal fault " + f});
    }
  }
  using Stage = Warning::Stage;
  using Kind = Warning::Kind;
  // A number that is not one (NaN, infinite) is no estimate, whatever produced it: the run failed
  // there, and the page must not show it as a result among the others.
  const auto non_finite = [](const model::Parameters<double>& estimate,
                             const model::Parameters<double>& sd) {
    std::string names;
    for (std::size_t k = 0; k < model::kParameterCount; ++k) {
      if (std::isfinite(estimate[k]) && std::isfinite(sd[k])) continue;
      names += (names.empty() ? "" : ", ") + std::string(model::kParameterNames[k]);
    }
    return names;
  };
  const auto not_a_number = [&](Stage stage, const std::string& what,
                                const model::Parameters<double>& estimate,
                                const model::Parameters<double>& sd) {
    const std::string names = non_finite(estimate, sd);
    if (names.empty()) return;
    out.push_back({stage, Kind::failed,
                   what + ": no estimate: " + names +
                       " not a finite number (NaN or infinite, with its sd): check the inputs "
                       "and settings for numbers that are not"});
  };
  if (input.lsmi_skipped.empty()) {
    for (std::size_t e = 0; e < input.per_experiment.size(); ++e) {
      const std::string name =
          e < input.experiment_names.size() ? input.experiment_names[e] : std::to_string(e + 1);
      not_a_number(Stage::lsmi, "LSMI on " + name, input.per_experiment[e].estimate,
                   input.per_experiment[e].std_dev);
    }
    not_a_number(Stage::lsmi, "LSMI on all experiments", input.combined.estimate,
                 input.combined.std_dev);
  }
  if (input.output_error) {
    not_a_number(Stage::output_error, "the output-error refinement", input.output_error->estimate,
                 input.output_error->std_dev);
  }
  // A free run whose angle error is larger than the measured angle's own spread predicts the
  // held-out session worse than its mean would: whatever its RMSE, it says nothing of the rig.
  if (input.output_error && !input.output_error->held_out_name.empty()) {
    const OutputErrorSummary& oe = *input.output_error;
    const auto worse_than_mean = [&](const std::string& set, const std::array<double, 2>& rmse) {
      for (std::size_t j = 0; j < 2; ++j) {
        if (!(rmse[j] > oe.measured_sd_rad[j])) continue;
        out.push_back({Stage::output_error, Kind::suspect,
                       "the free run of the held-out " + oe.held_out_name + " with the " + set +
                           " parameters misses q" + std::to_string(j + 1) + " by RMSE " +
                           short_number(rmse[j], 3) +
                           " rad, more than the measured angle's own "
                           "spread (sd " +
                           short_number(oe.measured_sd_rad[j], 3) +
                           " rad): it predicts the session worse than the angle's mean would"});
      }
    };
    if (oe.lsmi_rmse_rad) worse_than_mean("LSMI", *oe.lsmi_rmse_rad);
    worse_than_mean("output-error", oe.refined_rmse_rad);
  }
  // An empty or truncated paving is the run's own warning (pipeline::run).
  if (input.sivia) {
    const SiviaSummary& s = *input.sivia;
    for (const std::string& excluded : s.excludes_output_error) {
      out.push_back({Stage::sivia, Kind::suspect, excluded});
    }
    if (s.inconsistent_samples > 0) {
      out.push_back({Stage::sivia, Kind::note,
                     std::to_string(s.inconsistent_samples) +
                         " samples inconsistent with the whole set (tolerated by q = " +
                         std::to_string(s.q) + ")"});
    }
  }
  if (input.simulation) {
    for (const auto& r : input.simulation->results) {
      if (coverage_verdict(r.q2_step) == "low") {
        out.push_back({Stage::simulation, Kind::suspect,
                       "scenario " + scenario_label(r.scenario) + ", " + r.parameters.name +
                           ": the tube holds " + percent(r.q2_step.rate()) +
                           " of the measured q2 samples (step test), below " +
                           percent(kCoverageOkRate) +
                           ", the paper's lowest: check the model, the parameters or the "
                           "measurement"});
      }
      if (r.t_reached_s + 1e-9 >= r.scenario.duration_s &&
          r.status == validated::IntegrationResult::Status::ok) {
        continue;
      }
      out.push_back({Stage::simulation, Kind::failed,
                     "scenario " + scenario_label(r.scenario) + ", " + r.parameters.name +
                         ": the tube ended early, at " + dash_fixed(r.t_reached_s, 3) + " s of " +
                         dash_fixed(r.scenario.duration_s, 1) + " s (" +
                         validated::to_string(r.status) +
                         (r.reason.empty() ? "" : ": " + tube_end_text(r)) + ")"});
    }
  }
  return out;
}

}  // namespace furuta::report
