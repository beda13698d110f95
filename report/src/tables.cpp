// Table I, the SIVIA summary and Table III as text.
#include "furuta/report/tables.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "format.hpp"

namespace furuta::report {

std::string scenario_label(const validated::Scenario& s) {
  if (s.number >= 1 && s.number <= 26) {
    return std::string("(") + static_cast<char>('a' + s.number - 1) + ")";
  }
  return "#" + std::to_string(s.number);
}

std::string scenario_description(const validated::Scenario& s) {
  return "x0 = [0, 0, " + short_number(std::round(s.q2_initial_rad * kDegPerRad * 1e6) / 1e6) +
         " deg, 0], u = " + short_number(s.torque_nm) + " N m";
}

std::string format_table_one(const identification::Identification& id,
                             const identification::OutputErrorResult* refined) {
  std::ostringstream out;
  const int w = 26;
  std::vector<std::string> names;
  for (const identification::JointSeries& s : id.processed) names.push_back(s.name);
  const ColumnHeads heads = column_heads(names, w - 2);
  const bool lsmi = id.lsmi_ran();
  if (heads.legend && lsmi) {
    for (std::size_t i = 0; i < names.size(); ++i) {
      out << heads.heads[i] << ": " << names[i] << "\n";
    }
  }
  out << std::left << std::setw(6) << "p" << std::setw(13) << "unit";
  if (lsmi) {
    for (const std::string& head : heads.heads) out << std::setw(w) << head;
    out << std::setw(w) << "all experiments";
  }
  // A refinement that did not converge is no estimate: its column says so instead of numbers.
  const bool converged = refined != nullptr && refined->converged;
  if (refined != nullptr) out << std::setw(w) << (converged ? "output error" : "output error:");
  if (id.nominal) out << std::setw(13) << "CAD";
  if (id.truth) out << std::setw(13) << "truth";
  out << "\n";
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    out << std::left << std::setw(6) << model::kParameterNames[k] << std::setw(13)
        << model::kParameterUnits[k];
    auto cell = [&](const identification::LsmiResult& r) {
      return sci(r.estimate[k], 4) + " +-" + sci(r.std_dev[k], 1);
    };
    if (lsmi) {
      for (const identification::LsmiResult& r : id.per_experiment) out << std::setw(w) << cell(r);
      out << std::setw(w) << cell(id.combined);
    }
    if (refined != nullptr) {
      out << std::setw(w)
          << (converged ? sci(refined->estimate[k], 4) + " +-" + sci(refined->std_dev[k], 1)
                        : std::string(k == 0 ? "NOT converged" : "-"));
    }
    if (id.nominal)
      out << std::setw(13) << ((*id.nominal)[k] != 0 ? sci((*id.nominal)[k], 4) : "-");
    if (id.truth) out << std::setw(13) << sci((*id.truth)[k], 4);
    out << "\n";
  }
  if (lsmi) {
    out << std::left << std::setw(19) << "condition number";
    for (const identification::LsmiResult& r : id.per_experiment)
      out << std::setw(w) << sci(r.condition_number, 2);
    out << std::setw(w) << sci(id.combined.condition_number, 2) << "\n";
    out << std::left << std::setw(19) << "residual sigma N m";
    for (const identification::LsmiResult& r : id.per_experiment)
      out << std::setw(w) << sci(r.sigma, 2);
    out << std::setw(w) << sci(id.combined.sigma, 2) << "\n";
    out << "input lag (torque formed from the input this much earlier): " << std::fixed
        << std::setprecision(3) << id.input_lag_s * 1e3 << " ms\n";
  }
  if (refined != nullptr) {
    out << "output error: " << refined->segments << " segments, " << refined->iterations
        << " iterations, " << (refined->converged ? "converged" : "NOT converged")
        << "; angle residual RMS q1 " << sci(refined->angle_rms_rad[0], 2) << " rad, q2 "
        << sci(refined->angle_rms_rad[1], 2) << " rad; lag " << std::fixed << std::setprecision(3)
        << refined->input_lag_s * 1e3 << " ms (its sd: local, from the Jacobian)\n"
        << time_stamps_text(*refined) << "\n";
  }
  if (id.validation) {
    out << "\nheld-out torque on " << id.validation->name << ": RMSE "
        << sci(id.validation->fit.rmse_nm, 3) << " N m = " << std::fixed << std::setprecision(2)
        << id.validation->fit.rmse_percent_of_range << " % of the torque range over "
        << id.validation->fit.samples << " samples (the paper: 6.4 % with LSMI)\n";
  }
  for (const auto& warning : id.warnings) out << "warning: " << warning << "\n";
  return out.str();
}

