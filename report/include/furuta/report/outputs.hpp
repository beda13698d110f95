#pragma once
// Every file of an identification or a simulation, written from the pipeline's numbers
// (report/README.md lists them).
//
//   const pipeline::Run run = pipeline::run(batch, settings);
//   report::write_identification(dir, run, "furuta 0.1.0");
//   std::cout << report::terminal_text(run);

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "furuta/pipeline/pipeline.hpp"
#include "furuta/validated/scenarios.hpp"

namespace furuta::report {

// results.json, table.txt, signals_<n>.svg, torque_validation.svg (held out), report.html; with
// SIVIA sivia.json, sivia.svg (Fig. 4), paving.json; with the scenarios table3.txt,
// scenario_<n>_<set>.svg (Fig. 6), tubes.json. `dir` is created. std::runtime_error when a file
// cannot be written.
void write_identification(const std::filesystem::path& dir, const pipeline::Run& run,
                          const std::string& software_version);

// `furuta simulate`'s files: simulate.json ({"software_version", "parameters_from" when given,
// "simulation"}), table3.txt, tubes.json and the figures. Returns the figures' file names.
std::vector<std::string> write_simulation(const std::filesystem::path& dir,
                                          const pipeline::Simulation& simulation,
                                          const std::string& software_version,
                                          const std::optional<std::string>& parameters_from);

// Fig. 6's file name: "scenario_1_lsmi.svg", "scenario_1_truth_pm0p001pct.svg".
std::string scenario_figure_name(const validated::ScenarioResult& result);

// Writes text to a file (binary, whole); std::runtime_error when it cannot.
void write_text_file(const std::filesystem::path& path, const std::string& text);

}  // namespace furuta::report
