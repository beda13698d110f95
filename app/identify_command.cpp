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
#include "furuta/report/run_directory.hpp"
#include "furuta/report/tables.hpp"
#include "furuta/session_log/log_integrity.hpp"
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

// Every log fitted as one rig with the first log's configuration: its motor (the torque, eq. 4) and
// encoders. A log that ran with other values would be fitted with the wrong ones, and nothing would
// show it. With --config the user names the rig for all of them.
bool same_rig_as_first(const std::vector<session_log::SessionLog>& logs,
                       const std::optional<session_log::SessionLog>& held_out,
                       const config::RigConfig& first, std::ostream& err) {
  std::vector<const session_log::SessionLog*> others;
  for (std::size_t i = 1; i < logs.size(); ++i) others.push_back(&logs[i]);
  if (held_out) others.push_back(&*held_out);
  bool same = true;
  for (const session_log::SessionLog* log : others) {
    if (!log->start) continue;  // refused elsewhere as not a session log
    const config::RigConfig rig =
        config::parse_rig_config(log->start->rig_config_toml, log->path.string());
    std::string differs;
    const auto differ = [&](bool equal, const char* section) {
      if (!equal) differs += (differs.empty() ? "" : ", ") + std::string(section);
    };
    differ(rig.motor == first.motor, "[motor]");
    differ(rig.arm_encoder == first.arm_encoder, "[encoders.arm]");
    differ(rig.pendulum_encoder == first.pendulum_encoder, "[encoders.pendulum]");
    if (differs.empty()) continue;
    err << "furuta identify: " << log->path.string() << " ran with another rig configuration than "
        << logs.front().path.string() << ": " << differs
        << " differ. Fitted together, every log would be read with the first's; identify them "
           "separately, or pass --config to name the rig for all\n";
    same = false;
  }
  return same;
}

