#pragma once
// The identification report a person reads: one self-contained HTML page (inline CSS and SVG, no
// script, no external URL) with the rig and its sessions, Table I (LSMI), Table II (the intervals
// SIVIA starts from), the paving (Fig. 4), the held-out torque (Fig. 5), the data with their
// uncertainty bands (Fig. 2/3), the tubes and their coverage (Fig. 6, Table III), and what to be
// wary of. results.json is the machine-readable twin; both come from `furuta identify`.
//
//   report::ReportInput input = report::report_page(run, version, signals_svg, paving_svg);
//   write(dir / "report.html", report::render_html(input));     // or write_identification

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "furuta/config/rig_config.hpp"
#include "furuta/identification/guaranteed.hpp"
#include "furuta/identification/identify.hpp"
#include "furuta/pipeline/pipeline.hpp"
#include "furuta/session_log/session_log.hpp"
#include "furuta/validated/scenarios.hpp"

namespace furuta::report {

// What a session log says about itself (pipeline.hpp): the sessions table and the lost-sample
// warnings.
using pipeline::SessionSummary;
using pipeline::summarize_session;

// One vocabulary from the pipeline to the page: a warning is its stage, its kind and its text.
using pipeline::Warning;
// The heading a stage's warnings are shown under: "session" (the data), "LSMI",
// "physical" (also shown above everything), "output error", "SIVIA", "guaranteed", "simulation".
std::string topic(Warning::Stage stage);
// The kind as one word ("data", "skipped", "failed", "suspect", "note"): the HTML's class for it.
std::string kind_name(Warning::Kind kind);

// A row of Table II: the interval a parameter enters SIVIA with, and what SIVIA made of it.
struct IntervalRow {
  std::string parameter, unit;
  double lo = 0, hi = 0;
  std::string origin;                               // "LSMI +- 12 %" (carried) or "prior (unknown)"
  std::optional<std::array<double, 2>> outer_hull;  // SIVIA ran and found a set
};

struct SiviaSummary {
  std::size_t samples = 0;
  int q = 0;
  std::size_t inner = 0, boundary = 0, outer = 0, tested = 0;
  double seconds = 0;
  bool truncated = false;
  bool empty = false;
  std::string finding;  // why it is empty
  std::size_t inconsistent_samples = 0;
  // The output-error estimate's parameters outside the set (excluded_estimate_text says each).
  std::vector<std::string> excludes_output_error;
  std::string svg;  // Fig. 4 (svg_paving)
};

struct ValidationSummary {
  std::string name;  // the held-out experiment
  double rmse_nm = 0;
  double rmse_percent_of_range = 0;
  std::size_t samples = 0;  // the samples compared
  std::string svg;          // Fig. 5 (svg_torque_validation)
};

// The output-error refinement: Table I's column, its diagnostics, the held-out free runs.
struct OutputErrorSummary {
  model::Parameters<double> estimate{}, std_dev{};
  double input_lag_s = 0;
  std::array<double, 2> angle_rms_rad = {0, 0};  // fitted minus measured, q1 and q2
  std::size_t segments = 0;
  int iterations = 0;
  bool converged = false;
  std::string time_stamps;  // time_stamps_text
  // The held-out recording run free with the LSMI and the refined parameters.
  std::string held_out_name;
  std::optional<std::array<double, 2>> lsmi_rmse_rad;  // none when LSMI did not run
  std::array<double, 2> refined_rmse_rad = {0, 0};
  // The held-out measured angles' own spread (identification::FreeRun::measured_sd_rad).
  std::array<double, 2> measured_sd_rad = {0, 0};
  std::string svg;  // svg_free_runs; empty without a held-out recording
};

struct SimulationSummary {
  std::string measurement_source;                  // where the "measured" scenarios come from
  std::vector<validated::ScenarioResult> results;  // Table III rows; Fig. 6 drawn from each
};

// Everything the page shows, as plain data. Absent parts are said to be absent (not run, no
// held-out session), never left out silently.
// The windowed set inversion (identify --guaranteed) as the page shows it: rows of text.
struct GuaranteedSummary {
  std::string headline;                               // windows, verdict, time, the search box
  std::vector<std::vector<std::string>> scaled_rows;  // parameter, searched, set, +-%, truth
  std::vector<std::vector<std::string>> rig_rows;     // parameter, unit, set, drive's share
  std::vector<std::vector<std::string>> window_rows;  // recording, window, times, verdict
  std::vector<std::string> notes;                     // the lag, exclusions, why it stopped
  std::string set_svg;                                // svg_windowed_set
};

struct ReportInput {
  std::string title = "Identification report";
  std::string software_version;
  std::vector<std::pair<std::string, std::string>> rig;  // facts: name, backend, period, ...
  std::vector<SessionSummary> sessions;                  // empty for CSV inputs
  std::vector<std::string> inputs;                       // the files fitted and held out

