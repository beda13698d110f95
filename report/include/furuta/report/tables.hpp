#pragma once
// The text tables a terminal and table.txt / table3.txt show: Table I (LSMI), the SIVIA summary,
// Table III (coverage of the scenarios' measurements by the tubes).

#include <optional>
#include <string>
#include <vector>

#include "furuta/identification/guaranteed.hpp"
#include "furuta/identification/identify.hpp"
#include "furuta/identification/output_error.hpp"
#include "furuta/model/model.hpp"
#include "furuta/pipeline/pipeline.hpp"
#include "furuta/validated/scenarios.hpp"

namespace furuta::report {

// A scenario as the tables and figures name it: "(a)" for 1 ... "(d)" for 4, "#n" beyond 26.
std::string scenario_label(const validated::Scenario& scenario);
// "x0 = [0, 0, -100 deg, 0], u = 0 N m"
std::string scenario_description(const validated::Scenario& scenario);

// Table I: parameter, unit, one column per experiment, all, (CAD), (truth), each +- its standard
// deviation; condition numbers, residuals, the input lag, the held-out RMSE and the warnings.
// Experiments whose names do not fit a column are headed E1, E2, ..., named in a legend above.
// With `refined`, an "output error" column beside "all experiments" and a line of its lag,
// angle residuals and convergence.
std::string format_table_one(const identification::Identification& id,
                             const identification::OutputErrorResult* refined = nullptr);
// Whose clock the refinement's observation times came from, one sentence without a newline:
// "times: the boards' clocks (the host's stamps were on average 0.50 ms, at most 1.00 ms later)".
std::string time_stamps_text(const identification::OutputErrorResult& refined);

// What --sivia's set rests on, said wherever the set is shown: the paper's method takes the data's
// error bounds (velocities, accelerations, torque) from [sivia], which the data do not prove.
inline constexpr const char* kSiviaAssumedBoundsNote =
    "SIVIA is the paper's method: its set rests on [sivia]'s assumed error bounds of the "
    "velocities, "
    "accelerations and torque, which the data do not prove";

// "\nSIVIA (n samples, q = ..): counts ..." and each unknown's hull (6 digits, rounded outward)
// (with whether it holds the truth, when there is one), or the finding when the set is empty.
// `tested_span` (tube_span_text of the set's tubes) follows "contains the truth".
std::string sivia_summary_text(const identification::GuaranteedResult& result,
                               const std::optional<model::Parameters<double>>& truth,
                               const std::string& tested_span = "");

// " up to 0.025 s of 4 s (where its tubes end)": the scenario run of the set named `set` whose
// tube ended at the smallest share of its duration, when that is below kTestedShareOfSpan;
// "" when every tube of the set reached that far, or the set has none. A set whose tubes end
// there was tested against the truth's trajectory only so far.
std::string tube_span_text(const std::vector<validated::ScenarioResult>& results,
                           const std::string& set);

// "the set excludes the output-error estimate of fv2: 6.42e-04 lies 3.2 sd above [a, b] (the set
// rests on [sivia]'s assumed bounds)": one line, no newline.
std::string excluded_estimate_text(const pipeline::EstimateOutsideSet& excluded);
// The windowed set inversion's result: the windows, the scaled set against its search box (and
// the truth, simulated sessions), the rig-scale set with the drive's share of each width.
std::string windowed_summary_text(const pipeline::WindowedGuaranteed& windowed);
// A window's verdict as results.json and the outputs name it: carried (its flow reached its
// end), flow_stopped, inconsistent.
const char* window_verdict_name(identification::WindowVerdict verdict);
// A parameter of the output-error estimate outside the windowed set (scaled, in scaled sd).
std::string windowed_excluded_text(const pipeline::EstimateOutsideSet& excluded);

// A windowed set holds only what its windows' flows tested: when they carried a recording less
// than kTestedShareOfSpan of its chain's span, a claim that the set contains the truth holds up
// to there, not over the recording. A tenth or more of the readings untested is "long before
// the horizon".
inline constexpr double kTestedShareOfSpan = 0.9;
// " up to 0.06 s of 10 s" (the recording whose windows carried the smallest share of its span,
// times from its first command; " of recording 1" with several), or "" when every recording's
// windows carried at least kTestedShareOfSpan of it.
std::string tested_span_text(const identification::WindowedSet& set);

// Table III: per scenario and parameter set, time reached, steps, coverage of q2 (both modes,
// over all samples and over those reached) and q1, the q2 tube's mean width, the status; with
// the paper's figures for comparison. The integrator's reason for an early end has its numbers
// cut to 4 digits (tubes.json and results.json keep them whole).
std::string format_table_three(const std::vector<validated::ScenarioResult>& results);

// Why a tube ended before its scenario's end, for a person: a width past max_width from its
// numbers, the component named and angles in degrees as the rest of Table III
// ("q2's enclosure 386.1 deg wide > the limit of 360 deg at t = 0.05872 s"); any other reason as
// the integrator wrote it, its numbers cut to 4 digits. Empty when the tube reached the end.
std::string tube_end_text(const validated::ScenarioResult& result);

// The share of the measured q2 samples a tube must hold, over all samples (the paper's step test),
// for Table III to call its coverage "ok": the lowest the paper reports (20 %, LSMI's scenario
// (c)). Tubes of the right model and parameters hold every sample their start and noise allow;
// below the paper's worst they miss more than any row the method was published with, which is a
// sign of a wrong model, parameters or measurement, not of the method.
inline constexpr double kCoverageOkRate = 0.20;
// "ok" at or above kCoverageOkRate, "low" below it, "-" when no sample was tested.
std::string coverage_verdict(const validated::Coverage& q2_step);
// What the verdict tests: "q2 step >= 20 %".
std::string coverage_note();
// "reached the end", or "ended (width_exceeded): " and tube_end_text: the tube itself, apart from
// how well it covers.
std::string tube_status_text(const validated::ScenarioResult& result);
// What Table III's rows of a set known up to the drive's gain are (validated::ParameterSet::
// torque_scale), one line per such set; empty when there is none.
std::vector<std::string> per_gain_set_notes(const std::vector<validated::ScenarioResult>& results);

// Where the scenarios' measurements came from, as a sentence's part: "the simulated sessions'
// truth", ...
std::string measurement_source_text(const pipeline::MeasurementSource& source);

// "\nValidation by guaranteed simulation, measurements from <source>:" and Table III; a note
// first when SIVIA's set was empty (no SIVIA tubes).
std::string simulation_summary_text(const std::string& measurement_source, bool sivia_set_empty,
                                    const std::vector<validated::ScenarioResult>& results);

// "\nheld-out free run on NAME (angle RMSE, q1 / q2): LSMI a / b rad, output error c / d rad"
std::string held_out_free_run_text(const pipeline::HeldOutFreeRuns& runs);

// What `furuta identify` prints: Table I, then the held-out free runs, the SIVIA summary and the
// simulation summary when they ran.
std::string terminal_text(const pipeline::Run& run);
// terminal_text less Table I: what follows it once SIVIA and the scenarios are done (`furuta
// identify` prints Table I as soon as the fit is done, pipeline::Progress::fit_done).
std::string terminal_text_after_lsmi(const pipeline::Run& run);

}  // namespace furuta::report