// Session logs: the rig is the one the first log carries, unless --config gives one. A log that
// is not intact is refused (or, with --use-intact-part, cut at its gaps); one too short for the
// filters is refused, naming the file and the length needed.
std::optional<pipeline::Batch> inputs_from_logs(const IdentifyCommandOptions& options,
                                                std::ostream& err) {
  std::vector<session_log::SessionLog> logs;
  for (const auto& path : options.logs) logs.push_back(session_log::load_session_log(path));
  std::optional<session_log::SessionLog> held_out_log;
  if (!options.validate.empty()) held_out_log = session_log::load_session_log(options.validate);

  bool refused = false;
  const auto check_intact = [&](const session_log::SessionLog& log) {
    const auto problems = session_log::integrity_problems(log);
    if (problems.empty() || options.use_intact_part) return;
    const bool foreign =
        session_log::has_problem(problems, session_log::LogProblem::Kind::not_a_session_log);
    err << "furuta identify: " << log.path.string() << (foreign ? ": " : " is not intact: ")
        << session_log::describe(problems) << "\n";
    refused = true;
  };
  for (const auto& log : logs) check_intact(log);
  if (held_out_log) check_intact(*held_out_log);
  if (refused) {
    err << "furuta identify: refused: filtering and differentiating across a gap gives wrong "
           "parameters without a sign of it. Pass --use-intact-part to fit only the intact parts "
           "(each run of samples between gaps on its own), or leave the log out\n";
    return std::nullopt;
  }

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
    if (!same_rig_as_first(logs, held_out_log, in.rig, err)) return std::nullopt;
  } else {
    in.config_file = options.config_path;
  }
  const identification::IdentifyOptions identify = identify_options_for(in.rig, options);
  // The refinement needs no derivatives: with the CAD values to start from, a log too short for
  // LSMI's filters is fitted by it alone (pipeline::run).
  const bool refinement_alone =
      !options.no_output_error && in.rig.output_error.enabled && in.rig.nominal.has_value();
  const std::size_t min_samples = refinement_alone ? identification::kRefinementMinimumSamples
                                                   : identification::minimum_samples(identify);
  // Each log as one recording, or as its intact parts; nothing when it cannot be used.
  const auto recordings = [&](const session_log::SessionLog& log, pipeline::Role role) {
    std::vector<pipeline::Recording> out;
    if (options.use_intact_part && !session_log::integrity_problems(log).empty()) {
      // Runs LSMI can take; only when there is none, the shorter ones the refinement can.
      pipeline::IntactParts parts = pipeline::intact_part_recordings(
          log, role, identification::minimum_samples(identify), in.rig);
      if (parts.recordings.empty() && refinement_alone) {
        parts = pipeline::intact_part_recordings(log, role, min_samples, in.rig);
      }
      if (parts.recordings.empty()) {
        err << "furuta identify: " << parts.account << "\n";
        refused = true;
      }
      return std::move(parts.recordings);
    }
    if (log.samples.size() < 2) {
      err << "furuta identify: " << log.path.string() << ": no samples to identify ("
          << log.samples.size() << ")\n";
      refused = true;
      return out;
    }
    out.push_back(pipeline::log_recording(log, role, in.rig));
    const std::size_t samples = out.back().experiment.t_s.size();
    if (samples < min_samples) {
      err << "furuta identify: " << log.path.string() << ": "
          << identification::length_problem(out.back().experiment, identify);
      if (refinement_alone) {
        err << "; the output-error refinement alone needs " << min_samples;
      } else {
        err << " (the output-error refinement, which needs no derivatives, would fit it alone, "
            << (options.no_output_error        ? "but --no-output-error turns it off"
                : !in.rig.output_error.enabled ? "but [output_error] turns it off"
                                               : "but it starts from the CAD values and "
                                                 "the configuration has no [nominal]")
            << ")";
      }
      err << "\n";
      refused = true;
      out.clear();
    }
    return out;
  };
  for (const auto& log : logs) {
    for (auto& r : recordings(log, pipeline::Role::fit)) in.fit.push_back(std::move(r));
  }
  in.files = options.logs;
  if (held_out_log) {
    auto held_out = recordings(*held_out_log, pipeline::Role::held_out);
    if (!held_out.empty()) in.held_out = std::move(held_out.front());
    in.files.push_back(options.validate);
  }
  if (refused) return std::nullopt;
  in.nominal = in.rig.nominal;
  if (in.rig.backend == config::UsbBackend::simulated) in.truth = in.rig.simulation.parameters;
  in.angle_resolution_rad = bridge::resolution_rad(in.rig.pendulum_encoder);
  return in;
}

// A fitted recording whose input never changes gives equations without a scale: LSMI answers
// every parameter 0 +- 0, which looks like a result. Refused, naming the files and the column.
bool excited(const std::vector<pipeline::Recording>& fit, const identification::CsvImportSpec& spec,
             const IdentifyCommandOptions& options, std::ostream& err) {
  std::vector<std::string> constant;
  double value = 0;
  for (const pipeline::Recording& r : fit) {
    const std::vector<double>& u = r.experiment.input;
    const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
    if (lo != u.end() && *lo == *hi) {
      if (constant.empty()) value = *lo;
      constant.push_back(r.experiment.name);
    }
  }
  if (constant.empty()) return true;
  std::string files;
  for (const std::string& name : constant) files += (files.empty() ? "" : ", ") + name;
  const std::string column = "the input column '" + spec.input.name + "'";
  err << "furuta identify: ";
  if (constant.size() == fit.size()) {
    err << (fit.size() == 1 ? files + ": " + column + " is "
                            : "every fitted recording's " + column.substr(4) + " is constant (" +
                                  files + "); in " + constant.front() + " it is ")
        << value << " on every row: nothing to identify (without an input that moves the rig "
        << "every parameter would come out 0 +- 0); check input in " << options.import_spec.string()
        << " or record with an excitation\n";
  } else {
    err << files << ": " << column << " is constant (" << value
        << " on every row): nothing to identify in " << (constant.size() == 1 ? "it" : "them")
        << " (its Table I column would be 0 +- 0); leave " << (constant.size() == 1 ? "it" : "them")
        << " out of --csv, or check input in " << options.import_spec.string() << "\n";
  }
  return false;
}