std::string time_stamps_text(const identification::OutputErrorResult& r) {
  using identification::TimeStamps;
  const auto name = [](TimeStamps t) {
    switch (t) {
      case TimeStamps::board_clock:
        return "the board's clock";
      case TimeStamps::mixed:
        return "the board's clock where it kept time, else the host's stamps";
      case TimeStamps::host:
        break;
    }
    return "the host's stamps";
  };
  std::ostringstream s;
  s << "times: ";
  if (r.time_stamps[0] == r.time_stamps[1]) {
    s << (r.time_stamps[0] == TimeStamps::board_clock ? "the boards' clocks"
                                                      : name(r.time_stamps[0]));
  } else {
    s << "q1 " << name(r.time_stamps[0]) << ", q2 " << name(r.time_stamps[1]);
  }
  double mean = 0, most = 0;
  int mapped = 0;
  for (int j = 0; j < 2; ++j) {
    if (r.time_stamps[j] == TimeStamps::host) continue;
    mean += r.host_delay_mean_s[j];
    most = std::max(most, r.host_delay_max_s[j]);
    ++mapped;
  }
  if (mapped > 0) {
    s << std::fixed << std::setprecision(2) << " (the host's stamps were on average "
      << mean / mapped * 1e3 << " ms, at most " << most * 1e3 << " ms later)";
  }
  return s.str();
}

std::string tube_span_text(const std::vector<validated::ScenarioResult>& results,
                           const std::string& set) {
  const validated::ScenarioResult* least = nullptr;
  double least_share = kTestedShareOfSpan;
  for (const validated::ScenarioResult& r : results) {
    if (r.parameters.name != set || !(r.scenario.duration_s > 0)) continue;
    const double share = r.t_reached_s / r.scenario.duration_s;
    if (share < least_share) {
      least_share = share;
      least = &r;
    }
  }
  if (least == nullptr) return "";
  return " up to " + short_number(least->t_reached_s, 3) + " s of " +
         short_number(least->scenario.duration_s, 3) + " s (where its tubes end)";
}

std::string sivia_summary_text(const identification::GuaranteedResult& r,
                               const std::optional<model::Parameters<double>>& truth,
                               const std::string& tested_span) {
  std::ostringstream s;
  s << "\nSIVIA (" << r.samples << " samples, q = " << r.q << "): " << r.paving.inner.size()
    << " inner, " << r.paving.boundary.size() << " boundary, " << r.paving.outer_count
    << " outer boxes; " << r.paving.boxes_tested << " tested in "
    << short_number(r.paving.seconds, 3) << " s" << (r.paving.truncated ? " (truncated)" : "")
    << "\n  (" << kSiviaAssumedBoundsNote << ")\n";
  if (r.empty) {
    s << r.finding << "\n";
    return s.str();
  }
  const interval::Box hull = r.paving.outer_hull();
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    if (!r.unknown[k]) continue;
    s << "  " << model::kParameterNames[k] << " in " << interval_text(hull[k].lo(), hull[k].hi())
      << " " << model::kParameterUnits[k];
    if (truth) {
      s << (hull[k].contains((*truth)[k]) ? "  (contains the truth" + tested_span + ")"
                                          : std::string("  (misses the truth)"));
    }
    s << "\n";
  }
  if (!r.inconsistent_samples.empty()) {
    s << "  " << r.inconsistent_samples.size() << " samples inconsistent (tolerated by q)\n";
  }
  return s.str();
}

std::string excluded_estimate_text(const pipeline::EstimateOutsideSet& e) {
  std::ostringstream s;
  s << "the set excludes the output-error estimate of " << model::kParameterNames[e.parameter]
    << ": " << short_number(e.estimate, 4) << " lies "
    << (std::isinf(e.sd_away) ? std::string("(its sd is 0)") : short_number(e.sd_away, 3) + " sd")
    << " " << (e.estimate < e.set.lo() ? "below" : "above") << " "
    << interval_text(e.set.lo(), e.set.hi())
    << " (the set rests on [sivia]'s assumed bounds, or the model does not fit)";
  return s.str();
}

namespace {

using identification::kScaledParameterNames;

}  // namespace

std::string tested_span_text(const identification::WindowedSet& set) {
  std::optional<std::size_t> least;
  double least_share = kTestedShareOfSpan;
  for (std::size_t r = 0; r < set.spans.size(); ++r) {
    const identification::WindowedSet::Span& s = set.spans[r];
    const double span = s.planned_end_s - s.from_s;
    if (!(span > 0)) continue;
    const double share = (s.reached_s - s.from_s) / span;
    if (share < least_share) {
      least_share = share;
      least = r;
    }
  }
  if (!least) return "";
  const identification::WindowedSet::Span& s = set.spans[*least];
  return " up to " + short_number(s.reached_s - s.from_s, 3) + " s of " +
         short_number(s.planned_end_s - s.from_s, 3) + " s" +
         (set.spans.size() > 1 ? " of recording " + std::to_string(*least) : "");
}

