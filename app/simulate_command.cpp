// `furuta simulate`: the paper's validation by guaranteed simulation (section IV.B): the four
// scenarios measured on the simulated rig, tubes from point (LSMI) and interval (SIVIA)
// parameters, coverage rates (Table III) and Fig. 6-style figures: pipeline::simulate, then the
// report's writers. `furuta identify --simulate` runs the same after its fit.
#include <unistd.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <ostream>
#include <sstream>

#include "commands.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/pipeline/pipeline.hpp"
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

// --- results.json of `furuta identify` ---

class ResultsFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

double finite_number(const nlohmann::json& object, const std::string& key,
                     const std::string& where) {
  const auto it = object.find(key);
  if (it == object.end()) throw ResultsFileError(where + "." + key + ": missing");
  if (!it->is_number() || !std::isfinite(it->get<double>())) {
    throw ResultsFileError(where + "." + key + ": not a finite number");
  }
  return it->get<double>();
}

model::Parameters<double> parameters_from(const nlohmann::json& object, const std::string& where) {
  if (!object.is_object()) throw ResultsFileError(where + ": not an object");
  model::Parameters<double> p;
  p.mu1 = finite_number(object, "mu1", where);
  p.mu2 = finite_number(object, "mu2", where);
  p.mu3 = finite_number(object, "mu3", where);
  p.mu4 = finite_number(object, "mu4", where);
  p.mug = finite_number(object, "mug", where);
  p.fv1 = finite_number(object, "fv1", where);
  p.fv2 = finite_number(object, "fv2", where);
  return p;
}

struct ResultsParameters {
  // LSMI's point estimate, or for a recording too short for LSMI the refinement's (converged).
  std::optional<model::Parameters<double>> lsmi;
  std::optional<model::Parameters<double>> output_error;
  std::optional<model::Parameters<double>> truth;
  std::optional<model::Parameters<furuta::interval::Interval>> sivia;
  std::string note;  // why there is no SIVIA set, when there is none
};

// The SIVIA outer hull by parameter name: the carried mu's come out as their prior (the LSMI
// estimate +- Table II %), the frictions as the paving's hull.
model::Parameters<furuta::interval::Interval> sivia_hull(const nlohmann::json& sivia) {
  const auto names = sivia.find("parameters");
  const auto hull = sivia.find("outer_hull");
  if (names == sivia.end() || !names->is_array()) {
    throw ResultsFileError("sivia.parameters: missing");
  }
  if (hull == sivia.end() || !hull->is_array() || hull->size() != names->size()) {
    throw ResultsFileError("sivia.outer_hull: missing or not one interval per parameter");
  }
  model::Parameters<furuta::interval::Interval> p;
  const std::array<std::pair<const char*, interval::Interval*>, 7> slots = {{{"mu1", &p.mu1},
                                                                             {"mu2", &p.mu2},
                                                                             {"mu3", &p.mu3},
                                                                             {"mu4", &p.mu4},
                                                                             {"mug", &p.mug},
                                                                             {"fv1", &p.fv1},
                                                                             {"fv2", &p.fv2}}};
  for (const auto& [name, slot] : slots) {
    bool found = false;
    for (std::size_t k = 0; k < names->size(); ++k) {
      if (!(*names)[k].is_string() || (*names)[k].get<std::string>() != name) continue;
      const nlohmann::json& iv = (*hull)[k];
      const std::string where =
          std::string("sivia.outer_hull[") + std::to_string(k) + "] (" + name + ")";
      if (!iv.is_array() || iv.size() != 2 || !iv[0].is_number() || !iv[1].is_number()) {
        throw ResultsFileError(where + ": not an interval [lo, hi]");
      }
      const double lo = iv[0].get<double>(), hi = iv[1].get<double>();
      if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi) {
        throw ResultsFileError(where + ": not a bounded interval");
      }
      *slot = interval::Interval(lo, hi);
      found = true;
    }
    if (!found) throw ResultsFileError(std::string("sivia.parameters: no ") + name);
  }
  return p;
}

ResultsParameters read_results(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ResultsFileError("cannot open");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw ResultsFileError(std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object()) throw ResultsFileError("not a JSON object");
  ResultsParameters r;
  const auto combined = j.find("combined");
  if (combined != j.end()) {
    if (!combined->is_object() || !combined->contains("estimate")) {
      throw ResultsFileError("combined.estimate: missing");
    }
    r.lsmi = parameters_from((*combined)["estimate"], "combined.estimate");
  }
  const auto refined = j.find("output_error");
  if (!r.lsmi && refined != j.end() && refined->is_object() && refined->value("converged", false)) {
    if (!refined->contains("estimate")) throw ResultsFileError("output_error.estimate: missing");
    r.output_error = parameters_from((*refined)["estimate"], "output_error.estimate");
  }
  if (!r.lsmi && !r.output_error) {
    throw ResultsFileError(
        "no estimate: neither combined.estimate (LSMI) nor a converged output_error.estimate (not "
        "a results.json of furuta identify?)");
  }
  if (j.contains("truth")) r.truth = parameters_from(j["truth"], "truth");
  const auto sivia = j.find("sivia");
  if (sivia == j.end()) {
    r.note = "no SIVIA in it (furuta identify --sivia): point parameters only";
  } else if (!sivia->is_object()) {
    throw ResultsFileError("sivia: not an object");
  } else if (sivia->contains("skipped")) {
    r.note = "SIVIA did not run: point parameters only";
  } else if (sivia->value("empty", false)) {
    r.note = "SIVIA found no consistent parameter: point parameters only";
  } else {
    r.sivia = sivia_hull(*sivia);
  }
  return r;
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
    err << "furuta simulate: --seconds " << *options.seconds << ": expected in (0, 60]\n";
    return 2;
  }
  if (options.pieces == 0 || options.pieces > 64 || (options.pieces & (options.pieces - 1)) != 0) {
    err << "furuta simulate: --pieces " << options.pieces
        << ": expected 1, 2, 4, 8, 16, 32 or 64 (the split is a bisection)\n";
    return 2;
  }
  // Before the tubes, which may take long: a directory it may not replace is refused at once.
  if (const auto problem = report::output_directory_problem(options.output_dir)) {
    err << "furuta simulate: -o " << options.output_dir.string() << ": " << *problem << "\n";
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
    ResultsParameters r;
    try {
      r = read_results(options.results);
    } catch (const ResultsFileError& e) {
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
    if (r.output_error) {
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

  TerminalProgress progress;  // only on a terminal: logs and CI stay quiet
  const pipeline::Simulation simulation =
      pipeline::simulate(scenarios, sets, truth, source, options.pieces,
                         ::isatty(STDERR_FILENO) == 1 ? &progress : nullptr);
  std::vector<std::string> figures;
  bool replaced = false;
  try {
    report::RunDirectory dir(options.output_dir);
    figures = report::write_simulation(
        dir.staging(), simulation, daemon::kSoftwareVersion,
        options.results.empty() ? std::nullopt : std::optional(options.results.string()));
    replaced = dir.commit();
  } catch (const report::OutputDirectoryError& e) {
    err << "furuta simulate: -o " << options.output_dir.string() << ": " << e.what() << "\n";
    return 2;
  }
  out << note << report::format_table_three(simulation.results);
  out << "wrote " << (options.output_dir / "simulate.json").string() << ", table3.txt and "
      << figures.size() << " figures in " << options.output_dir.string() << "\n";
  if (replaced)
    out << "(the previous run's files in " << options.output_dir.string() << " were replaced)\n";
  return 0;
}

}  // namespace furuta::app
