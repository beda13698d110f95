#pragma once
// The `furuta` command's subcommands, each a function over plain options so tests can call them.

#include <array>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "furuta/control/upright_lqr.hpp"
#include "furuta/model/model.hpp"
#include "furuta/pipeline/pipeline.hpp"
#include "furuta/validated/scenarios.hpp"

namespace furuta::app {

// One rule for every command's exit status (README, "Exit status").
inline constexpr int kExitDone = 0;  // everything asked happened
inline constexpr int kExitPartOrRefused =
    1;                                  // done in part, or refused: the output says what and why
inline constexpr int kExitNotDone = 2;  // bad usage or input (named), or nothing answered
// Not allowed: `furuta start` without the command key (sysexits' EX_NOPERM).
inline constexpr int kExitNotPermitted = 77;
inline constexpr const char* kExitStatusHelp =
    "Exit status: 0 done; 1 done in part or refused (the output says what was set aside and why); "
    "2 not done: bad usage, bad or untrustworthy input, or nothing answered; 77 not permitted "
    "(`furuta start` cannot read the command key: not in group furuta).";
// CLI11's own codes for a usage error (100 and up) folded into the rule; --help and --version are
// 0.
inline int usage_exit_status(int cli11_exit_code) {
  return cli11_exit_code == 0 ? kExitDone : kExitNotDone;
}

struct DevicesOptions {
  bool simulated = false;  // list the simulated rig's boards instead of the USB bus
  // With `simulated`: the configuration whose [simulation] builds the rig (its boards' serials and
  // firmware versions). Empty: the built-in defaults.
  std::string config_path;
};
// Lists connected Phidget boards; says clearly when there are none or access is denied.
// Returns 0 when every board found was listed, 1 when some were and others could not be opened,
// 2 when none was listed (none found, all denied, USB unreadable: no board answered).
int run_devices_command(const DevicesOptions& options, std::ostream& out, std::ostream& err);

// --- talking to a running daemon over LCM ---
struct RemoteOptions {
  std::string lcm_url;  // empty: the configuration's
  std::filesystem::path config_path;
  double reply_timeout_s = 2.0;
  // start: how long to wait, after the daemon accepted it, for the session to run or be refused
  // (the loop refuses a pendulum that swings); stop, estop: for the session to end.
  double wait_s = 5.0;
  bool wait = true;  // false: return once the daemon has answered the command itself
  // The key `start` signs with (docs/security.md); empty: the configuration's
  // [daemon] command_key_file.
  std::filesystem::path command_key;
  // The daemon's public key, which every answer must be signed under; empty: the configuration's
  // [daemon] daemon_public_key_file. Unreadable: answers are taken unverified, and said so.
  std::filesystem::path daemon_public_key;
};
// A session's excitation as the user gave it; what is left out comes from the configuration's
// [excitation], field by field.
struct StartOptions {
  std::optional<std::string> profile;
  std::optional<double> amplitude_duty;
  std::optional<double> duration_s;
  std::string label;
  std::optional<std::int64_t> seed;
  // A balance session: the controller file (`furuta controller design`) instead of a profile.
  std::optional<std::filesystem::path> balance;
};
enum class RemoteKind { start, stop, estop, status };
// Sends one command and reports the daemon's verdict on it. Only answers signed under the
// daemon's public key count (others are ignored and counted; said when nothing else came); stop,
// e-stop and status are sent again until answered. start: 0 once the session runs, 1
// refused (by the command's check, or by the loop: a session running, the pendulum swinging, the
// logs directory), 2 no answer, or no verdict within wait_s. stop, estop: 0 once the session has
// ended (or when none ran: said so), 2 when it still runs after wait_s. status: 0. Every kind: 1
// refused, 2 nothing answered. Over LCM; daemon_channel.hpp takes another channel.
int run_remote_command(RemoteKind kind, const RemoteOptions& remote, const StartOptions& start,
                       std::ostream& out, std::ostream& err);

// --- a one-shot session without a daemon ---
struct RunOptions {
  std::filesystem::path config_path;
  bool simulated = false;          // the simulated rig, whatever the configuration says
  bool virtual_time = false;       // simulated: as fast as the machine goes
  std::filesystem::path logs_dir;  // empty: the configuration's
  std::string lcm_url;             // empty: the configuration's; "memq://" publishes nowhere
  StartOptions session;
};
int run_session_command(const RunOptions& options, std::ostream& out, std::ostream& err);

// --- logs ---
// Each applies session_log::integrity_problems. log info: 0 intact, 1 not intact (the problems
// listed), 2 not a session log.
int run_log_info_command(const std::filesystem::path& log, std::ostream& out, std::ostream& err);
// Writes the samples the log has: 0; 1 when the log is not intact or has no samples (the header
// only), saying so on err; 2 when it is not a session log (nothing written).
int run_log_export_csv_command(const std::filesystem::path& log, const std::filesystem::path& csv,
                               std::ostream& out, std::ostream& err);
// Replays a log's USB traffic through the daemon (virtual time) and compares the samples with the
// logged ones, matched by sequence number: 0 when identical; 1 when any differ, either side has
// samples the other lacks, or the log is not intact (then only what both have is compared).
int run_replay_command(const std::filesystem::path& log, const std::filesystem::path& config_path,
                       std::ostream& out, std::ostream& err);

// --- identification ---
// Fits either session logs or CSV recordings (another rig, another logger), not both: they are
// fitted together as one rig.
struct IdentifyCommandOptions {
  std::vector<std::filesystem::path> logs;  // session logs to fit
  std::vector<std::filesystem::path> csvs;  // or CSV recordings to fit, mapped by import_spec
  std::filesystem::path import_spec;        // TOML ([csv], [motor]); required with CSV inputs
  std::filesystem::path validate;  // optional held-out session: a log, or a CSV (name ends .csv)
  // Empty: the configuration carried by the first log. With CSVs it is optional: only duty input
  // needs it (eq. 4's motor data); it also gives the CAD values and [identification]'s filters.
  std::filesystem::path config_path;
  // Holds this run's files only: replaced whole, refused when it is not a previous run's
  // (report/run_directory.hpp).
  std::filesystem::path output_dir = "identification";
  // Given here, these override the configuration's [identification].
  std::optional<double> cutoff_hz;
  // The torque is formed from the input this much earlier. CSVs: 0 unless given (the
  // configuration's lag belongs to the daemon's data path, not another logger's).
  std::optional<double> input_lag_ms;
  bool estimate_input_lag = false;  // estimate it even when the configuration gives it
  bool sivia = false;               // guaranteed identification after the LSMI ([sivia])
  // The windowed set inversion around the output-error estimate ([guaranteed]).
  bool guaranteed = false;
  // Skip the output-error refinement the configuration's [output_error] enables.
  bool no_output_error = false;
  bool diagnose = false;       // the refits of candidate recording mistakes, whatever the fit
  std::optional<int> threads;  // SIVIA threads (default: the configuration's)
  // The paper's scenarios after the fit (Table III, Fig. 6), with the LSMI estimate and, with
  // --sivia, SIVIA's hull; measured on the simulated rig (its truth, or the configuration's
  // simulated-rig parameters). Each scenario's duration, if given (else the paper's 4 s).
  bool simulate = false;
  std::optional<double> simulate_seconds;
  // A log that is not intact (damaged, truncated, cut short, samples missing) is refused unless
  // this is set; then each contiguous run of its samples long enough for the filters is fitted as
  // a recording of its own, and the warnings say what was used and what was dropped.
  bool use_intact_part = false;
};
}  // namespace furuta::app
namespace furuta::pipeline {
struct BatchRequest;
}
namespace furuta::app {
// The command's inputs and overrides as the pipeline's intake takes them (pipeline/intake.hpp).
pipeline::BatchRequest batch_request(const IdentifyCommandOptions& options);
// The command's inputs through pipeline::load_batch, then pipeline::run (progress on stderr when
// it is a terminal).
// Nothing when the inputs are unusable (the reason on err: bad arguments, unreadable or foreign
// files, a bad configuration); what the fit itself throws passes through. With `table_one`,
// Table I is written there as soon as LSMI is done, before SIVIA and the scenarios run.
std::optional<pipeline::Run> run_identification(const IdentifyCommandOptions& options,
                                                std::ostream& err,
                                                std::ostream* table_one = nullptr);
// What `furuta identify` prints of a run whose files are in dir: Table I (unless printed
// already), the SIVIA and simulation summaries, where the files are.
void print_identification(std::ostream& out, const pipeline::Run& run,
                          const std::filesystem::path& dir, bool table_one_printed = false);
// run_identification, then every file (report::write_identification) and print_identification.
// 0; 1 when the output-error refinement did not converge or use_intact_part fitted a log in part
// (each such log's account of what was dropped on err); 2 for unusable inputs (a log not intact
// without use_intact_part, one too short for any method) or an output directory it may not use.
int run_identify_command(const IdentifyCommandOptions& options, std::ostream& out,
                         std::ostream& err);

// --- validation by guaranteed simulation (the paper's section IV.B) ---
struct SimulateCommandOptions {
  std::vector<int> scenarios;  // 1..4; empty: all four
  // A results.json of `furuta identify`: LSMI and SIVIA parameters, or the refinement's where LSMI
  // did not run.
  std::filesystem::path results;
  bool truth =
      false;  // the simulated rig's truth as point parameters (the default without results)
  std::optional<double> relative_pct;  // with the truth: also the truth +- this % as intervals
  std::optional<double> seconds;       // each scenario's duration (default: the paper's 4 s)
  std::size_t pieces = 1;  // tubes per run: 1, or a power of two split at 0.5 s (tighter, slower)
  std::filesystem::path output_dir = "simulation";  // as IdentifyCommandOptions::output_dir
};
// Writes simulate.json, table3.txt, tubes.json and scenario_<n>_<parameters>.svg; prints Table
// III.
// 0 on success (whatever the tubes reached: failures are reported in the table), 2 on bad input.
int run_simulate_command(const SimulateCommandOptions& options, std::ostream& out,
                         std::ostream& err);

// --- balance sessions' report ---
struct ReportCommandOptions {
  std::vector<std::filesystem::path> logs;  // session logs, reported in this order
  // Holds this report's files only: replaced whole, as IdentifyCommandOptions::output_dir.
  std::filesystem::path output_dir;
};
// report.html (a section per log), balance.json and balance_<n>.svg (report::write_balance_report).
// 0 written; 1 written, but a log is not intact (reported as far as it goes) or is not a balance
// session (its section says what it is), each named on err; 2 no log, a file that is no session
// log, or an -o it may not use (report::RunDirectory's refusals, an input inside it): nothing
// written.
int run_report_command(const ReportCommandOptions& options, std::ostream& out, std::ostream& err);

// --- the identification trigger (log_processor.hpp) ---
// --- the balance controller (control/, docs/control.md) ---
enum class ControllerParameters { output_error, lsmi, cad };
const char* to_string(ControllerParameters source);
struct ControllerDesignOptions {
  std::filesystem::path results;  // a results.json of `furuta identify`
  ControllerParameters parameters = ControllerParameters::output_error;
  // The rig: its motor (eq. 4), loop period, data path's lag ([identification] input_lag_ms),
  // duty limit ([limits] max_amplitude_duty) and, on the simulated rig, supply.
  std::filesystem::path config_path;
  std::optional<double> supply_v;  // default: the simulated rig's, else the motor's nominal
  control::LqrWeights weights;
  std::filesystem::path output;  // the controller file
};
// 0 written; 2 an unreadable results file, parameters it lacks, an output that is an input, or
// a design that fails (a plant the duty cannot stabilise).
int run_controller_design_command(const ControllerDesignOptions& options, std::ostream& out,
                                  std::ostream& err);

// `furuta controller verify`: the balancing loop proven to hold over a parameter box
// (verification/).
struct ControllerVerifyOptions {
  std::filesystem::path controller;  // a controller file of `furuta controller design`
  // A results.json (its output-error estimate +- sd standard deviations) or a box file (.toml,
  // config/parameter_box.hpp).
  std::filesystem::path parameters;
  double sd = 3.0;
  // The rig: the encoders' counts, the board's duty ramp, the arm's limit.
  std::filesystem::path config_path;
  double start_deg = 2.0;     // the pendulum within +- this of upright at the start ...
  double start_deg_s = 10.0;  // ... and its rate within +- this; the arm at its centre at rest
  double estimate_error_deg_s = 1.0;  // the filter's rates off by at most this (angles: a count)
  std::optional<std::array<double, 2>> lag_ms;  // default: the controller's lag
  std::optional<double> reading_age_ms;         // default: the controller's
  std::optional<double> upright_deg;            // default: the controller's fall angle
  double horizon_s = 10.0;
  bool start_region = false;  // also bisect the largest certified start
  std::size_t max_pieces = 32;
  double handover_s = 0.0;  // SplitOptions::handover_s
  std::size_t max_symbols = 1000;
  std::size_t sampled = 40;          // trajectories of the sampled check
  std::filesystem::path output_dir;  // report.html, verification.json, verification.svg
};
// 0 certified; 1 not certified (the report says where and why); 2 bad input (named).
int run_controller_verify_command(const ControllerVerifyOptions& options, std::ostream& out,
                                  std::ostream& err);

struct ProcessLogsOptions {
  std::filesystem::path logs_dir;     // empty: the configuration's [daemon] logs_dir
  std::filesystem::path config_path;  // its [automation] says what to identify
  // The configuration was named (-c): its rig and [identification] fit every batch, as
  // `identify -c` does; otherwise each batch is fitted with the configuration its logs carry.
  bool config_named = false;
  std::filesystem::path identifications_dir;  // empty: [automation] identifications_dir
  bool watch = false;  // pass again whenever a log lands, until SIGINT or SIGTERM
};
// One pass over the logs directory (or, with watch, a pass per landing log). 0: every log was
// identified or waits for its batch; 1: some went to failed/ (each with a .reason.txt) or to
// done/ unidentified (a label [automation] does not name).
int run_process_logs_command(const ProcessLogsOptions& options, std::ostream& out,
                             std::ostream& err);

}  // namespace furuta::app