// CSV recordings, mapped by the import spec. The rig configuration is optional: duty input needs
// its motor (eq. 4); voltage input has its motor in the spec's [motor], torque input needs none.
std::optional<pipeline::Batch> inputs_from_csvs(const IdentifyCommandOptions& options,
                                                std::ostream& err) {
  const identification::CsvImportSpec spec =
      identification::load_csv_import_spec(options.import_spec);
  if (options.guaranteed && !spec.bounds) {
    err << "furuta identify: --guaranteed: " << options.import_spec.string()
        << " has no [guaranteed] table: a CSV recording's bounds (each angle's error, the "
           "pendulum's zero, the lag, the supply) are stated there (docs/csv-import.md, "
           "\"Guaranteed identification\")\n";
    return std::nullopt;
  }
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
  in.input_between_samples = spec.input_between_samples;
  const auto load = [&](const std::filesystem::path& path) {
    return identification::experiment_from_csv(identification::import_csv(path, spec),
                                               path.filename().string());
  };
  for (const auto& path : options.csvs) in.fit.push_back({load(path), std::nullopt, std::nullopt});
  if (!excited(in.fit, spec, options, err)) return std::nullopt;
  in.files = options.csvs;
  if (!options.validate.empty()) {
    in.held_out = pipeline::Recording{load(options.validate), std::nullopt, std::nullopt};
    in.files.push_back(options.validate);
  }
  in.files.push_back(options.import_spec);
  if (spec.angle_unit == identification::AngleUnit::counts) {
    in.angle_resolution_rad = 2 * std::numbers::pi / spec.pendulum_counts_per_rev;
    in.counts_per_rev = {spec.arm_counts_per_rev, spec.pendulum_counts_per_rev};
  }
  in.encoder_resolution_rad = spec.resolution_rad;
  in.recording_bounds = spec.bounds;

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

// Table I the moment the fit is done (SIVIA and the scenarios can take minutes), then the
// terminal's progress lines, if any.
class IdentifyProgress : public pipeline::Progress {
 public:
  IdentifyProgress(std::ostream* table_one, pipeline::Progress* terminal)
      : table_one_(table_one), terminal_(terminal) {}
  void output_error_started(std::size_t experiments) override {
    if (terminal_ != nullptr) terminal_->output_error_started(experiments);
  }
  void fit_done(const identification::Identification& id,
                const identification::OutputErrorResult* refined) override {
    if (terminal_ != nullptr) terminal_->fit_done(id, refined);
    if (table_one_ != nullptr) *table_one_ << report::format_table_one(id, refined) << std::flush;
  }
  void sivia(std::size_t tested, std::size_t pending) override {
    if (terminal_ != nullptr) terminal_->sivia(tested, pending);
  }
  void sivia_done() override {
    if (terminal_ != nullptr) terminal_->sivia_done();
  }
  void windows(std::size_t done, std::size_t total) override {
    if (terminal_ != nullptr) terminal_->windows(done, total);
  }
  void windows_done() override {
    if (terminal_ != nullptr) terminal_->windows_done();
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
  if (options.no_output_error) settings.output_error.run = false;
  settings.output_error.diagnose = options.diagnose;
  settings.sivia.run = options.sivia;
  settings.windowed.run = options.guaranteed;
  settings.sivia.threads = options.threads.value_or(rig.sivia.threads);
  settings.simulation.run = options.simulate;
  if (options.simulate_seconds) {
    for (validated::Scenario& s : settings.simulation.scenarios) {
      s.duration_s = *options.simulate_seconds;
    }
  }
  return settings;
}

namespace {

// The command's inputs as a batch, checked; nothing when they are unusable (the reason on err).
std::optional<pipeline::Batch> checked_batch(const IdentifyCommandOptions& options,
                                             std::ostream& err) {
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
  if (options.sivia && !pipeline::has_data_error_bounds(batch->rig.sivia)) {
    // Zero bounds claim exact data: SIVIA then finds no consistent parameter, an empty set that
    // reads like a finding about the rig.
    const std::string where =
        !options.config_path.empty()
            ? options.config_path.string() + "'s [sivia]"
            : (csv_input ? std::string("without --config, [sivia]")
                         : "the configuration " + options.logs.front().string() +
                               " carries: its [sivia]");
    err << "furuta identify: --sivia needs the data's error bounds, and " << where
        << " has every one at 0 (q2_bound, dq1_bound, dq2_bound, ddq1_bound, ddq2_bound, "
           "tau_bound): SIVIA would find an empty set. Set them in the [sivia] section of a rig "
           "configuration (config/rig.toml shows them) and pass it with --config\n";
    return std::nullopt;
  }
  return batch;
}

pipeline::Run run_batch(const pipeline::Batch& batch, const IdentifyCommandOptions& options,
                        std::ostream* table_one) {
  // Progress only on a terminal: logs and CI stay quiet.
  TerminalProgress terminal;
  const bool tty = ::isatty(STDERR_FILENO) == 1;
  IdentifyProgress progress(table_one, tty ? &terminal : nullptr);
  return pipeline::run(batch, identify_settings(batch.rig, options), &progress);
}

}  // namespace

std::optional<pipeline::Run> run_identification(const IdentifyCommandOptions& options,
                                                std::ostream& err, std::ostream* table_one) {
  const std::optional<pipeline::Batch> batch = checked_batch(options, err);
  if (!batch) return std::nullopt;
  return run_batch(*batch, options, table_one);
}

void print_identification(std::ostream& out, const pipeline::Run& run,
                          const std::filesystem::path& dir, bool table_one_printed) {
  out << (table_one_printed ? report::terminal_text_after_lsmi(run) : report::terminal_text(run));
  out << "wrote " << (dir / "results.json").string() << " and figures in " << dir.string() << "\n";
  out << "report: " << (dir / "report.html").string() << "\n";
}

int run_identify_command(const IdentifyCommandOptions& options, std::ostream& out,
                         std::ostream& err) {
  if (options.diagnose && options.no_output_error) {
    err << "furuta identify: --diagnose refits the output-error refinement: not with "
           "--no-output-error\n";
    return 2;
  }
  const std::optional<pipeline::Batch> batch = checked_batch(options, err);
  if (!batch) return 2;
  // Before the fit, which may take long: a directory it may not replace is refused at once.
  if (const auto problem = report::output_directory_problem(options.output_dir)) {
    err << "furuta identify: -o " << options.output_dir.string() << ": " << *problem << "\n";
    return 2;
  }
  const pipeline::Run run = run_batch(*batch, options, &out);
  bool replaced = false;
  try {
    report::RunDirectory dir(options.output_dir);
    report::write_identification(dir.staging(), run, daemon::kSoftwareVersion);
    replaced = dir.commit();
  } catch (const report::OutputDirectoryError& e) {
    err << "furuta identify: -o " << options.output_dir.string() << ": " << e.what() << "\n";
    return 2;
  }
  print_identification(out, run, options.output_dir, true);
  if (replaced)
    out << "(the previous run's files in " << options.output_dir.string() << " were replaced)\n";
  // Done in part: the estimate asked for (the refinement's) is not had.
  if (run.output_error && !run.output_error->result.converged) {
    err << "furuta identify: done in part: the output-error refinement did not converge (its "
           "warning says where it stopped); "
        << (run.identification.lsmi_ran() ? "Table I shows LSMI alone"
                                          : "and LSMI did not run: no estimate")
        << "\n";
    return 1;
  }
  return 0;
}

}  // namespace furuta::app
