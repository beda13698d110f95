// What the report claims next to a number follows from a check of that number: Table III's end
// reason in degrees from the integrator's numbers, a coverage verdict from a named threshold, a
// set that "contains the truth" only as far as its windows tested it, a free run worse than the
// signal's own spread flagged, and an estimate that is not a number marked failed.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "furuta/report/report.hpp"
#include "furuta/report/tables.hpp"

namespace furuta::report::claims_test {
namespace {

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

ReportInput minimal_input() {
  ReportInput in;
  in.software_version = "0.1.0-test";
  in.experiment_names = {"run1"};
  in.per_experiment.resize(1);
  in.per_experiment[0].estimate = {1e-3, 2e-3, 8e-4, 1.2e-3, 7e-2, 8e-2, 6e-4};
  in.per_experiment[0].std_dev = {1e-5, 2e-5, 8e-6, 1.2e-5, 7e-4, 8e-4, 6e-6};
  in.combined = in.per_experiment[0];
  return in;
}

std::string all_warnings(const ReportInput& in) {
  std::string all;
  for (const Warning& w : derived_warnings(in)) all += kind_name(w.kind) + ": " + w.text + "\n";
  return all;
}

// A scenario row whose tube covered `covered` of 1000 measured q2 samples.
validated::ScenarioResult covered_row(std::size_t covered) {
  validated::ScenarioResult r;
  r.scenario = validated::paper_scenario(3);
  r.parameters.name = "LSMI";
  r.t_reached_s = r.scenario.duration_s;
  r.q2_step.measurements = 1000;
  r.q2_step.in_time = 1000;
  r.q2_step.covered = covered;
  return r;
}

// Before: "width_exceeded: enclosure width 6.737 > max_width 6.283 at t = 0.05872", radians
// without a unit beside a width column in degrees.
TEST(ReportClaims, TableThreesEndReasonIsInDegreesFromTheIntegratorsNumbers) {
  validated::ScenarioResult r;
  r.scenario = validated::paper_scenario(1);
  r.parameters.name = "SIVIA";
  r.status = validated::IntegrationResult::Status::width_exceeded;
  r.reason =
      "enclosure width 6.7367745165386133 > max_width 6.2831853071795862 at t = "
      "0.058721594480886791";
  r.width_stop =
      validated::WidthStop{2, 6.7367745165386133, 2 * std::numbers::pi, 0.058721594480886791};
  r.t_reached_s = 0.058721594480886791;
  const std::string expected =
      "q2's enclosure 386 deg wide > the limit of 360 deg at t = 0.05872 s";
  EXPECT_EQ(tube_end_text(r), expected);
  const std::string table = format_table_three({r});
  EXPECT_TRUE(has(table, "ended (width_exceeded): " + expected)) << table;
  EXPECT_FALSE(has(table, "6.737")) << table;
  ReportInput in = minimal_input();
  in.simulation = SimulationSummary{"the truth", {r}};
  const std::string html = render_html(in);
  EXPECT_TRUE(has(html, "q2&#39;s enclosure 386 deg wide &gt; the limit of 360 deg") ||
              has(html, "q2's enclosure 386 deg wide &gt; the limit of 360 deg"))
      << "the table and the warning";
  EXPECT_FALSE(has(html, "6.737")) << "nor in the warnings";
  // A velocity is in degrees per second, a carried parameter in its own unit.
  r.width_stop->component = 3;
  EXPECT_TRUE(has(tube_end_text(r), "dq2's enclosure 386 deg/s wide > the limit of 360 deg/s"));
  r.width_stop->component = 5;
  EXPECT_TRUE(has(tube_end_text(r), "component 5's enclosure 6.737 wide > the limit of 6.283"));
}

// Before: "ok" beside a coverage of 10.8 %: the integrator's status, read as a verdict on it.
TEST(ReportClaims, ACoverageVerdictComesFromTheNamedThreshold) {
  EXPECT_EQ(kCoverageOkRate, 0.20);
  EXPECT_EQ(coverage_verdict(covered_row(108).q2_step), "low");
  EXPECT_EQ(coverage_verdict(covered_row(200).q2_step), "ok");
  EXPECT_EQ(coverage_verdict(validated::Coverage{}), "-");
  const std::string table = format_table_three({covered_row(108), covered_row(460)});
  EXPECT_TRUE(has(table, "q2 step >= 20 %")) << table;
  EXPECT_TRUE(has(table, "low       reached the end")) << table;
  EXPECT_TRUE(has(table, "ok        reached the end")) << table;
  ReportInput in = minimal_input();
  in.simulation = SimulationSummary{"the truth", {covered_row(108)}};
  const std::string html = render_html(in);
  EXPECT_TRUE(has(html, "<td>low</td>")) << html;
  EXPECT_FALSE(has(html, "<td>ok</td>")) << html;
  const std::string warnings = all_warnings(in);
  EXPECT_TRUE(has(warnings,
                  "suspect: scenario (c), LSMI: the tube holds 10.8 % of the measured "
                  "q2 samples (step test), below 20.0 %"))
      << warnings;
  in.simulation = SimulationSummary{"the truth", {covered_row(460)}};
  EXPECT_FALSE(has(all_warnings(in), "holds")) << all_warnings(in);
}

pipeline::WindowedGuaranteed windowed_set(double reached_s) {
  pipeline::WindowedGuaranteed w;
  identification::WindowedSet& r = w.result;
  r.verdict = identification::WindowedSetVerdict::contracted;
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    r.search[k] = interval::Interval(0.0, 3.0);
    r.set[k] = interval::Interval(0.5, 2.0);
    w.rig_set[k] = interval::Interval(0.5, 2.0);
    w.estimate_scaled[k] = 1.0;
  }
  r.lag_s = interval::Interval(0.0, 0.01);
  r.pendulum_zero_rad = interval::Interval(-0.01, 0.01);
  w.truth_scaled = model::Parameters<double>{1, 1, 1, 1, 1, 1, 1};
  r.spans = {{2.0, 12.0, 2.0 + reached_s}};
  return w;
}

// Before: "contains the truth" beside windows whose flows stopped at 0.06 s of 10 s.
TEST(ReportClaims, ASetContainsTheTruthOnlyAsFarAsItsWindowsTestedIt) {
  const std::string early = windowed_summary_text(windowed_set(0.06));
  EXPECT_TRUE(has(early, "contains the truth up to 0.06 s of 10 s")) << early;
  const std::string whole = windowed_summary_text(windowed_set(10.0));
  EXPECT_TRUE(has(whole, "contains the truth\n")) << whole;
  EXPECT_FALSE(has(whole, "up to")) << whole;
  // Several recordings: the least tested is named.
  pipeline::WindowedGuaranteed two = windowed_set(10.0);
  two.result.spans.push_back({1.0, 5.0, 1.5});
  EXPECT_EQ(tested_span_text(two.result), " up to 0.5 s of 4 s of recording 1");
  // The page's table says the same.
  ReportInput in = minimal_input();
  in.guaranteed = guaranteed_summary(windowed_set(0.06), {});
  bool found = false;
  for (const auto& row : in.guaranteed->scaled_rows) {
    found = found || row.back() == "inside up to 0.06 s of 10 s";
  }
  EXPECT_TRUE(found);
}

// Before: SIVIA's hull "(contains the truth)" beside its tubes that ended at 0.025 s of 4 s.
TEST(ReportClaims, SiviasSetContainsTheTruthOnlyAsFarAsItsTubesReach) {
  validated::ScenarioResult early;
  early.scenario = validated::paper_scenario(4);
  early.parameters.name = pipeline::kSiviaSetName;
  early.t_reached_s = 0.025;
  validated::ScenarioResult whole = early;
  whole.parameters.name = "LSMI";
  whole.t_reached_s = whole.scenario.duration_s;
  EXPECT_EQ(tube_span_text({whole, early}, pipeline::kSiviaSetName),
            " up to 0.025 s of 4 s (where its tubes end)");
  EXPECT_EQ(tube_span_text({whole}, "LSMI"), "");
  identification::GuaranteedResult g;
  g.unknown.fill(false);
  g.unknown[5] = true;
  interval::Box box(model::kParameterCount, interval::Interval(0.0, 1.0));
  g.paving.prior = box;
  g.paving.inner = {box};
  const model::Parameters<double> truth{0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5};
  const std::string text =
      sivia_summary_text(g, truth, tube_span_text({whole, early}, pipeline::kSiviaSetName));
  EXPECT_TRUE(has(text, "(contains the truth up to 0.025 s of 4 s (where its tubes end))")) << text;
  EXPECT_TRUE(has(sivia_summary_text(g, truth), "(contains the truth)"));
}

// Before: LSMI's free run missing q2 by 1.36 rad went unflagged.
TEST(ReportClaims, AFreeRunWorseThanTheSignalsOwnSpreadIsSuspect) {
  ReportInput in = minimal_input();
  OutputErrorSummary oe;
  oe.estimate = in.combined.estimate;
  oe.std_dev = in.combined.std_dev;
  oe.converged = true;
  oe.held_out_name = "held.lcmlog";
  oe.lsmi_rmse_rad = std::array<double, 2>{0.01, 1.36};
  oe.refined_rmse_rad = {0.004, 0.02};
  oe.measured_sd_rad = {0.3, 0.41};
  in.output_error = oe;
  const std::string warnings = all_warnings(in);
  EXPECT_TRUE(has(warnings,
                  "suspect: the free run of the held-out held.lcmlog with the LSMI "
                  "parameters misses q2 by RMSE 1.36 rad, more than the measured "
                  "angle's own spread (sd 0.41 rad)"))
      << warnings;
  EXPECT_FALSE(has(warnings, "output-error parameters")) << warnings;
  EXPECT_FALSE(has(warnings, "misses q1")) << warnings;
  EXPECT_TRUE(has(render_html(in), "<li class=\"suspect\">")) << "the red border";

  // The terminal's line says it too.
  pipeline::HeldOutFreeRuns runs;
  runs.name = "held.lcmlog";
  runs.lsmi = identification::FreeRun{};
  runs.lsmi->rmse_rad = {0.01, 1.36};
  runs.refined.rmse_rad = {0.004, 0.02};
  runs.refined.measured_sd_rad = {0.3, 0.41};
  const std::string text = held_out_free_run_text(runs);
  EXPECT_TRUE(has(text,
                  "warning: the LSMI free run misses q2 by more than the measured angle's "
                  "own spread"))
      << text;
  EXPECT_FALSE(has(text, "output-error free run")) << text;
}

// Before: a run with NaN results had no red box.
TEST(ReportClaims, AnEstimateThatIsNotANumberMarksTheRunFailed) {
  ReportInput in = minimal_input();
  EXPECT_FALSE(has(all_warnings(in), "not a finite number"));
  in.combined.estimate.mu1 = std::numeric_limits<double>::quiet_NaN();
  in.per_experiment[0].std_dev.fv2 = std::numeric_limits<double>::infinity();
  const std::string warnings = all_warnings(in);
  EXPECT_TRUE(has(warnings,
                  "failed: LSMI on all experiments: no estimate: mu1 not a finite "
                  "number"))
      << warnings;
  EXPECT_TRUE(has(warnings, "failed: LSMI on run1: no estimate: fv2 not a finite number"))
      << warnings;
  EXPECT_TRUE(has(render_html(in), "<li class=\"failed\">"));
  OutputErrorSummary oe;
  oe.estimate = minimal_input().combined.estimate;
  oe.std_dev = minimal_input().combined.std_dev;
  oe.estimate.mug = std::numeric_limits<double>::quiet_NaN();
  in = minimal_input();
  in.output_error = oe;
  EXPECT_TRUE(has(all_warnings(in), "failed: the output-error refinement: no estimate: mug"))
      << all_warnings(in);
}

}  // namespace
}  // namespace furuta::report::claims_test
