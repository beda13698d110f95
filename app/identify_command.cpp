// `furuta identify LOG... [--validate LOG]` and `furuta identify --csv FILE... --import-spec SPEC
// [--validate FILE.csv]`: LSMI on session logs or CSV recordings, Table I, results.json, figures.
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <ostream>
#include <sstream>

#include "commands.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/identification/csv_import.hpp"
#include "furuta/identification/guaranteed.hpp"
#include "furuta/identification/identify.hpp"
#include "furuta/report/json.hpp"
#include "furuta/report/report.hpp"
#include "furuta/report/svg.hpp"
#include "furuta/report/tables.hpp"
#include "furuta/session_log/session_log.hpp"

namespace furuta::app {

namespace {

void write_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

// A CSV recording rather than a session log: decided by the name alone, as the user sees it.
bool is_csv(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".csv";
}

// What the fit needs besides the experiments, whichever kind of input they came from.
struct FitInputs {
  std::vector<identification::RawExperiment> experiments;
  std::optional<identification::RawExperiment> validation;
  config::RigConfig settings;  // [identification] and the motor for eq. 4
  std::optional<model::Parameters<double>> nominal, truth;
  identification::VoltageMotor voltage_motor;
  double angle_resolution_rad = 0;               // the signals figures' quantisation band
  std::vector<report::SessionSummary> sessions;  // session logs only, for the report
};

struct GuaranteedRun {
  report::Json json;
  std::string svg, summary;
  std::optional<interval::Box> outer_hull;  // absent when the set is empty
  identification::GuaranteedResult result;
};

// A configuration without [sivia] bounds leaves them all 0: no data boxes to draw.
bool has_bounds(const config::SiviaConfig& cfg) {
  for (const auto* b : {&cfg.q2_bound, &cfg.dq1_bound, &cfg.dq2_bound, &cfg.ddq1_bound,
                        &cfg.ddq2_bound, &cfg.tau_bound}) {
    if ((*b)[0] > 0 || (*b)[1] > 0) return true;
  }
  return false;
}

// [sivia]'s bounds on the preprocessed data: SIVIA's data boxes, and the bands of Fig. 2/3.
identification::DataErrorBounds data_error_bounds(const config::SiviaConfig& cfg) {
  const auto bound = [](const std::array<double, 2>& b) {
    return identification::ChannelErrorBound{b[0], b[1]};
  };
  identification::DataErrorBounds bounds;
  bounds.q2 = bound(cfg.q2_bound);
  bounds.dq1 = bound(cfg.dq1_bound);
  bounds.dq2 = bound(cfg.dq2_bound);
  bounds.ddq1 = bound(cfg.ddq1_bound);
  bounds.ddq2 = bound(cfg.ddq2_bound);
  bounds.tau = bound(cfg.tau_bound);
  return bounds;
}

identification::InnerTest inner_test(config::SiviaInnerTest test) {
  using identification::InnerTest;
  switch (test) {
    case config::SiviaInnerTest::witness:
      return InnerTest::witness;
    case config::SiviaInnerTest::intermediate_value:
      return InnerTest::intermediate_value;
    case config::SiviaInnerTest::for_all_data:
      return InnerTest::for_all_data;
    case config::SiviaInnerTest::none:
      break;
  }
  return InnerTest::none;
}

// SIVIA over the fitted sessions: the mu's around the combined LSMI estimate (Table II style), the
// frictions' priors, the data bounds and the paver settings from [sivia].
GuaranteedRun run_guaranteed(const config::SiviaConfig& cfg,
                             const identification::Identification& id,
                             const identification::IdentifyOptions& identify_options,
                             const IdentifyCommandOptions& options,
                             const std::optional<model::Parameters<double>>& truth) {
  using namespace identification;
  GuaranteedOptions g;
  g.prior = paper_prior(id.combined.estimate, cfg.mu_uncertainty_pct, 1.0);
  g.prior[5] = interval::Interval(cfg.fv1_prior[0], cfg.fv1_prior[1]);
  g.prior[6] = interval::Interval(cfg.fv2_prior[0], cfg.fv2_prior[1]);
  g.unknown.fill(false);
  for (const std::string& name : cfg.unknowns) {
    for (std::size_t k = 0; k < model::kParameterCount; ++k) {
      if (name == model::kParameterNames[k]) g.unknown[k] = true;
    }
  }
  g.epsilon = cfg.epsilon;
  g.epsilon_relative = cfg.epsilon_relative;
  g.contract = cfg.contract;
  g.inner = inner_test(cfg.inner_test);
  g.q = cfg.q;
  g.threads = options.threads.value_or(cfg.threads);
  // Progress only on a terminal: logs and CI stay quiet.
  const bool tty = ::isatty(STDERR_FILENO) == 1;
  if (tty) {
    g.progress = [](std::size_t tested, std::size_t pending) {
      std::fprintf(stderr, "\rSIVIA: %zu boxes tested, %zu pending   ", tested, pending);
      std::fflush(stderr);
    };
  }
  const DataErrorBounds bounds = data_error_bounds(cfg);
  std::vector<const JointSeries*> series;
  for (const JointSeries& s : id.processed) series.push_back(&s);
  const std::size_t trim = identify_options.lsmi.trim_samples != 0
                               ? identify_options.lsmi.trim_samples
                               : edge_samples(identify_options.preprocess);
  const std::vector<IntervalSample> samples = interval_samples(series, bounds, trim);
  const SampleConstraints constraints(samples, g.prior, g.unknown);
  const GuaranteedResult r = guaranteed_identification(constraints, g);
  if (tty) std::fprintf(stderr, "\n");

  GuaranteedRun run;
  run.json = report::sivia_json(r, samples);
  std::vector<double> reference;
  if (truth) {
    const auto t = truth->to_array();
    reference.assign(t.begin(), t.end());
  }
  run.svg = report::svg_paving(r, 5, 6, truth ? &reference : nullptr);
  if (!r.empty) run.outer_hull = r.paving.outer_hull();
  run.summary = report::sivia_summary_text(r, truth);
  run.result = r;
  return run;
}

struct SimulationRun {
  report::Json json;
  std::string summary;
  std::string source;  // of the measurements
  std::vector<validated::ScenarioResult> results;
};

// The paper's scenarios with the fitted parameters: the LSMI estimate as points and, when SIVIA
// ran and found a set, its outer hull (the carried mu's as their Table II intervals). The
// measurements come from the simulated rig: the truth when the sessions were simulated, else the
// configuration's simulated-rig parameters.
SimulationRun run_simulation(const identification::Identification& id,
                             const std::optional<interval::Box>& sivia_hull,
                             const IdentifyCommandOptions& options, const FitInputs& fit) {
  std::vector<validated::ParameterSet> sets;
  if (sivia_hull) {
    const interval::Box& h = *sivia_hull;
    sets.push_back({"SIVIA", model::Parameters<furuta::interval::Interval>{h[0], h[1], h[2], h[3],
                                                                           h[4], h[5], h[6]}});
  }
  sets.push_back(validated::point_parameters("LSMI", id.combined.estimate));
  std::vector<validated::Scenario> scenarios = validated::paper_scenarios();
  if (options.simulate_seconds) {
    for (validated::Scenario& s : scenarios) s.duration_s = *options.simulate_seconds;
  }
  const model::Parameters<double> truth = fit.truth.value_or(fit.settings.simulation.parameters);
  const std::string source = fit.truth ? "the simulated sessions' truth"
                                       : "the configuration's simulated rig (the sessions carry "
                                         "no truth)";
  const SimulationReport report =
      run_scenario_simulations(scenarios, sets, truth, options.output_dir, source);
  write_file(options.output_dir / "table3.txt", report.table);
  SimulationRun run;
  run.json = report.json;
  run.source = source;
  run.results = report.results;
  run.summary = report::simulation_summary_text(source, options.sivia && !sivia_hull, run.results);
  return run;
}

// The HTML report's content: what this run computed, and what it did not (null: not run).
report::ReportInput report_page(const identification::Identification& id, const FitInputs& fit,
                                const identification::IdentifyOptions& identify_options,
                                const std::vector<identification::InputFile>& inputs,
                                const std::vector<std::string>& signals_svg, bool bounds_configured,
                                const GuaranteedRun* guaranteed, const SimulationRun* simulation) {
  report::ReportInput page = report::report_input(id);
  page.software_version = daemon::kSoftwareVersion;
  const auto number = [](double v, const char* unit) {
    std::ostringstream s;
    s << v << " " << unit;
    return s.str();
  };
  page.rig = {{"configuration", fit.settings.name.empty() ? "-" : fit.settings.name},
              {"inputs", fit.sessions.empty() ? "CSV recordings" : "session logs"},
              {"sample period", number(id.processed.front().sample_period_s * 1e3, "ms")},
              {"low-pass cut-off", number(identify_options.preprocess.cutoff_hz, "Hz")}};
  if (fit.truth) page.rig.push_back({"rig", "simulated (its true parameters are known)"});
  page.sessions = fit.sessions;
  for (const auto& file : inputs) page.inputs.push_back(file.path);
  page.signals_svg = signals_svg;
  page.signals_bands = bounds_configured
                           ? "the bands are the data error bounds of [sivia] (SIVIA's data boxes)"
                           : "the band is the pendulum encoder's quantisation";
  page.table_two = report::table_two(id.combined.estimate, fit.settings.sivia,
                                     guaranteed ? &guaranteed->result : nullptr);
  if (guaranteed) page.sivia = report::sivia_summary(guaranteed->result, guaranteed->svg);
  if (simulation) {
    page.simulation = report::SimulationSummary{simulation->source, simulation->results};
  }
  return page;
}

// Session logs: the rig is the one the first log carries, unless --config gives one.
std::optional<FitInputs> inputs_from_logs(const IdentifyCommandOptions& options,
                                          std::ostream& err) {
  std::vector<session_log::SessionLog> logs;
  for (const auto& path : options.logs) logs.push_back(session_log::load_session_log(path));
  if (!logs.front().start && options.config_path.empty()) {
    err << "furuta identify: " << options.logs.front().string()
        << " has no session start record (and so no configuration); pass --config\n";
    return std::nullopt;
  }
  FitInputs in;
  in.settings =
      options.config_path.empty()
          ? config::parse_rig_config(logs.front().start->rig_config_toml,
                                     options.logs.front().string() + " (rig configuration)")
          : config::load_rig_config(options.config_path);
  for (const auto& log : logs) {
    in.experiments.push_back(identification::experiment_from_log(log));
    in.sessions.push_back(report::summarize_session(log, "fit"));
  }
  if (!options.validate.empty()) {
    const session_log::SessionLog held_out = session_log::load_session_log(options.validate);
    in.validation = identification::experiment_from_log(held_out);
    in.sessions.push_back(report::summarize_session(held_out, "held out"));
  }
  in.nominal = in.settings.nominal;
  if (in.settings.backend == config::UsbBackend::simulated) {
    in.truth = in.settings.simulation.parameters;
  }
  in.angle_resolution_rad = bridge::resolution_rad(in.settings.pendulum_encoder);
  return in;
}

// CSV recordings, mapped by the import spec. The rig configuration is optional: duty input needs
// its motor (eq. 4); voltage input has its motor in the spec's [motor], torque input needs none.
std::optional<FitInputs> inputs_from_csvs(const IdentifyCommandOptions& options,
                                          std::ostream& err) {
  const identification::CsvImportSpec spec =
      identification::load_csv_import_spec(options.import_spec);
  FitInputs in;
  if (!options.config_path.empty()) {
    in.settings = config::load_rig_config(options.config_path);
    in.nominal = in.settings.nominal;  // no truth: the simulation is not where the CSVs came from
  } else if (spec.input_kind == identification::InputKind::duty) {
    err << "furuta identify: " << options.import_spec.string()
        << ": input_kind = \"duty\" needs the rig's motor data (eq. 4): pass --config RIG.toml\n";
    return std::nullopt;
  }
  // The configuration's input lag is the daemon's data path; another logger's is unknown, so 0
  // unless the command gives one (or asks for it to be estimated).
  in.settings.identification.input_lag_ms = 0.0;
  if (spec.voltage_motor) in.voltage_motor = *spec.voltage_motor;
  const auto load = [&](const std::filesystem::path& path) {
    return identification::experiment_from_csv(identification::import_csv(path, spec),
                                               path.filename().string());
  };
  for (const auto& path : options.csvs) in.experiments.push_back(load(path));
  if (!options.validate.empty()) in.validation = load(options.validate);
  if (spec.angle_unit == identification::AngleUnit::counts) {
    in.angle_resolution_rad = 2 * std::numbers::pi / spec.pendulum_counts_per_rev;
  }

  // The differentiator's stop band (twice the cut-off) must fit below every file's Nyquist
  // frequency; a recording slower than the rig's loop needs a lower cut-off than its default.
  const double cutoff_hz = options.cutoff_hz.value_or(in.settings.identification.cutoff_hz);
  std::vector<const identification::RawExperiment*> all;
  for (const auto& e : in.experiments) all.push_back(&e);
  if (in.validation) all.push_back(&*in.validation);
  for (const auto* e : all) {
    const double nyquist_hz = 0.5 / e->sample_period_s;
    if (!(2 * cutoff_hz < nyquist_hz)) {
      err << "furuta identify: " << e->name << ": the cut-off " << cutoff_hz
          << " Hz puts the differentiator's stop band (" << 2 * cutoff_hz
          << " Hz) above the Nyquist frequency " << nyquist_hz << " Hz; pass --cutoff below "
          << nyquist_hz / 2 << "\n";
      return std::nullopt;
    }
  }
  return in;
}

}  // namespace

identification::IdentifyOptions identify_options_for(const config::RigConfig& rig,
                                                     const IdentifyCommandOptions& options) {
  identification::IdentifyOptions identify_options;
  const double cutoff_hz = options.cutoff_hz.value_or(rig.identification.cutoff_hz);
  identify_options.preprocess.cutoff_hz = cutoff_hz;
  identify_options.preprocess.differentiator_passband_hz = cutoff_hz;
  identify_options.preprocess.differentiator_stopband_hz = 2 * cutoff_hz;
  identify_options.preprocess.butterworth_order = rig.identification.butterworth_order;
  identify_options.preprocess.differentiator_taps = rig.identification.differentiator_taps;
  const std::optional<double> lag_ms =
      options.estimate_input_lag
          ? std::nullopt
          : (options.input_lag_ms ? options.input_lag_ms : rig.identification.input_lag_ms);
  identify_options.estimate_input_lag = !lag_ms.has_value();
  identify_options.preprocess.input_lag_s = lag_ms.value_or(0.0) * 1e-3;
  return identify_options;
}

int run_identify_command(const IdentifyCommandOptions& options, std::ostream& out,
                         std::ostream& err) {
  if (options.logs.empty() && options.csvs.empty()) {
    err << "furuta identify: give at least one session log, or --csv FILE with --import-spec "
           "SPEC\n";
    return 2;
  }
  for (const auto& path : options.logs) {
    if (is_csv(path)) {
      err << "furuta identify: " << path.string()
          << " is a CSV file: pass it as --csv FILE, with --import-spec SPEC\n";
      return 2;
    }
  }
  const bool csv_input = !options.csvs.empty();
  if (csv_input && !options.logs.empty()) {
    err << "furuta identify: session logs and CSV files are fitted together as one rig; give "
           "one kind\n";
    return 2;
  }
  if (!options.validate.empty() && is_csv(options.validate) != csv_input) {
    err << "furuta identify: the held-out " << options.validate.string() << " is "
        << (csv_input ? "not a CSV file" : "a CSV file") << " but the fitted inputs are "
        << (csv_input ? "CSV files" : "session logs") << "; validate on the same kind\n";
    return 2;
  }
  if (csv_input && options.import_spec.empty()) {
    err << "furuta identify: --csv needs --import-spec SPEC (the columns, units and conventions; "
           "see identification/README.md)\n";
    return 2;
  }
  if (!csv_input && !options.import_spec.empty()) {
    err << "furuta identify: --import-spec applies to --csv inputs only\n";
    return 2;
  }

  std::optional<FitInputs> fit;
  try {
    fit = csv_input ? inputs_from_csvs(options, err) : inputs_from_logs(options, err);
  } catch (const config::ConfigError& e) {  // the import spec or the rig configuration
    err << "furuta identify: " << e.what() << "\n";
    return 2;
  } catch (const identification::CsvImportError& e) {
    err << "furuta identify: " << e.what() << "\n";
    return 2;
  }
  if (!fit) return 2;

  const identification::IdentifyOptions identify_options =
      identify_options_for(fit->settings, options);
  identification::Identification id = identification::identify(
      fit->experiments, fit->validation, identify_options, fit->settings.motor, fit->voltage_motor);
  if (fit->nominal) id.nominal = *fit->nominal;
  if (fit->truth) id.truth = *fit->truth;

  std::filesystem::create_directories(options.output_dir);
  std::vector<identification::InputFile> inputs;
  const auto add_input = [&](const std::filesystem::path& path) {
    inputs.push_back({path.string(), identification::sha256_file(path.string())});
  };
  for (const auto& path : options.logs) add_input(path);
  for (const auto& path : options.csvs) add_input(path);
  if (!options.validate.empty()) add_input(options.validate);
  if (csv_input) add_input(options.import_spec);
  const std::string table = report::format_table_one(id);
  write_file(options.output_dir / "table.txt", table);
  report::Json more = report::Json::object();
  std::string sivia_summary;
  std::optional<interval::Box> guaranteed_hull;
  std::optional<GuaranteedRun> guaranteed;
  if (options.sivia) {
    guaranteed = run_guaranteed(fit->settings.sivia, id, identify_options, options, fit->truth);
    const GuaranteedRun& run = *guaranteed;
    more["sivia"] = run.json;
    sivia_summary = run.summary;
    guaranteed_hull = run.outer_hull;
    write_file(options.output_dir / "sivia.json", report::json_text(run.json));
    write_file(options.output_dir / "sivia.svg", run.svg);
  }
  std::string simulation_summary;
  std::optional<SimulationRun> simulation;
  if (options.simulate) {
    simulation = run_simulation(id, guaranteed_hull, options, *fit);
    more["simulation"] = simulation->json;
    simulation_summary = simulation->summary;
  }
  write_file(options.output_dir / "results.json",
             report::json_text(report::results_json(id, inputs, daemon::kSoftwareVersion, more)));
  const identification::DataErrorBounds bounds = data_error_bounds(fit->settings.sivia);
  const bool bounds_configured = has_bounds(fit->settings.sivia);
  std::vector<std::string> signals;
  for (std::size_t i = 0; i < id.processed.size(); ++i) {
    signals.push_back(report::svg_signals(id.raw[i], id.processed[i], fit->angle_resolution_rad,
                                          bounds_configured ? &bounds : nullptr));
    write_file(options.output_dir / ("signals_" + std::to_string(i + 1) + ".svg"), signals.back());
  }
  if (id.validation) {
    write_file(options.output_dir / "torque_validation.svg",
               report::svg_torque_validation(*id.validation));
  }
  const report::ReportInput page =
      report_page(id, *fit, identify_options, inputs, signals, bounds_configured,
                  guaranteed ? &*guaranteed : nullptr, simulation ? &*simulation : nullptr);
  const std::filesystem::path report_path = options.output_dir / "report.html";
  write_file(report_path, report::render_html(page));
  out << table << sivia_summary << simulation_summary;
  out << "wrote " << (options.output_dir / "results.json").string() << " and figures in "
      << options.output_dir.string() << "\n";
  out << "report: " << report_path.string() << "\n";
  return 0;
}

}  // namespace furuta::app