std::string windowed_summary_text(const pipeline::WindowedGuaranteed& w) {
  const identification::WindowedSet& r = w.result;
  std::ostringstream s;
  std::size_t contracted = 0;
  for (const identification::WindowRecord& record : r.windows) {
    contracted += record.verdict == identification::WindowVerdict::contracted;
  }
  s << "\nguaranteed set (windowed set inversion, " << r.windows.size() << " windows, "
    << contracted << " carried through; " << short_number(r.seconds, 3) << " s):\n"
    << "  searched: the output-error estimate +- " << short_number(w.search_sd, 3)
    << " sd; parameters outside the search box are neither kept nor excluded\n";
  if (r.verdict == identification::WindowedSetVerdict::empty) {
    s << "  EMPTY: " << readable_numbers(r.finding) << "\n";
    return s.str();
  }
  if (r.verdict == identification::WindowedSetVerdict::unresolved) {
    s << "  nothing concluded: " << readable_numbers(r.finding) << "\n";
    return s.str();
  }
  s << "  scaled (per unit of the drive's gain g; b = (fv1 + k_w) / g), half-widths against the "
       "estimate:\n";
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const double centre = w.estimate_scaled[k];
    s << "  " << kScaledParameterNames[k] << " in " << interval_text(r.set[k].lo(), r.set[k].hi())
      << "  " << half_width_percent(r.set[k].rad(), centre) << " (searched "
      << half_width_percent(r.search[k].rad(), centre) << ")";
    if (w.truth_scaled) {
      s << (r.set[k].contains((*w.truth_scaled)[k]) ? "  contains the truth" + tested_span_text(r)
                                                    : std::string("  misses the truth"));
    }
    s << "\n";
  }
  s << "  rig scale (times the drive's interval from [motor] and [guaranteed] "
       "motor_tolerance_pct):\n";
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const interval::Interval& x = w.rig_set[k];
    s << "  " << model::kParameterNames[k] << " in " << interval_text(x.lo(), x.hi()) << " "
      << model::kParameterUnits[k] << "  (" << short_number(100.0 * w.drive_share[k], 3)
      << " % of the width is the drive's)\n";
  }
  s << "  lag in [" << short_number(r.lag_s.lo() * 1e3, 4) << ", "
    << short_number(r.lag_s.hi() * 1e3, 4) << "] ms, the pendulum's zero in ["
    << short_number(r.pendulum_zero_rad.lo(), 3) << ", "
    << short_number(r.pendulum_zero_rad.hi(), 3) << "] rad\n";
  for (const identification::WindowRecord& record : r.windows) {
    if (record.verdict == identification::WindowVerdict::contracted) continue;
    s << "  window " << record.index << " of recording " << record.recording << " ("
      << short_number(record.t0_s, 4) << "-" << short_number(record.t1_s, 4)
      << " s): " << window_verdict_name(record.verdict) << " at "
      << short_number(record.reached_s, 4) << " s: " << readable_numbers(record.reason) << "\n";
  }
  if (!r.finding.empty()) s << "  " << readable_numbers(r.finding) << "\n";
  return s.str();
}

const char* window_verdict_name(identification::WindowVerdict v) {
  switch (v) {
    case identification::WindowVerdict::inconsistent:
      return "inconsistent";
    case identification::WindowVerdict::contracted:
      return "carried";
    case identification::WindowVerdict::flow_failed:
      return "flow_stopped";
  }
  return "flow_stopped";
}

std::string windowed_excluded_text(const pipeline::EstimateOutsideSet& e) {
  std::ostringstream s;
  s << "the guaranteed set excludes the output-error estimate of "
    << kScaledParameterNames[e.parameter] << ": " << short_number(e.estimate, 4) << " lies "
    << (std::isinf(e.sd_away) ? std::string("(its sd is 0)") : short_number(e.sd_away, 3) + " sd")
    << " " << (e.estimate < e.set.lo() ? "below" : "above") << " "
    << interval_text(e.set.lo(), e.set.hi())
    << " (a physical input's bound is broken, or the model does not fit)";
  return s.str();
}

