// report.html: render_html, one function per section of the page.
#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "format.hpp"
#include "furuta/report/report.hpp"
#include "furuta/report/svg.hpp"
#include "furuta/report/tables.hpp"
#include "html_page.hpp"

namespace furuta::report {

namespace {

// "1.0845e-03 ± 2.0e-05", which a narrow column breaks before the "±" only.
std::string plus_minus(const std::string& value, const std::string& sd) {
  return value + " \u00b1\u00a0" + sd;
}

std::string table_three_cell(const validated::Coverage& c) {
  return dash_fixed(100 * c.rate(), 1) + " (" + dash_fixed(100 * c.rate_in_time(), 1) + ")";
}

// "seed1.lcmlog" -> "fig-signals-1": ids stay ASCII whatever the names are.
std::string figure_id(const std::string& prefix, std::size_t n) {
  return prefix + "-" + std::to_string(n);
}

// The document's head, its title and what it is.
void page_head(Html& h, const ReportInput& in) {
  h.document_start(
      in.title, in.software_version +
                    ": identification of a rotary inverted (Furuta) pendulum, least squares (LSMI) "
                    "and guaranteed (SIVIA, validated simulation). The numbers are also in "
                    "results.json.");
  h.raw("</header>\n");
}

// The balance sessions among the logs, as their sections show them (file names).
std::vector<BalanceLogEntry> balance_logs(const ReportInput& in) {
  std::vector<BalanceLogEntry> out;
  for (const SessionSummary& s : in.sessions) {
    if (s.balance) out.push_back({s.file, s, {}});
  }
  return out;
}

// The table of contents: one link per section.
void contents(Html& h, bool balance) {
  h.raw("<nav>\n<ol>\n");
  std::vector<std::pair<std::string, std::string>> contents = {
      {"summary", "Rig and sessions"},
      {"warnings", "Warnings"},
      {"lsmi", "Least squares (Table I)"},
      {"data", "Data and uncertainty bands (Fig. 2/3)"},
      {"validation", "Held-out torque (Fig. 5)"},
      {"sivia", "Guaranteed identification (Table II, Fig. 4)"},
      {"guaranteed", "Guaranteed set from the angles"},
      {"simulation", "Validated simulation (Table III, Fig. 6)"}};
  if (balance) contents.insert(contents.begin() + 1, {"balance", "Balance sessions"});
  for (const auto& [id, name] : contents) {
    h.raw("<li><a href=\"#" + id + "\">");
    h.text(name);
    h.raw("</a></li>\n");
  }
  h.raw("</ol>\n</nav>\n");
}

// How a session ended: its end record's reason in words ("duration reached", "arm angle limit"),
// or that the log has none.
std::string ended(const SessionSummary& s) {
  if (!s.complete) return "cut short (no end record)";
  std::string reason = s.end_reason.empty() ? std::string("yes") : s.end_reason;
  std::replace(reason.begin(), reason.end(), '_', ' ');
  return reason;
}

// The sessions, from their logs.
void sessions_table(Html& h, const std::vector<SessionSummary>& sessions) {
  std::vector<std::vector<std::string>> rows;
  for (const SessionSummary& s : sessions) {
    rows.push_back(
        {s.file, s.role, s.label, s.profile, dash_fixed(s.amplitude_duty, 2),
         dash_fixed(s.duration_s, 1), dash_fixed(s.period_s * 1e3, 1), std::to_string(s.seed),
         std::to_string(s.samples), std::to_string(s.missing_samples),
         std::to_string(s.motor_lost_reports) + " / " + std::to_string(s.encoder_lost_reports),
         std::to_string(s.overruns), std::to_string(s.faults), ended(s)});
  }
  h.table("sessions", "Sessions (from their logs)",
          {"log", "role", "label", "profile", "amplitude [duty]", "duration [s]", "period [ms]",
           "seed", "samples", "missing samples", "lost reports motor / encoder", "missed cycles",
           "faults", "ended"},
          rows);
}

// The rig, the settings, the sessions and the input files.
void section_rig_and_sessions(Html& h, const ReportInput& in) {
  h.raw("<section id=\"summary\">\n");
  h.element("h2", "Rig and sessions");
  std::vector<std::vector<std::string>> rig_rows;
  for (const auto& [key, value] : in.rig) rig_rows.push_back({key, value});
  rig_rows.push_back({"input lag", dash_fixed(in.input_lag_s * 1e3, 3) + " ms"});
  h.table("rig", "The rig and the identification settings", {"", "value"}, rig_rows);
  if (!in.sessions.empty()) sessions_table(h, in.sessions);
  if (!in.inputs.empty()) {
    h.raw("<p>Inputs: ");
    for (std::size_t i = 0; i < in.inputs.size(); ++i) {
      if (i) h.raw(", ");
      h.element("code", in.inputs[i]);
    }
    h.raw("</p>\n");
  }
  h.raw("</section>\n");
}

// What each balance session among the logs did (the identification fits its applied duty like
// any other input); no section when there is none.
void section_balance(Html& h, const std::vector<BalanceLogEntry>& logs) {
  if (logs.empty()) return;
  h.raw("<section id=\"balance\">\n");
  h.element("h2", "Balance sessions");
  h.paragraph(
      "The sessions that ran the balance controller: when it caught the pendulum, how well it "
      "held it, the duty and arm travel it took and the controller file. Their input was "
      "computed from the measured angles (closed loop), which biases least squares; the "
      "output-error fit simulates the model with the applied duty.");
  balance_log_sections(h, logs, "h3");
  h.raw("</section>\n");
}

// The warnings given and derived, by topic; "None" when none.
void section_warnings(Html& h, const ReportInput& in) {
  h.raw("<section id=\"warnings\">\n");
  h.element("h2", "Warnings");
  std::vector<Warning> warnings = in.warnings;
  for (Warning& w : derived_warnings(in)) warnings.push_back(std::move(w));
  if (warnings.empty()) {
    h.paragraph(
        "None: the regressor is well conditioned, every parameter is excited, the sessions lost "
        "nothing, and what ran of SIVIA and the simulation finished.",
        "none");
  } else {
    h.raw("<ul class=\"warnings\">\n");
    for (const Warning& w : warnings) {
      h.raw("<li class=\"" + kind_name(w.kind) + "\">");
      h.element("span", topic(w.stage), "class=\"topic\"");
      h.text(" " + w.text);
      h.raw("</li>\n");
    }
    h.raw("</ul>\n");
  }
  h.raw("</section>\n");
}

// Table I: one column per experiment, all together, CAD and truth; each estimate +- its sd.
// Long session names would widen every column: they head it as E1, E2, ... and are listed below.
void table_one(Html& h, const ReportInput& in) {
  const ColumnHeads heads = column_heads(in.experiment_names, 16);
  std::vector<std::string> header = {"parameter", "unit"};
  const bool lsmi = in.lsmi_skipped.empty();
  if (lsmi) {
    for (const auto& head : heads.heads) header.push_back(head);
    header.push_back("all experiments");
  }
  // A refinement that did not converge is no estimate: its column says so instead of numbers.
  const bool refined = in.output_error && in.output_error->converged;
  if (in.output_error) header.push_back(refined ? "output error" : "output error: not converged");
  if (in.nominal) header.push_back("CAD");
  if (in.truth) header.push_back("truth");
  std::vector<std::vector<std::string>> rows;
  for (std::size_t i = 0; i < model::kParameterCount; ++i) {
    std::vector<std::string> row = {std::string(model::kParameterNames[i]),
                                    pretty_unit(std::string(model::kParameterUnits[i]))};
    const auto cell = [i](const identification::LsmiResult& r) {
      return plus_minus(dash_sci(r.estimate[i], 4), dash_sci(r.std_dev[i], 1));
    };
    if (lsmi) {
      for (const auto& r : in.per_experiment) row.push_back(cell(r));
      row.push_back(cell(in.combined));
    }
    if (in.output_error) {
      row.push_back(refined ? plus_minus(dash_sci(in.output_error->estimate[i], 4),
                                         dash_sci(in.output_error->std_dev[i], 1))
                            : "-");
    }
    if (in.nominal) row.push_back((*in.nominal)[i] != 0 ? dash_sci((*in.nominal)[i], 4) : "-");
    if (in.truth) row.push_back(dash_sci((*in.truth)[i], 4));
    rows.push_back(std::move(row));
  }
  h.table("table-1",
          !lsmi     ? "Table I: output-error estimates \u00b1 one standard deviation"
          : refined ? "Table I: LSMI and output-error estimates \u00b1 one standard deviation"
                    : "Table I: LSMI estimates \u00b1 one standard deviation",
          header, rows);
  if (heads.legend && lsmi) {
    h.raw("<ul class=\"keys\" id=\"table-1-keys\">\n");
    for (std::size_t i = 0; i < in.experiment_names.size(); ++i) {
      h.raw("<li>");
      h.element("strong", heads.heads[i]);
      h.text(": " + in.experiment_names[i]);
      h.raw("</li>\n");
    }
    h.raw("</ul>\n");
  }
}

// One row of the LSMI diagnostics.
std::vector<std::string> diagnostic(const std::string& name, const identification::LsmiResult& r) {
  std::string poorly_excited;
  for (const auto& p : r.poorly_excited) {
    poorly_excited += (poorly_excited.empty() ? "" : ", ") + p;
  }
  return {name,
          std::to_string(r.rows / 2),
          dash_sci(r.condition_number, 2),
          std::to_string(r.rank),
          dash_sci(r.sigma, 2),
          poorly_excited.empty() ? "-" : poorly_excited};
}

// Table I and how well the data excite the parameters.
void section_lsmi(Html& h, const ReportInput& in) {
  h.raw("<section id=\"lsmi\">\n");
  h.element("h2", "Least squares (Table I)");
  h.paragraph(
      "The model's seven parameters by least squares (LSMI) on each experiment and on all "
      "together, each with its standard deviation (the residual's, through "
      "(W\u1d40W)\u207b\u00b9). "
      "The standard deviations measure noise, not bias.");
  if (!in.lsmi_skipped.empty()) h.paragraph("LSMI did not run: " + in.lsmi_skipped + ".");
  table_one(h, in);
  if (in.output_error) {
    const OutputErrorSummary& oe = *in.output_error;
    h.paragraph(
        "Output error: the model simulated with the input as the board applied it and fitted to "
        "the measured angles (multiple shooting, " +
        std::to_string(oe.segments) + " segments, " + std::to_string(oe.iterations) +
        " iterations, " +
        (oe.converged ? "converged" : "not converged: where it stopped is in results.json") +
        "), inside the physical region; angle residual RMS q1 " + dash_sci(oe.angle_rms_rad[0], 2) +
        " rad, q2 " + dash_sci(oe.angle_rms_rad[1], 2) + " rad; data path lag " +
        dash_fixed(oe.input_lag_s * 1e3, 3) + " ms; " + oe.time_stamps +
        ". Its standard deviations are local (from the Jacobian at the optimum, robust to "
        "angle errors correlated within a segment) and take the model and the input as exact.");
  }
  if (!in.lsmi_skipped.empty()) {
    h.raw("</section>\n");
    return;
  }
  std::vector<std::vector<std::string>> diagnostics;
  for (std::size_t e = 0; e < in.per_experiment.size() && e < in.experiment_names.size(); ++e) {
    diagnostics.push_back(diagnostic(in.experiment_names[e], in.per_experiment[e]));
  }
  diagnostics.push_back(diagnostic("all experiments", in.combined));
  h.table("lsmi-diagnostics",
          "How well the data excite the parameters: the column-scaled regressor's condition "
          "number, its rank (of 7), the residual",
          {"experiment", "samples", "condition number", "rank", "residual \u03c3 [N m]",
           "poorly excited"},
          diagnostics);
  h.raw("</section>\n");
}

// Fig. 2/3: one figure per experiment.
void section_data(Html& h, const ReportInput& in) {
  h.raw("<section id=\"data\">\n");
  h.element("h2", "Data and uncertainty bands (Fig. 2/3)");
  if (in.signals_svg.empty()) {
    h.paragraph("No experiment figures.", "absent");
  }
  for (std::size_t i = 0; i < in.signals_svg.size(); ++i) {
    const std::string name = i < in.experiment_names.size() ? in.experiment_names[i] : "";
    h.figure(figure_id("fig-signals", i + 1), in.signals_svg[i],
             "Fig. " + std::to_string(i + 2) + " (" + name +
                 "): the measured angles, the filtered velocities and accelerations of the arm "
                 "(left) and the pendulum (right), and the motor torque " +
                 (in.torque_source.empty() ? std::string() : "(" + in.torque_source + ") ") +
                 "over time t [s], each on an axis of its own; " +
                 (in.signals_bands.empty() ? std::string("the shaded bands are the data's "
                                                         "uncertainty")
                                           : in.signals_bands) +
                 ".");
  }
  h.raw("</section>\n");
}

// Fig. 5, or why there is none.
void section_validation(Html& h, const ReportInput& in) {
  h.raw("<section id=\"validation\">\n");
  h.element("h2", "Held-out torque (Fig. 5)");
  if (in.validation) {
    const ValidationSummary& v = *in.validation;
    h.paragraph("On the held-out session " + v.name +
                ", the torque predicted by the combined LSMI "
                "estimate misses the measured one by RMSE " +
                dash_sci(v.rmse_nm, 3) + " N m, " + dash_fixed(v.rmse_percent_of_range, 2) +
                " % of the torque range over " + std::to_string(v.samples) +
                " samples (eq. 12; the paper: 6.4 % with LSMI).");
    h.figure("fig-5", v.svg,
             "Fig. 5: measured (black" +
                 (in.torque_source.empty() ? std::string() : ", " + in.torque_source) +
                 ") and LSMI-predicted (red) motor torque [N m] over time t [s] on a session not "
                 "used for the fit; RMSE " +
                 dash_fixed(v.rmse_percent_of_range, 2) + " % of the range.");
  } else if (!in.lsmi_skipped.empty()) {
    h.paragraph("LSMI did not run: no torque validation.", "absent");
  } else if (in.output_error && !in.output_error->held_out_name.empty()) {
    h.paragraph("The held-out session " + in.output_error->held_out_name +
                    " is too short for LSMI's filters: no torque validation (the warnings say "
                    "how short).",
                "absent");
  } else {
    h.paragraph(
        "No held-out session was given (furuta identify --validate LOG): no torque "
        "validation.",
        "absent");
  }
  if (in.output_error && !in.output_error->svg.empty()) {
    const OutputErrorSummary& oe = *in.output_error;
    const auto rmse = [](const std::array<double, 2>& r) {
      return "q1 " + dash_sci(r[0], 3) + " rad, q2 " + dash_sci(r[1], 3) + " rad";
    };
    const bool lsmi = oe.lsmi_rmse_rad.has_value();
    h.figure("fig-free-run", oe.svg,
             "The held-out " + oe.held_out_name +
                 ": measured angles (black) against free runs of the model from the same input "
                 "with the " +
                 (lsmi ? "LSMI (red) and the " : "") +
                 "output-error (blue) parameters, over time t [s]. Angle RMSE " +
                 (lsmi ? "with LSMI: " + rmse(*oe.lsmi_rmse_rad) + "; " : "") +
                 "with output error: " + rmse(oe.refined_rmse_rad) + ".");
  }
  h.raw("</section>\n");
}

// Table II: the intervals SIVIA starts from and its outer hull.
void intervals_table(Html& h, const std::vector<IntervalRow>& table) {
  std::vector<std::vector<std::string>> rows;
  for (const IntervalRow& r : table) {
    rows.push_back({r.parameter, pretty_unit(r.unit),
                    "[" + dash_sci(r.lo, 4) + ", " + dash_sci(r.hi, 4) + "]", r.origin,
                    r.outer_hull ? "[" + dash_sci((*r.outer_hull)[0], 4) + ", " +
                                       dash_sci((*r.outer_hull)[1], 4) + "]"
                                 : "-"});
  }
  if (!rows.empty()) {
    h.table("table-2",
            "Table II: the intervals SIVIA starts from, and its outer approximation's hull",
            {"parameter", "unit", "interval used", "from", "SIVIA outer hull"}, rows);
  }
}

// Table II and Fig. 4, or the intervals SIVIA would start from.
void section_sivia(Html& h, const ReportInput& in) {
  h.raw("<section id=\"sivia\">\n");
  h.element("h2", "Guaranteed identification (Table II, Fig. 4)");
  intervals_table(h, in.table_two);
  if (in.sivia) {
    const SiviaSummary& s = *in.sivia;
    h.paragraph("SIVIA over " + std::to_string(s.samples) + " samples (q = " + std::to_string(s.q) +
                "): " + std::to_string(s.inner) + " inner, " + std::to_string(s.boundary) +
                " boundary and " + std::to_string(s.outer) + " outer boxes; " +
                std::to_string(s.tested) + " tested in " + short_number(s.seconds, 3) + " s" +
                (s.truncated ? " (truncated)" : "") + ".");
    h.paragraph(std::string(kSiviaAssumedBoundsNote) + ".");
    for (const std::string& excluded : s.excludes_output_error) {
      h.paragraph("Warning: " + excluded + ".");
    }
    if (s.empty) h.paragraph("The feasible set is empty. " + s.finding);
    h.figure("fig-4", s.svg,
             "Fig. 4: the SIVIA paving projected on the viscous frictions (fv1, fv2) [N m s]: "
             "inner boxes (every parameter consistent with the data), boundary boxes "
             "(undecided at epsilon) and outer boxes (proven inconsistent).");
  } else if (!in.lsmi_skipped.empty()) {
    h.paragraph("SIVIA starts from LSMI's estimate, and LSMI did not run: no paving.", "absent");
  } else {
    h.paragraph(
        "SIVIA was not run (furuta identify --sivia): no paving. The intervals above are "
        "those it would start from.",
        "absent");
  }
  h.raw("</section>\n");
}

// The windowed set inversion's set, scaled and at the rig's scale, and its windows.
void section_guaranteed(Html& h, const ReportInput& in) {
  h.raw("<section id=\"guaranteed\">\n");
  h.element("h2", "Guaranteed set from the angles (windowed set inversion)");
  if (!in.guaranteed) {
    h.paragraph(
        "The windowed set inversion was not run (furuta identify --guaranteed, or [automation] "
        "guaranteed).",
        "absent");
    h.raw("</section>\n");
    return;
  }
  const GuaranteedSummary& g = *in.guaranteed;
  h.paragraph(g.headline);
  for (const std::string& note : g.notes) h.paragraph(note);
  if (!g.scaled_rows.empty()) {
    h.table("guaranteed-scaled",
            "The set in the scaled parameters (per unit of the drive's gain g; b = (fv1 + k_w) / "
            "g), which the angles determine",
            {"parameter", "searched", "set", "half-width", "truth (simulated rig)"}, g.scaled_rows);
  }
  if (!g.set_svg.empty()) {
    h.figure("guaranteed-set", g.set_svg,
             "The set (blue) in its search box (grey), per scaled parameter, as offsets from the "
             "output-error estimate (|) in its standard deviations; the truth (red circle) when "
             "the sessions were simulated; on the right the set's half-width and the step (the "
             "k-th windows of every recording) after which it was within 1 % of it.");
  }
  if (!g.rig_rows.empty()) {
    h.table("guaranteed-rig",
            "The set at the rig's scale: the scaled set times the drive's interval ([motor] and "
            "[guaranteed] motor_tolerance_pct)",
            {"parameter", "unit", "set", "share of the width the drive's tolerance causes"},
            g.rig_rows);
  }
  if (!g.window_rows.empty()) {
    h.table("guaranteed-windows", "The windows (times on the commands' clock)",
            {"recording", "window", "planned [s]", "reached [s]", "readings", "verdict"},
            g.window_rows);
  }
  h.raw("</section>\n");
}

// Table III's rows as the page shows them.
void table_three(Html& h, const std::vector<validated::ScenarioResult>& results) {
  std::vector<std::vector<std::string>> rows;
  for (const auto& r : results) {
    rows.push_back(
        {scenario_label(r.scenario) + " " + scenario_description(r.scenario), r.parameters.name,
         dash_fixed(r.t_reached_s, 3) + " / " + dash_fixed(r.scenario.duration_s, 1),
         std::to_string(r.steps), table_three_cell(r.q2_step), table_three_cell(r.q2_interpolated),
         dash_fixed(100 * r.q1_step.rate(), 1), dash_fixed(100 * r.q1_interpolated.rate(), 1),
         dash_fixed(r.q2_mean_width_rad * kDegPerRad, 3), coverage_verdict(r.q2_step),
         tube_status_text(r)});
  }
  h.table("table-3", "Table III: coverage of the measurements by the tubes [%]",
          {"scenario", "parameters", "reached / duration [s]", "steps", "q2 step, all (reached)",
           "q2 interp., all (reached)", "q1 step", "q1 interp.", "q2 mean width [deg]",
           "coverage (" + coverage_note() + ")", "tube"},
          rows);
}

// Fig. 6: one figure per scenario and parameter set.
void figures_six(Html& h, const std::vector<validated::ScenarioResult>& results) {
  std::size_t n = 0;
  for (const auto& r : results) {
    const bool early = r.t_reached_s + 1e-9 < r.scenario.duration_s;
    h.figure(figure_id("fig-6", ++n), svg_scenario(r),
             "Fig. 6 " + scenario_label(r.scenario) + ", " + r.parameters.name +
                 " parameters: the tube of the pendulum angle q2 [deg] over time t [s] (shaded) "
                 "and the measured q2 (points; red where outside the tube); q2 step coverage " +
                 dash_fixed(100 * r.q2_step.rate(), 1) + " %" +
                 (early ? ", the tube ended at " + dash_fixed(r.t_reached_s, 3) + " s" : "") + ".");
  }
}

// Table III and Fig. 6, or why there are none.
void section_simulation(Html& h, const ReportInput& in) {
  h.raw("<section id=\"simulation\">\n");
  h.element("h2", "Validated simulation (Table III, Fig. 6)");
  if (in.simulation) {
    h.paragraph("The paper's four scenarios, measured on the simulated rig (" +
                in.simulation->measurement_source +
                "), against guaranteed tubes of the pendulum angle from each parameter set. "
                "Coverage: the share of the measured samples inside the tube, over all samples "
                "and (in parentheses) over those the tube reached; \"step\" is the paper's test, "
                "\"interp.\" the enclosure at the sample's instant. The paper, q2 step: "
                "46/61/38/25 % with interval parameters, 41/34/20/21 % with LSMI. The coverage "
                "column says \"ok\" when the q2 step coverage over all samples is at least " +
                short_number(100 * kCoverageOkRate) +
                " %, the paper's lowest, and \"low\" below it: tubes that miss more than any the "
                "method was published with point at the model, the parameters or the "
                "measurement. The tube column says whether the tube reached the scenario's end.");
    for (const std::string& note : per_gain_set_notes(in.simulation->results)) {
      h.paragraph(note + ".");
    }
    table_three(h, in.simulation->results);
    figures_six(h, in.simulation->results);
  } else {
    h.paragraph(
        "The validated simulation was not run (furuta identify --simulate): no tubes, no "
        "Table III.",
        "absent");
  }
  h.raw("</section>\n");
}

// An LSMI estimate no rig can have: above everything else, since every number below inherits
// the recording mistake it most likely comes from.
void section_physical(Html& h, const ReportInput& in) {
  std::vector<const Warning*> physical;
  for (const Warning& w : in.warnings) {
    if (w.stage == Warning::Stage::physical) physical.push_back(&w);
  }
  if (physical.empty()) return;
  h.raw("<section id=\"physical\" class=\"physical\" role=\"alert\">\n");
  h.element("h2", "The LSMI estimate is not physical");
  for (const Warning* w : physical) h.paragraph(w->text);
  h.paragraph(
      "LSMI is reported unconstrained, as the paper's reference; the numbers below are what the "
      "recordings give as read, not a rig's parameters.");
  h.raw("</section>\n");
}

}  // namespace

std::string render_html(const ReportInput& in) {
  Html h;
  page_head(h, in);
  section_physical(h, in);
  const std::vector<BalanceLogEntry> balance = balance_logs(in);
  contents(h, !balance.empty());
  section_rig_and_sessions(h, in);
  section_balance(h, balance);
  section_warnings(h, in);
  section_lsmi(h, in);
  section_data(h, in);
  section_validation(h, in);
  section_sivia(h, in);
  section_guaranteed(h, in);
  section_simulation(h, in);
  h.raw("</body>\n</html>\n");
  return h.str();
}

}  // namespace furuta::report
