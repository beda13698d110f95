#pragma once
// The machine-readable outputs as JSON values (nlohmann::ordered_json: the keys stay in the order
// they are written) and their text. results.json, sivia.json and simulate.json keep the layout
// they always had; report/README.md lists the files.
//
//   write(dir / "results.json", json_text(results_json(run, "furuta 0.1.0")));

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "furuta/identification/guaranteed.hpp"
#include "furuta/identification/identify.hpp"
#include "furuta/model/model.hpp"
#include "furuta/pipeline/pipeline.hpp"
#include "furuta/validated/scenarios.hpp"

namespace furuta::report {

using Json = nlohmann::ordered_json;

// A document's text: the top-level members one per line (and, to `expanded_levels` levels, the
// members of the containers below that hold containers), every value below that on one line ({"a":
// 1, "b": [1, 2]}), numbers in the shortest form that reads back as the same double, NaN and
// infinities as null (JSON has neither), strings UTF-8 (invalid bytes replaced). Ends with a
// newline.
std::string json_text(const Json& document, int expanded_levels = 1);
// One value on one line, as inside json_text.
std::string json_line(const Json& value);

// {"mu1": ..., ..., "fv2": ...}
Json parameters_json(const model::Parameters<double>& p);
// [lo, hi], or null for an empty interval.
Json interval_json(const interval::Interval& x);
// [[lo, hi], ...] per component.
Json box_json(const interval::Box& box);

// One LSMI fit: estimate, std_dev, relative_sd, sigma_nm, condition_number, rank, rows, warnings.
Json lsmi_json(const identification::LsmiResult& r);

// results.json: software version, inputs (path, sha256), experiments, combined, input lag, CAD,
// truth, validation; `more`'s members ("sivia", "simulation") next; the warnings last.
Json results_json(const identification::Identification& id,
                  const std::vector<identification::InputFile>& inputs,
                  const std::string& software_version, const Json& more = Json::object());

// The paving (sivia.json and results.json's "sivia"): prior, unknowns, counts, time, hulls, the
// unknowns' area and every inner / boundary box (outer boxes counted only), the samples found
// inconsistent or excluding (`samples` are the data boxes SIVIA was given, by index), the finding.
Json sivia_json(const identification::GuaranteedResult& result,
                const std::vector<identification::IntervalSample>& samples);

// Table III's rows: scenario, parameters as [lo, hi], initial uncertainty, status, coverage.
Json scenarios_json(const std::vector<validated::ScenarioResult>& results);

// The scenarios with what they were measured and integrated with ("simulation" in results.json
// and simulate.json): truth, truth_source, measurement, integrator, figures (file names),
// tubes_file (tubes.json beside it), results.
Json simulation_json(const pipeline::Simulation& simulation);

// tubes.json: per scenario run (scenario, parameter set, parameters, status, components, the
// integrator's start box and torque) every piece: its start time and box, the earlier piece and
// number of steps it inherits (a split piece shares the steps before its split), and its own
// steps, each listed once: its time interval "t" [t0, t1], the box "over" the step and the box at
// its "end", one [lo, hi] per component. Every solution from a piece's start box lies in `over` at
// every t in [t0, t1] of each of its steps. docs/outputs.md says what each field promises.
Json tubes_json(const pipeline::Simulation& simulation);
// paving.json: every SIVIA box with its verdict (inner, boundary, outer when kept; inner boxes
// with the carried components where their proof fixed them, `inner_carried`), what contraction
// removed (each kept contraction's box before and after), the prior, the unknowns, the constraint
// rows and q, the data error bounds and every sample's data boxes (q2, dq1, dq2, ddq1, ddq2, tau
// as [lo, hi]). docs/outputs.md says what each field promises.
Json paving_json(const pipeline::Guaranteed& guaranteed);

// results.json's "output_error": laid out like "combined" (estimate, std_dev) plus the lag, the
// pendulum's zero offset, the input gains, the angle residuals per joint, segments, iterations,
// convergence and, with a held-out recording, both parameter sets' free-run RMSE on it.
Json output_error_json(const pipeline::OutputError& output_error);
// The windowed set inversion (identify --guaranteed): the search box and the set, scaled and at
// the rig's scale, the lag, every window with how far its flow carried it, the physical inputs
// with their sources (docs/outputs.md says what each field promises).
Json windowed_json(const pipeline::WindowedGuaranteed& windowed,
                   const std::vector<pipeline::EstimateOutsideSet>& excludes_output_error);

// results.json of a run: results_json above with "sivia" (naming paving.json in "paving_file")
// and "simulation" and "output_error" when they ran.
Json results_json(const pipeline::Run& run, const std::string& software_version);

// What a simulation or a controller's design takes back from a results.json: the point estimates
// (LSMI's, the converged refinement's), the CAD values and the truth of simulated sessions,
// SIVIA's outer hull by parameter (the carried mu's as their prior), or why there is none.
struct ResultsFile {
  std::optional<model::Parameters<double>> lsmi;
  std::optional<model::Parameters<double>> output_error;     // only when the refinement converged
  std::optional<model::Parameters<double>> output_error_sd;  // its standard deviations, if given
  std::optional<model::Parameters<double>> nominal;          // CAD ([nominal]), when it was given
  std::optional<model::Parameters<double>> truth;
  std::optional<model::Parameters<interval::Interval>> sivia;
  std::string note;  // why there is no SIVIA set, when there is none
};
// A results.json that cannot be read, naming the field ("combined.estimate.mu3: missing").
class ResultsFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
// Throws ResultsFileError.
ResultsFile read_results(const std::filesystem::path& path);

// batch.json, the trigger's record of one identification: its name, when, the logs directory,
// the fitted logs and the held-out one (null when none) with their labels.
struct BatchManifest {
  struct Log {
    std::string log;  // where the log is now, relative to the logs directory
    std::string label;
  };
  std::string identification;
  std::string identified_at;  // UTC, ISO 8601
  std::string logs_dir;
  std::vector<Log> fit;
  std::optional<Log> validation;
};
Json batch_json(const BatchManifest& batch);

}  // namespace furuta::report
