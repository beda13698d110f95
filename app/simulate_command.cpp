// `furuta simulate`: the paper's validation by guaranteed simulation (section IV.B): the four
// scenarios measured on the simulated rig, tubes from point (LSMI) and interval (SIVIA)
// parameters, coverage rates (Table III) and Fig. 6-style figures: pipeline::simulate, then the
// report's writers. `furuta identify --simulate` runs the same after its fit.
#include <unistd.h>

#include <ostream>
#include <sstream>

#include "commands.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/pipeline/pipeline.hpp"
#include "furuta/report/json.hpp"
#include "furuta/report/outputs.hpp"
#include "furuta/report/run_directory.hpp"
#include "furuta/report/tables.hpp"
#include "terminal_progress.hpp"

namespace furuta::app {

namespace {

std::string percent_text(double pct) {
  std::ostringstream s;
  s << pct;
  return s.str();
}

}  // namespace

int run_simulate_command(const SimulateCommandOptions& options, std::ostream& out,
                         std::ostream& err) {
  if (!options.results.empty() && options.truth) {
    err << "furuta simulate: --results and --truth choose the parameters two ways; give one\n";
    return 2;
  }
  if (options.relative_pct && !options.results.empty()) {
    err << "furuta simulate: --relative widens the truth (--truth); with --results the interval "
           "parameters are SIVIA's\n";
    return 2;
  }
  if (options.relative_pct && !(*options.relative_pct > 0 && *options.relative_pct < 100)) {
    err << "furuta simulate: --relative " << *options.relative_pct
        << ": a percentage in (0, 100) expected\n";
    return 2;
  }
  if (options.seconds && !(*options.seconds > 0 && *options.seconds <= 60)) {
    err << "furuta simulate: --scenario-seconds " << *options.seconds << ": expected in (0, 60]\n";
    return 2;
  }
  if (options.pieces == 0 || options.pieces > 64 || (options.pieces & (options.pieces - 1)) != 0) {
    err << "furuta simulate: --pieces " << options.pieces
        << ": expected 1, 2, 4, 8, 16, 32 or 64 (the split is a bisection)\n";
    return 2;
  }
  if (options.output_dir.empty()) {
    err << "furuta simulate: -o is empty: give the directory for the run's files\n";
    return 2;
  }
  // The run replaces its directory whole: results.json read from it would be deleted.
  if (report::input_in_the_way(options.output_dir, {options.results})) {
    err << "furuta simulate: -o " << options.output_dir.string() << " would overwrite the input "
        << options.results.string()
        << " (the output directory is replaced whole): give another -o\n";
    return 2;
  }
  std::vector<validated::Scenario> scenarios;
  for (const int n : options.scenarios) {
    if (n < 1 || n > 4) {
      err << "furuta simulate: --scenario " << n << ": the paper's scenarios are 1 to 4\n";
      return 2;
    }
    scenarios.push_back(validated::paper_scenario(n));
  }
  if (scenarios.empty()) scenarios = validated::paper_scenarios();
  if (options.seconds) {
    for (validated::Scenario& s : scenarios) s.duration_s = *options.seconds;
  }

  std::vector<validated::ParameterSet> sets;
  model::Parameters<double> truth = model::paper_run1();
  pipeline::MeasurementSource source;  // the simulated rig's default
  std::string note;
  if (!options.results.empty()) {
    report::ResultsFile r;
    try {
      r = report::read_results(options.results);
    } catch (const report::ResultsFileError& e) {
      err << "furuta simulate: " << options.results.string() << ": " << e.what() << "\n";
      return 2;
    }
    if (r.truth) {
      truth = *r.truth;
      source = {pipeline::MeasurementSource::Kind::results_truth, options.results.string()};
    } else {
      note = options.results.string() + " has no truth (not a simulated rig): the measurements " +
             "come from " + report::measurement_source_text(source) + "\n";
    }
    if (r.sivia) sets.push_back({"SIVIA", *r.sivia});
    if (r.lsmi) sets.push_back(validated::point_parameters("LSMI", *r.lsmi));
    // The refinement's tube only where LSMI did not run: with both, the simulation is LSMI's.
    if (r.output_error && !r.lsmi) {
      sets.push_back(validated::point_parameters(pipeline::kOutputErrorSetName, *r.output_error));
    }
    if (!r.note.empty()) note += options.results.string() + ": " + r.note + "\n";
  } else {
    if (options.relative_pct) {
      sets.push_back({"truth+-" + percent_text(*options.relative_pct) + "%",
                      validated::parameters_around(truth, *options.relative_pct / 100)});
    }
    sets.push_back(validated::point_parameters("truth", truth));
  }

  std::optional<pipeline::Simulation> simulation;
  std::vector<std::string> figures;
  bool replaced = false;
  try {
    // Before the tubes, which may take long: a directory it may not replace or cannot write, or
    // one another run is writing, is refused at once. Held until the files are in place.
    report::RunDirectory dir(options.output_dir);
    TerminalProgress progress;  // only on a terminal: logs and CI stay quiet
    simulation = pipeline::simulate(scenarios, sets, truth, source, options.pieces,
                                    ::isatty(STDERR_FILENO) == 1 ? &progress : nullptr);
    figures = report::write_simulation(
        dir.staging(), *simulation, daemon::kSoftwareVersion,
        options.results.empty() ? std::nullopt : std::optional(options.results.string()));
    replaced = dir.commit();
  } catch (const report::OutputDirectoryError& e) {
    err << "furuta simulate: -o " << options.output_dir.string() << ": " << e.what() << "\n";
    return 2;
  }
  out << note << report::format_table_three(simulation->results);
  out << "wrote " << (options.output_dir / "simulate.json").string() << ", table3.txt and "
      << figures.size() << " figures in " << options.output_dir.string() << "\n";
  if (replaced)
    out << "(the previous run's files in " << options.output_dir.string() << " were replaced)\n";
  return 0;
}

}  // namespace furuta::app
