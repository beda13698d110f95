// The files of an identification and of a simulation.
#include "furuta/report/outputs.hpp"

#include <cctype>
#include <fstream>
#include <stdexcept>

#include "furuta/report/json.hpp"
#include "furuta/report/report.hpp"
#include "furuta/report/svg.hpp"
#include "furuta/report/tables.hpp"

namespace furuta::report {

namespace {

// tubes.json's layout: a line per step (document, runs, a run, its pieces, a piece, its steps).
constexpr int kTubesLevels = 6;

// The parameter set's name as a file name part: "LSMI" -> "lsmi", "truth+-1%" -> "truth_pm1pct".
std::string slug(const std::string& name) {
  std::string out;
  for (std::size_t i = 0; i < name.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(name[i]);
    if (std::isalnum(c)) {
      out += static_cast<char>(std::tolower(c));
    } else if (name.compare(i, 2, "+-") == 0) {
      out += "_pm";
      ++i;
    } else if (c == '%') {
      out += "pct";
    } else if (c == '.') {
      out += 'p';
    } else if (out.empty() || out.back() != '_') {
      out += '_';
    }
  }
  return out.empty() ? "parameters" : out;
}

void write_scenario_figures(const std::filesystem::path& dir, const pipeline::Simulation& s) {
  for (const validated::ScenarioResult& r : s.results) {
    write_text_file(dir / scenario_figure_name(r), svg_scenario(r));
  }
}

}  // namespace

void write_text_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

std::string scenario_figure_name(const validated::ScenarioResult& r) {
  return "scenario_" + std::to_string(r.scenario.number) + "_" + slug(r.parameters.name) + ".svg";
}

void write_identification(const std::filesystem::path& dir, const pipeline::Run& run,
                          const std::string& software_version) {
  std::filesystem::create_directories(dir);
  const identification::Identification& id = run.identification;
  const Json results = results_json(run, software_version);
  write_text_file(dir / "results.json", json_text(results));
  write_text_file(dir / "table.txt",
                  format_table_one(id, run.output_error ? &run.output_error->result : nullptr));
  std::string paving_svg;
  if (run.sivia) {
    std::vector<double> reference;
    if (id.truth) {
      const auto t = id.truth->to_array();
      reference.assign(t.begin(), t.end());
    }
    paving_svg = svg_paving(run.sivia->result, 5, 6, id.truth ? &reference : nullptr);
    write_text_file(dir / "sivia.json", json_text(results["sivia"]));
    write_text_file(dir / "sivia.svg", paving_svg);
    write_text_file(dir / "paving.json", json_text(paving_json(*run.sivia), 2));
  }
  if (run.simulation) {
    write_text_file(dir / "table3.txt", format_table_three(run.simulation->results));
    write_scenario_figures(dir, *run.simulation);
    write_text_file(dir / "tubes.json", json_text(tubes_json(*run.simulation), kTubesLevels));
  }
  std::vector<std::string> signals;
  for (std::size_t i = 0; i < id.processed.size(); ++i) {
    signals.push_back(svg_signals(id.raw[i], id.processed[i], run.angle_resolution_rad,
                                  run.data_bounds ? &*run.data_bounds : nullptr));
    write_text_file(dir / ("signals_" + std::to_string(i + 1) + ".svg"), signals.back());
  }
  const ReportInput page = report_page(run, software_version, signals, paving_svg);
  // The page's figures are the files': each drawn once.
  if (page.validation) write_text_file(dir / "torque_validation.svg", page.validation->svg);
  if (page.output_error && !page.output_error->svg.empty()) {
    write_text_file(dir / "free_run.svg", page.output_error->svg);
  }
  if (page.guaranteed && !page.guaranteed->set_svg.empty()) {
    write_text_file(dir / "guaranteed_set.svg", page.guaranteed->set_svg);
  }
  write_text_file(dir / "report.html", render_html(page));
}

std::vector<std::string> write_simulation(const std::filesystem::path& dir,
                                          const pipeline::Simulation& simulation,
                                          const std::string& software_version,
                                          const std::optional<std::string>& parameters_from) {
  std::filesystem::create_directories(dir);
  write_scenario_figures(dir, simulation);
  Json json;
  json["software_version"] = software_version;
  if (parameters_from) json["parameters_from"] = *parameters_from;
  json["simulation"] = simulation_json(simulation);
  write_text_file(dir / "simulate.json", json_text(json));
  write_text_file(dir / "table3.txt", format_table_three(simulation.results));
  write_text_file(dir / "tubes.json", json_text(tubes_json(simulation), kTubesLevels));
  std::vector<std::string> figures;
  for (const validated::ScenarioResult& r : simulation.results) {
    figures.push_back(scenario_figure_name(r));
  }
  return figures;
}

}  // namespace furuta::report