  // Table I: one column per experiment, then all together.
  std::vector<std::string> experiment_names;
  std::vector<identification::LsmiResult> per_experiment;
  identification::LsmiResult combined;
  std::string lsmi_skipped;  // why LSMI did not run ("" when it did: the columns above)
  std::optional<model::Parameters<double>> nominal, truth;
  double input_lag_s = 0;
  std::optional<OutputErrorSummary> output_error;  // absent: not run

  // How the torque of Fig. 2/3/5 was had: "by eq. 4 from the logged duty cycle", "as recorded".
  std::string torque_source;
  std::vector<std::string> signals_svg;  // Fig. 2/3, one per experiment (svg_signals)
  std::string signals_bands;             // what the bands in them are

  std::optional<ValidationSummary> validation;  // Fig. 5

  std::vector<IntervalRow> table_two;
  std::optional<SiviaSummary> sivia;            // Fig. 4; absent: --sivia not given
  std::optional<GuaranteedSummary> guaranteed;  // absent: --guaranteed not given

  std::optional<SimulationSummary> simulation;  // Table III, Fig. 6; absent: --simulate not given

  // The run's warnings (pipeline::Run::warnings); render_html adds derived_warnings().
  std::vector<Warning> warnings;
};

// Table I, the validation, how the torque was had and the identification's own warnings
// (pipeline::identification_warnings) from an identification.
ReportInput report_input(const identification::Identification& id);

// How the torque was formed from a recording's input, for the captions: eq. 4 for duty (a log's
// or a CSV's), the import spec's [motor] for voltage, nothing for recorded torque.
std::string torque_source(identification::InputKind input, bool csv);

// The whole page of a run: report_input, the rig (the configuration file given, or the log that
// carried it) and the settings, the sessions and input files (where Run::inputs says they are),
// the figures given (Fig. 2/3 per experiment, Fig. 4), Table II, SIVIA's summary and the
// scenarios.
ReportInput report_page(const pipeline::Run& run, const std::string& software_version,
                        const std::vector<std::string>& signals_svg, const std::string& paving_svg);

// Table II: the intervals of the SIVIA problem the configuration sets up around the LSMI estimate
// (the mu's +- [sivia] mu_uncertainty_pct, the frictions' priors; unknowns as in [sivia]), and,
// when SIVIA ran, its outer hull per parameter.
std::vector<IntervalRow> table_two(const model::Parameters<double>& lsmi,
                                   const config::SiviaConfig& sivia,
                                   const identification::GuaranteedResult* result);
SiviaSummary sivia_summary(const identification::GuaranteedResult& result, std::string svg);
// The windowed set inversion's section: its set against the search box (and the truth when the
// sessions are simulated), at the rig's scale, its windows, the lag and the exclusions.
GuaranteedSummary guaranteed_summary(const pipeline::WindowedGuaranteed& windowed,
                                     const std::vector<pipeline::EstimateOutsideSet>& excluded);

// What the struct itself shows to be wary of, beyond the run's warnings: damaged or cut-short logs
// and fatal faults, the output-error estimate outside SIVIA's set, samples SIVIA tolerated, tubes
// that ended early.
std::vector<Warning> derived_warnings(const ReportInput& input);

// The page. Every text is escaped; the SVG strings are the project's own generators' output and
// go in as they are (an XML declaration, if any, is dropped).
std::string render_html(const ReportInput& input);

// Text as HTML character data or attribute value.
std::string escape_html(const std::string& text);

}  // namespace furuta::report
