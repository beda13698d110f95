// `furuta identify LOG... [--validate LOG]` and `furuta identify --csv FILE... --import-spec SPEC
// [--validate FILE.csv]`: the arguments as a pipeline::BatchRequest, the pipeline's intake and
// run, then the report's writers (Table I, results.json, figures, report.html).
#include <unistd.h>

#include <ostream>

#include "commands.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/pipeline/intake.hpp"
#include "furuta/pipeline/pipeline.hpp"
#include "furuta/report/outputs.hpp"
#include "furuta/report/run_directory.hpp"
#include "furuta/report/tables.hpp"
#include "terminal_progress.hpp"

namespace furuta::app {

namespace {

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

pipeline::BatchRequest batch_request(const IdentifyCommandOptions& options) {
  pipeline::BatchRequest request;
  request.logs = options.logs;
  request.csvs = options.csvs;
  request.import_spec = options.import_spec;
  request.validate = options.validate;
  request.config_path = options.config_path;
  request.use_intact_part = options.use_intact_part;
  pipeline::SettingsOverrides& o = request.overrides;
  o.cutoff_hz = options.cutoff_hz;
  o.input_lag_ms = options.input_lag_ms;
  o.estimate_input_lag = options.estimate_input_lag;
  o.no_output_error = options.no_output_error;
  o.diagnose = options.diagnose;
  o.sivia = options.sivia;
  o.guaranteed = options.guaranteed;
  o.threads = options.threads;
  o.simulate = options.simulate;
  o.simulate_seconds = options.simulate_seconds;
  return request;
}

namespace {

// The command's inputs through the pipeline's intake; each refusal on err.
std::optional<pipeline::Intake> checked_intake(const IdentifyCommandOptions& options,
                                               std::ostream& err) {
  pipeline::Intake intake = pipeline::load_batch(batch_request(options));
  for (const std::string& refusal : intake.refusals) err << "furuta identify: " << refusal << "\n";
  if (!intake.batch) return std::nullopt;
  return intake;
}

// Every file the command reads: none may be where its output goes.
std::vector<std::filesystem::path> identify_inputs(const IdentifyCommandOptions& options) {
  std::vector<std::filesystem::path> inputs = options.logs;
  inputs.insert(inputs.end(), options.csvs.begin(), options.csvs.end());
  for (const auto& named : {options.validate, options.import_spec, options.config_path}) {
    if (!named.empty()) inputs.push_back(named);
  }
  return inputs;
}

pipeline::Run run_batch(const pipeline::Intake& intake, std::ostream* table_one) {
  // Progress only on a terminal: logs and CI stay quiet.
  TerminalProgress terminal;
  const bool tty = ::isatty(STDERR_FILENO) == 1;
  IdentifyProgress progress(table_one, tty ? &terminal : nullptr);
  return pipeline::run(*intake.batch, intake.settings, &progress);
}

}  // namespace

std::optional<pipeline::Run> run_identification(const IdentifyCommandOptions& options,
                                                std::ostream& err, std::ostream* table_one) {
  const std::optional<pipeline::Intake> intake = checked_intake(options, err);
  if (!intake) return std::nullopt;
  return run_batch(*intake, table_one);
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
  if (options.output_dir.empty()) {
    err << "furuta identify: -o is empty: give the directory for the run's files\n";
    return 2;
  }
  // The run replaces its directory whole: an input there would be deleted with the old files.
  if (const auto input = report::input_in_the_way(options.output_dir, identify_inputs(options))) {
    err << "furuta identify: -o " << options.output_dir.string() << " would overwrite the input "
        << input->string() << " (the output directory is replaced whole): give another -o\n";
    return 2;
  }
  const std::optional<pipeline::Intake> intake = checked_intake(options, err);
  if (!intake) return 2;
  std::optional<pipeline::Run> run;
  bool replaced = false;
  try {
    // Before the fit, which may take long: a directory it may not replace or cannot write, or one
    // another run is writing, is refused at once. Held until the files are in place.
    report::RunDirectory dir(options.output_dir);
    run = run_batch(*intake, &out);
    report::write_identification(dir.staging(), *run, daemon::kSoftwareVersion);
    replaced = dir.commit();
  } catch (const report::OutputDirectoryError& e) {
    err << "furuta identify: -o " << options.output_dir.string() << ": " << e.what() << "\n";
    return 2;
  }
  print_identification(out, *run, options.output_dir, true);
  if (replaced)
    out << "(the previous run's files in " << options.output_dir.string() << " were replaced)\n";
  // Done in part: a log fitted by its intact parts only; what was dropped is said.
  bool in_part = false;
  for (const std::string& account : intake->batch->used_in_part) {
    err << "furuta identify: done in part: " << account << "\n";
    in_part = true;
  }
  // Done in part: the estimate asked for (the refinement's) is not had.
  if (run->output_error && !run->output_error->result.converged) {
    err << "furuta identify: done in part: the output-error refinement did not converge (its "
           "warning says where it stopped); "
        << (run->identification.lsmi_ran() ? "Table I shows LSMI alone"
                                           : "and LSMI did not run: no estimate")
        << "\n";
    return 1;
  }
  return in_part ? kExitPartOrRefused : kExitDone;
}

}  // namespace furuta::app