std::vector<std::string> per_gain_set_notes(const std::vector<validated::ScenarioResult>& results) {
  std::vector<std::string> notes;
  for (const validated::ScenarioResult& r : results) {
    const interval::Interval& scale = r.parameters.torque_scale;
    if (scale == interval::Interval(1.0)) continue;
    std::string note = r.parameters.name +
                       ": every rig the set allows, as its parameters per unit of the drive's "
                       "gain g under the torque times 1/g in " +
                       interval_text(scale.lo(), scale.hi()) +
                       " 1/(N m), through the Taylor-model flow; no assumed bound";
    if (std::find(notes.begin(), notes.end(), note) == notes.end()) notes.push_back(note);
  }
  return notes;
}

std::string tube_end_text(const validated::ScenarioResult& r) {
  if (!r.width_stop) return readable_numbers(r.reason);
  const validated::WidthStop& w = *r.width_stop;
  // The scenario tubes' components: [q1, dq1, q2, dq2], then parameters carried as state (each in
  // its own unit, which max_width is compared in unconverted).
  static constexpr const char* kNames[] = {"q1", "dq1", "q2", "dq2"};
  static constexpr const char* kUnits[] = {"deg", "deg/s", "deg", "deg/s"};
  std::string name = "component " + std::to_string(w.component);
  std::string unit;
  double factor = 1.0;
  if (w.component < 4) {
    name = kNames[w.component];
    unit = std::string(" ") + kUnits[w.component];
    factor = kDegPerRad;
  }
  return name + "'s enclosure " + short_number(w.width * factor, 4) + unit +
         " wide > the limit of " + short_number(w.max_width * factor, 4) + unit +
         " at t = " + short_number(w.t, 4) + " s";
}

std::string coverage_note() {
  return "q2 step >= " + short_number(100 * kCoverageOkRate) + " %";
}

std::string tube_status_text(const validated::ScenarioResult& r) {
  const bool whole = r.status == validated::IntegrationResult::Status::ok &&
                     r.t_reached_s + 1e-9 >= r.scenario.duration_s;
  if (whole) return "reached the end";
  std::string text = std::string("ended (") + validated::to_string(r.status) + ")";
  const std::string why = tube_end_text(r);
  return why.empty() ? text : text + ": " + why;
}

std::string coverage_verdict(const validated::Coverage& q2_step) {
  if (q2_step.measurements == 0) return "-";
  return q2_step.rate() >= kCoverageOkRate ? "ok" : "low";
}

std::string format_table_three(const std::vector<validated::ScenarioResult>& results) {
  std::ostringstream out;
  out << "Table III: coverage of the measurements by the tubes, over all samples (and over the "
         "samples reached)\n"
         "  step: the paper's test (sample time in a step, value in the step's box); interp.: "
         "the enclosure at the sample time\n"
         "  paper, q2 step: 46/61/38/25 % with IA (SIVIA) parameters, 41/34/20/21 % with LSMI\n";
  for (const std::string& note : per_gain_set_notes(results)) out << "  " << note << "\n";
  out << std::left << std::setw(5) << "scen" << std::setw(12) << "parameters" << std::right
      << std::setw(14) << "reached [s]" << std::setw(7) << "steps" << std::setw(20) << "q2 step %"
      << std::setw(20) << "q2 interp. %" << std::setw(9) << "q1 step" << std::setw(9) << "q1 int."
      << std::setw(13) << "q2 width"
      << "  " << std::left << std::setw(10) << "coverage"
      << "tube\n";
  out << std::left << std::setw(5) << "" << std::setw(12) << "" << std::right << std::setw(14) << ""
      << std::setw(7) << "" << std::setw(20) << "all (reached)" << std::setw(20) << "all (reached)"
      << std::setw(9) << "%" << std::setw(9) << "%" << std::setw(13) << "mean [deg]"
      << "  " << std::left << std::setw(10) << coverage_note() << "\n";
  for (const validated::ScenarioResult& r : results) {
    const auto both = [](const validated::Coverage& c) {
      return fixed(100 * c.rate(), 1) + " (" + fixed(100 * c.rate_in_time(), 1) + ")";
    };
    out << std::left << std::setw(5) << scenario_label(r.scenario) << std::setw(12)
        << r.parameters.name << std::right << std::setw(14)
        << (fixed(r.t_reached_s, 3) + " / " + fixed(r.scenario.duration_s, 1)) << std::setw(7)
        << r.steps << std::setw(20) << both(r.q2_step) << std::setw(20) << both(r.q2_interpolated)
        << std::setw(9) << fixed(100 * r.q1_step.rate(), 1) << std::setw(9)
        << fixed(100 * r.q1_interpolated.rate(), 1) << std::setw(13)
        << fixed(r.q2_mean_width_rad * kDegPerRad, 3) << "  " << std::left << std::setw(10)
        << coverage_verdict(r.q2_step) << tube_status_text(r) << "\n";
  }
  return out.str();
}

