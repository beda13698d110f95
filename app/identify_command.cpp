// `furuta identify LOG... [--validate LOG]` and `furuta identify --csv FILE... --import-spec SPEC
// [--validate FILE.csv]`: the recordings as a pipeline::Batch, pipeline::run, then the report's
// writers (Table I, results.json, figures, report.html).
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <numbers>
#include <ostream>

#include "commands.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/identification/csv_import.hpp"
#include "furuta/identification/identify.hpp"
#include "furuta/pipeline/pipeline.hpp"
#include "furuta/report/outputs.hpp"
#include "furuta/report/tables.hpp"
#include "furuta/session_log/session_log.hpp"
#include "terminal_progress.hpp"

namespace furuta::app {

namespace {

// A CSV recording rather than a session log: decided by the name alone, as the user sees it.
bool is_csv(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".csv";
}

// Session logs: the rig is the one the first log carries, unless --config gives one.
std::optional<pipeline::Batch> inputs_from_logs(const IdentifyCommandOptions& options,
                                                std::ostream& err) {
  std::vector<session_log::SessionLog> logs;
  for (const auto& path : options.logs) logs.push_back(session_log::load_session_log(path));
  if (!logs.front().start && options.config_path.empty()) {
    err << "furuta identify: " << options.logs.front().string()
        << " has no session start record (and so no configuration); pass --config\n";
    return std::nullopt;
  }
  pipeline::Batch in;
  in.rig = options.config_path.empty()
               ? config::parse_rig_config(logs.front().start->rig_config_toml,
                                          options.logs.front().string() + " (rig configuration)")
               : config::load_rig_config(options.config_path);
  if (options.config_path.empty()) {
    in.config_carried_by = options.logs.front();
  } else {
    in.config_file = options.config_path;
  }
  for (const auto& log : logs) in.fit.push_back(pipeline::log_recording(log, pipeline::Role::fit));
  in.files = options.logs;
  if (!options.validate.empty()) {
    in.held_out = pipeline::log_recording(session_log::load_session_log(options.validate),
                                          pipeline::Role::held_out);
    in.files.push_back(options.validate);
  }
  in.nominal = in.rig.nominal;
  if (in.rig.backend == config::UsbBackend::simulated) in.truth = in.rig.simulation.parameters;
  in.angle_resolution_rad = bridge::resolution_rad(in.rig.pendulum_encoder);
  return in;
}

// CSV recordings, mapped by the import spec. The rig configuration is optional: duty input needs
// its motor (eq. 4); voltage input has its motor in the spec's [motor], torque input needs none.
std::optional<pipeline::Batch> inputs_from_csvs(const IdentifyCommandOptions& options,
                                                std::ostream& err) {
  const identification::CsvImportSpec spec =
      identification::load_csv_import_spec(options.import_spec);
  pipeline::Batch in;
  in.kind = pipeline::InputKind::csv_recordings;
  if (!options.config_path.empty()) {
    in.rig = config::load_rig_config(options.config_path);
    in.config_file = options.config_path;
    in.nominal = in.rig.nominal;  // no truth: the simulation is not where the CSVs came from
  } else if (spec.input_kind == identification::InputKind::duty) {
    err << "furuta identify: " << options.import_spec.string()
        << ": input_kind = \"duty\" needs the rig's motor data (eq. 4): pass --config RIG.toml\n";
    return std::nullopt;
  }
  // The configuration's input lag is the daemon's data path; another logger's is unknown, so 0
  // unless the command gives one (or asks for it to be estimated).
  in.rig.identification.input_lag_ms = 0.0;
  if (spec.voltage_motor) in.voltage_motor = *spec.voltage_motor;
  const auto load = [&](const std::filesystem::path& path) {
    return identification::experiment_from_csv(identification::import_csv(path, spec),
                                               path.filename().string());
  };
  for (const auto& path : options.csvs) in.fit.push_back({load(path), std::nullopt});
  in.files = options.csvs;
  if (!options.validate.empty()) {
    in.held_out = pipeline::Recording{load(options.validate), std::nullopt};
    in.files.push_back(options.validate);
  }
  in.files.push_back(options.import_spec);
  if (spec.angle_unit == identification::AngleUnit::counts) {
    in.angle_resolution_rad = 2 * std::numbers::pi / spec.pendulum_counts_per_rev;
  }

  // The differentiator's stop band (twice the cut-off) must fit below every file's Nyquist
  // frequency; a recording slower than the rig's loop needs a lower cut-off than its default.
  const double cutoff_hz = options.cutoff_hz.value_or(in.rig.identification.cutoff_hz);
  std::vector<const identification::RawExperiment*> all;
  for (const auto& r : in.fit) all.push_back(&r.experiment);
  if (in.held_out) all.push_back(&in.held_out->experiment);
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

// Table I the moment LSMI is done (SIVIA and the scenarios can take minutes), then the terminal's
// progress lines, if any.
class IdentifyProgress : public pipeline::Progress {
 public:
  IdentifyProgress(std::ostream* table_one, pipeline::Progress* terminal)
      : table_one_(table_one), terminal_(terminal) {}
  void lsmi_done(const identification::Identification& id) override {
    if (table_one_ != nullptr) *table_one_ << report::format_table_one(id) << std::flush;
  }
  void sivia(std::size_t tested, std::size_t pending) override {
    if (terminal_ != nullptr) terminal_->sivia(tested, pending);
  }
  void sivia_done() override {
    if (terminal_ != nullptr) terminal_->sivia_done();
  }
  void scenario(const validated::Scenario& scenario, const std::string& set) override {
    if (terminal_ != nullptr) terminal_->scenario(scenario, set);
  }
  void scenarios_done() override {
    if (terminal_ != nullptr) terminal_->scenarios_done();
  }

 private:
  std::ostream* table_one_;
  pipeline::Progress* terminal_;
};

}  // namespace

identification::IdentifyOptions identify_options_for(const config::RigConfig& rig,
                                                     const IdentifyCommandOptions& options) {
  config::RigConfig overridden = rig;
  config::IdentificationConfig& c = overridden.identification;
  if (options.cutoff_hz) c.cutoff_hz = *options.cutoff_hz;
  if (options.estimate_input_lag) {
    c.input_lag_ms.reset();
  } else if (options.input_lag_ms) {
    c.input_lag_ms = options.input_lag_ms;
  }
  return pipeline::settings_for(overridden).identify;
}

pipeline::Settings identify_settings(const config::RigConfig& rig,
                                     const IdentifyCommandOptions& options) {
  pipeline::Settings settings = pipeline::settings_for(rig);
  settings.identify = identify_options_for(rig, options);
  settings.sivia.run = options.sivia;
  settings.sivia.threads = options.threads.value_or(rig.sivia.threads);
  settings.simulation.run = options.simulate;
  if (options.simulate_seconds) {
    for (validated::Scenario& s : settings.simulation.scenarios) {
      s.duration_s = *options.simulate_seconds;
    }
  }
  return settings;
}

std::optional<pipeline::Run> run_identification(const IdentifyCommandOptions& options,
                                                std::ostream& err, std::ostream* table_one) {
  if (options.logs.empty() && options.csvs.empty()) {
    err << "furuta identify: give at least one session log, or --csv FILE with --import-spec "
           "SPEC\n";
    return std::nullopt;
  }
  for (const auto& path : options.logs) {
    if (is_csv(path)) {
      err << "furuta identify: " << path.string()
          << " is a CSV file: pass it as --csv FILE, with --import-spec SPEC\n";
      return std::nullopt;
    }
  }
  const bool csv_input = !options.csvs.empty();
  if (csv_input && !options.logs.empty()) {
    err << "furuta identify: session logs and CSV files are fitted together as one rig; give "
           "one kind\n";
    return std::nullopt;
  }
  if (!options.validate.empty() && is_csv(options.validate) != csv_input) {
    err << "furuta identify: the held-out " << options.validate.string() << " is "
        << (csv_input ? "not a CSV file" : "a CSV file") << " but the fitted inputs are "
        << (csv_input ? "CSV files" : "session logs") << "; validate on the same kind\n";
    return std::nullopt;
  }
  if (csv_input && options.import_spec.empty()) {
    err << "furuta identify: --csv needs --import-spec SPEC (the columns, units and conventions; "
           "see identification/README.md)\n";
    return std::nullopt;
  }
  if (!csv_input && !options.import_spec.empty()) {
    err << "furuta identify: --import-spec applies to --csv inputs only\n";
    return std::nullopt;
  }

  std::optional<pipeline::Batch> batch;
  try {
    batch = csv_input ? inputs_from_csvs(options, err) : inputs_from_logs(options, err);
  } catch (const config::ConfigError& e) {  // the import spec or the rig configuration
    err << "furuta identify: " << e.what() << "\n";
    return std::nullopt;
  } catch (const identification::CsvImportError& e) {
    err << "furuta identify: " << e.what() << "\n";
    return std::nullopt;
  }
  if (!batch) return std::nullopt;
  // Progress only on a terminal: logs and CI stay quiet.
  TerminalProgress terminal;
  const bool tty = ::isatty(STDERR_FILENO) == 1;
  IdentifyProgress progress(table_one, tty ? &terminal : nullptr);
  return pipeline::run(*batch, identify_settings(batch->rig, options), &progress);
}

void print_identification(std::ostream& out, const pipeline::Run& run,
                          const std::filesystem::path& dir, bool table_one_printed) {
  out << (table_one_printed ? report::terminal_text_after_lsmi(run) : report::terminal_text(run));
  out << "wrote " << (dir / "results.json").string() << " and figures in " << dir.string() << "\n";
  out << "report: " << (dir / "report.html").string() << "\n";
}

int run_identify_command(const IdentifyCommandOptions& options, std::ostream& out,
                         std::ostream& err) {
  const std::optional<pipeline::Run> run = run_identification(options, err, &out);
  if (!run) return 2;
  report::write_identification(options.output_dir, *run, daemon::kSoftwareVersion);
  print_identification(out, *run, options.output_dir, true);
  return 0;
}

}  // namespace furuta::app