std::string simulation_summary_text(const std::string& measurement_source, bool sivia_set_empty,
                                    const std::vector<validated::ScenarioResult>& results) {
  return "\nValidation by guaranteed simulation, measurements from " + measurement_source + ":\n" +
         (sivia_set_empty ? "(SIVIA's set is empty: no SIVIA tubes)\n" : "") +
         format_table_three(results);
}

std::string measurement_source_text(const pipeline::MeasurementSource& source) {
  using Kind = pipeline::MeasurementSource::Kind;
  switch (source.kind) {
    case Kind::sessions_truth:
      return "the simulated sessions' truth";
    case Kind::configured_rig:
      return "the configuration's simulated rig (the sessions carry no truth)";
    case Kind::results_truth:
      return source.file + " (truth)";
    case Kind::paper_default:
      break;
  }
  return "the simulated rig's default (the paper's run 1)";
}

std::string terminal_text(const pipeline::Run& run) {
  return format_table_one(run.identification,
                          run.output_error ? &run.output_error->result : nullptr) +
         terminal_text_after_lsmi(run);
}

std::string held_out_free_run_text(const pipeline::HeldOutFreeRuns& runs) {
  std::ostringstream out;
  out << "\nheld-out free run on " << runs.name << " (angle RMSE, q1 / q2): ";
  if (runs.lsmi) {
    out << "LSMI " << sci(runs.lsmi->rmse_rad[0], 3) << " / " << sci(runs.lsmi->rmse_rad[1], 3)
        << " rad, ";
  }
  out << "output error " << sci(runs.refined.rmse_rad[0], 3) << " / "
      << sci(runs.refined.rmse_rad[1], 3) << " rad\n";
  // An error above the measured angle's own spread: worse than predicting its mean.
  const std::array<double, 2>& sd = runs.refined.measured_sd_rad;
  const auto flag = [&](const char* set, const std::array<double, 2>& rmse) {
    for (std::size_t j = 0; j < 2; ++j) {
      if (rmse[j] > sd[j]) {
        out << "warning: the " << set << " free run misses q" << j + 1 << " by more than the "
            << "measured angle's own spread (sd " << sci(sd[j], 3)
            << " rad): worse than its mean\n";
      }
    }
  };
  if (runs.lsmi) flag("LSMI", runs.lsmi->rmse_rad);
  flag("output-error", runs.refined.rmse_rad);
  return out.str();
}

identification::RecordingSource recording_source(const pipeline::Run& run) {
  return run.kind == pipeline::InputKind::csv_recordings
             ? identification::RecordingSource::csv
             : identification::RecordingSource::session_log;
}

std::string terminal_text_after_lsmi(const pipeline::Run& run) {
  std::string text;
  if (run.output_error && run.output_error->held_out) {
    text += held_out_free_run_text(*run.output_error->held_out);
  }
  // A diagnosis asked for on a fit that needed none (one that did is among Table I's warnings).
  if (run.output_error && run.output_error->diagnosis &&
      run.output_error->diagnosis->as_recorded.plausible) {
    text += identification::diagnosis_text(*run.output_error->diagnosis, recording_source(run),
                                           run.output_error->counts_per_rev) +
            "\n";
  }
  if (run.sivia) {
    text += sivia_summary_text(
        run.sivia->result, run.identification.truth,
        run.simulation ? tube_span_text(run.simulation->results, pipeline::kSiviaSetName) : "");
  } else {
    for (const pipeline::Warning& w : run.warnings) {
      if (w.stage == pipeline::Warning::Stage::sivia) text += "warning: " + w.text + "\n";
    }
  }
  for (const pipeline::EstimateOutsideSet& e : run.sivia_excludes_output_error) {
    text += "warning: " + excluded_estimate_text(e) + "\n";
  }
  if (run.windowed) {
    text += windowed_summary_text(*run.windowed);
  } else {
    for (const pipeline::Warning& w : run.warnings) {
      if (w.stage == pipeline::Warning::Stage::guaranteed) text += "warning: " + w.text + "\n";
    }
  }
  for (const pipeline::EstimateOutsideSet& e : run.windowed_excludes_output_error) {
    text += "warning: " + windowed_excluded_text(e) + "\n";
  }
  if (run.simulation) {
    text += simulation_summary_text(measurement_source_text(run.simulation->source),
                                    run.sivia && run.sivia->result.empty, run.simulation->results);
  }
  return text;
}

}  // namespace furuta::report
