// furuta: the command-line entry point. Thin: options in, a subcommand function out.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>
#include <map>
#include <string>

#include "cli_numbers.hpp"
#include "commands.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/daemon/rig_connection.hpp"

namespace {

// An output path typed as '' names nothing: bad usage, rather than read as the default or as the
// current directory.
CLI::Validator not_empty_path() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        return text.empty() ? "an empty path names no file or directory" : std::string();
      },
      "");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"furuta: identification experiments on a rotary inverted pendulum"};
  app.require_subcommand(1);
  app.set_version_flag("--version", furuta::daemon::kSoftwareVersion);
  app.footer(furuta::app::kExitStatusHelp);
  // Every option whose default is a plain value shows it in --help.
  app.option_defaults()->always_capture_default();

  furuta::app::DevicesOptions devices;
  CLI::App* devices_cmd = app.add_subcommand("devices", "List connected Phidget boards");
  devices_cmd->add_flag("--sim", devices.simulated,
                        "List the simulated rig's boards instead, through its USB descriptors");
  devices_cmd
      ->add_option("-c,--config", devices.config_path,
                   "With --sim: the rig configuration whose [simulation] builds the boards "
                   "(serials, firmware); default: the built-in simulated rig")
      ->check(CLI::ExistingFile);

  // A running daemon, over LCM.
  furuta::app::RemoteOptions remote;
  remote.config_path = furuta::config::default_rig_config_path();
  furuta::app::StartOptions start;
  auto add_remote = [&](CLI::App* cmd) {
    cmd->add_option("--lcm-url", remote.lcm_url, "LCM URL (default: the configuration's)");
    cmd->add_option("-c,--config", remote.config_path, "Rig configuration (TOML)")
        ->check(CLI::ExistingFile);
    cmd->add_option("--timeout", remote.reply_timeout_s, "Seconds to wait for the daemon's answer")
        ->check(furuta::app::finite_in(0.1, 60.0));
    cmd->add_option("--daemon-public-key", remote.daemon_public_key,
                    "The key the daemon's answers are checked with (default: the "
                    "configuration's [daemon] daemon_public_key_file)");
  };
  auto add_session = [&](CLI::App* cmd, furuta::app::StartOptions& start) {
    cmd->add_option("--profile", start.profile,
                    "bang_bang, free_decay, step, prbs, chirp, multisine (default: the "
                    "configuration's [excitation], as for every option left out)");
    // The limits are the configuration's; what it can never accept is bad usage (exit 2), checked
    // with them before anything runs.
    cmd->add_option("--amplitude", start.amplitude_duty,
                    "Duty amplitude, above 0 and at most the configuration's [limits] "
                    "max_amplitude_duty (0.5 in config/rig.toml)")
        ->check(furuta::app::finite_number());
    cmd->add_option("--duration", start.duration_s,
                    "Seconds, above 0 and at most the configuration's [limits] max_duration_s")
        ->check(furuta::app::finite_number());
    cmd->add_option("--label", start.label, "A label for the session's name");
    cmd->add_option("--seed", start.seed, "Seed of randomised profiles");
    cmd->add_option("--balance", start.balance,
                    "Swing the pendulum up and balance it with this controller file (`furuta "
                    "controller design`) instead of an excitation profile; --duration as usual")
        ->check(CLI::ExistingFile)
        ->excludes("--profile")
        ->excludes("--amplitude");
  };
  // The daemon answers a command at once; the session starts (or is refused) or ends a moment
  // later.
  bool no_wait = false;
  auto add_wait = [&](CLI::App* cmd, const std::string& what) {
    auto* wait = cmd->add_option("--wait", remote.wait_s,
                                 "Seconds to wait for " + what + " (exit 2 if it has not by then)")
                     ->check(furuta::app::finite_in(0.1, 600.0));
    cmd->add_flag("--no-wait", no_wait, "Return once the daemon has accepted the command")
        ->excludes(wait);
  };
  CLI::App* start_cmd = app.add_subcommand(
      "start",
      "Start a session on the running daemon; waits until it runs (exit 0) or is refused (1). "
      "The command is signed with the rig's command key: members of group furuta only (77)");
  add_remote(start_cmd);
  start_cmd->add_option("--command-key", remote.command_key,
                        "The key to sign with (default: the configuration's [daemon] "
                        "command_key_file)");
  add_session(start_cmd, start);
  add_wait(start_cmd,
           "the session to run or be refused, after the daemon accepted it (the pendulum must "
           "have hung still for [daemon] rest_check_s)");
  CLI::App* stop_cmd =
      app.add_subcommand("stop", "Stop the running session; waits until it has ended");
  add_remote(stop_cmd);
  add_wait(stop_cmd, "the session to end");
  CLI::App* estop_cmd = app.add_subcommand("estop", "Emergency stop: motor to zero, braked");
  add_remote(estop_cmd);
  add_wait(estop_cmd, "the session to end");
  CLI::App* status_cmd = app.add_subcommand("status", "The daemon's state");
  add_remote(status_cmd);

  furuta::app::RunOptions run;
  run.config_path = furuta::config::default_rig_config_path();
  CLI::App* run_cmd = app.add_subcommand("run", "Run one session without a daemon");
  run_cmd->add_option("-c,--config", run.config_path, "Rig configuration (TOML)")
      ->check(CLI::ExistingFile);
  run_cmd->add_flag("--sim", run.simulated, "Use the simulated rig");
  run_cmd->add_flag("--virtual-time", run.virtual_time,
                    "Simulated rig: run as fast as possible instead of in real time");
  run_cmd->add_option("--logs-dir", run.logs_dir,
                      "Where the log goes (default: the configuration's [daemon] logs_dir)");
  run_cmd->add_option("--lcm-url", run.lcm_url,
                      "LCM URL for samples (memq:// for none; default: the configuration's)");
  add_session(run_cmd, run.session);

  std::string log_path, csv_path, replay_config;
  CLI::App* log_cmd = app.add_subcommand("log", "Session logs");
  log_cmd->require_subcommand(1);
  CLI::App* info_cmd = log_cmd->add_subcommand("info", "Summarise a session log");
  info_cmd->add_option("LOG", log_path, "A session log (.lcmlog)")
      ->required()
      ->check(CLI::ExistingFile);
  CLI::App* export_cmd = log_cmd->add_subcommand("export-csv", "Samples of a log as CSV");
  export_cmd->add_option("LOG", log_path, "A session log (.lcmlog)")
      ->required()
      ->check(CLI::ExistingFile);
  export_cmd->add_option("-o,--output", csv_path, "The CSV file to write")
      ->required()
      ->check(not_empty_path());
  CLI::App* replay_cmd =
      app.add_subcommand("replay", "Replay a log's USB traffic and check the samples reproduce");
  replay_cmd->add_option("LOG", log_path, "A session log (.lcmlog)")
      ->required()
      ->check(CLI::ExistingFile);
  replay_cmd
      ->add_option("-c,--config", replay_config,
                   "Rig configuration (default: the one the log carries)")
      ->check(CLI::ExistingFile);

  furuta::app::IdentifyCommandOptions identify;
  CLI::App* identify_cmd = app.add_subcommand(
      "identify", "Least-squares identification (Table I) of session logs or CSV recordings");
  identify_cmd->add_option("LOG", identify.logs, "Session logs (.lcmlog) to fit")
      ->check(CLI::ExistingFile);
  identify_cmd
      ->add_option("--csv", identify.csvs,
                   "A CSV recording to fit instead of logs (repeat for several); needs "
                   "--import-spec")
      ->check(CLI::ExistingFile);
  identify_cmd
      ->add_option("--import-spec", identify.import_spec,
                   "TOML mapping the CSVs' columns, units, pendulum zero and input ([csv]; "
                   "[motor] for voltage input)")
      ->check(CLI::ExistingFile);
  identify_cmd
      ->add_option("--validate", identify.validate,
                   "A held-out session: a log, or a CSV (name ending .csv) when fitting CSVs")
      ->check(CLI::ExistingFile);
  identify_cmd
      ->add_option("-c,--config", identify.config_path,
                   "Rig configuration (default: the one the first log carries; with CSVs only "
                   "needed for duty input)")
      ->check(CLI::ExistingFile);
  identify_cmd
      ->add_option("-o,--output", identify.output_dir,
                   "Directory for results and figures, replaced whole: new, empty or a "
                   "previous run's (default: identification)")
      ->check(not_empty_path());
  identify_cmd
      ->add_option("--cutoff", identify.cutoff_hz,
                   "Low-pass cut-off [Hz] (default: the configuration's; 15 without one)")
      ->check(furuta::app::finite_in(0.01, 1000.0));
  auto* lag_option = identify_cmd->add_option(
      "--input-lag-ms", identify.input_lag_ms,
      "Input-to-angle lag [ms], not negative: the angles cannot lead the input (default: the "
      "configuration's, else estimated; CSVs: 0)");
  lag_option->check(furuta::app::finite_in(0.0, 1000.0));
  identify_cmd
      ->add_flag("--estimate-input-lag", identify.estimate_input_lag,
                 "Estimate the lag from the data (to calibrate the configuration's)")
      ->excludes(lag_option);
  identify_cmd->add_flag("--no-output-error", identify.no_output_error,
                         "Skip the output-error refinement after the LSMI ([output_error])");
  identify_cmd->add_flag(
      "--diagnose", identify.diagnose,
      "Refit with each candidate recording mistake undone (an angle's sign, scale or zero, the "
      "input's sign or scale) and name the one the data support, whatever the fit (it runs by "
      "itself when the refinement's fit is no rig's answer; not with --no-output-error)");
  identify_cmd->add_flag("--sivia", identify.sivia,
                         "Guaranteed identification by SIVIA after the LSMI ([sivia] settings)");
  identify_cmd->add_flag(
      "--guaranteed", identify.guaranteed,
      "Guaranteed set by windowed set inversion around the output-error estimate ([guaranteed]; "
      "a CSV's bounds from its import spec's [guaranteed]; minutes)");
  identify_cmd->add_option("--threads", identify.threads, "SIVIA threads (0: all cores)")
      ->check(furuta::app::whole_in(0, 1024));

  identify_cmd->add_flag("--use-intact-part", identify.use_intact_part,
                         "Fit a damaged, truncated or cut-short log's intact parts (each run of "
                         "samples between gaps on its own) instead of refusing it");
  identify_cmd->add_flag("--simulate", identify.simulate,
                         "After the fit, the paper's four scenarios by guaranteed simulation "
                         "(Table III, Fig. 6), with the LSMI and (with --sivia) SIVIA parameters");
  // One name for one thing: each scenario's duration is --scenario-seconds for identify and
  // simulate alike; the names each had before stay as hidden aliases.
  identify_cmd
      ->add_option("--scenario-seconds", identify.simulate_seconds,
                   "With --simulate: each scenario's duration [s] (default: the paper's 4)")
      ->check(furuta::app::finite_in(0.01, 60.0));
  identify_cmd->add_option("--simulate-seconds", identify.simulate_seconds)
      ->check(furuta::app::named(furuta::app::finite_in(0.01, 60.0), "--simulate-seconds"))
      ->group("");

  furuta::app::SimulateCommandOptions simulate;
  CLI::App* simulate_cmd = app.add_subcommand(
      "simulate",
      "The paper's validation scenarios by guaranteed simulation: coverage rates (Table III) and "
      "tubes (Fig. 6)");
  std::string scenario_choice = "all";
  simulate_cmd->add_option("--scenario", scenario_choice, "1, 2, 3, 4 or all");
  auto* results_option = simulate_cmd->add_option(
      "--results", simulate.results,
      "results.json of furuta identify: its LSMI estimate and SIVIA hull as the parameters");
  results_option->check(CLI::ExistingFile);
  simulate_cmd
      ->add_flag("--truth", simulate.truth,
                 "The simulated rig's truth as point parameters (the default without --results)")
      ->excludes(results_option);
  simulate_cmd
      ->add_option("--relative", simulate.relative_pct,
                   "With the truth: also the truth +- this percent as interval parameters")
      ->check(furuta::app::finite_in(0.0, 100.0));
  simulate_cmd
      ->add_option("--scenario-seconds", simulate.seconds,
                   "Each scenario's duration [s] (default: the paper's 4)")
      ->check(furuta::app::finite_in(0.01, 60.0));
  simulate_cmd->add_option("--seconds", simulate.seconds)
      ->check(furuta::app::named(furuta::app::finite_in(0.01, 60.0), "--seconds"))
      ->group("");
  simulate_cmd
      ->add_option("--pieces", simulate.pieces,
                   "Tubes per run: 1 (default), or 2, 4, ... 64: the initial box split at 0.5 s, "
                   "tighter tubes for that many times the work")
      ->check(furuta::app::whole_in(1, 64));
  simulate_cmd
      ->add_option("-o,--output", simulate.output_dir,
                   "Directory for results and figures, replaced whole: new, empty or a "
                   "previous run's (default: simulation)")
      ->check(not_empty_path());

  furuta::app::ControllerDesignOptions design;
  design.config_path = furuta::config::default_rig_config_path();
  CLI::App* controller_cmd =
      app.add_subcommand("controller", "The balance controller (docs/control.md)");
  controller_cmd->require_subcommand(1);
  CLI::App* design_cmd = controller_cmd->add_subcommand(
      "design",
      "Design the balance controller from an identification: the model linearised about upright, "
      "sampled at the loop period with the data path's lag, a discrete LQR");
  design_cmd->add_option("RESULTS", design.results, "A results.json of furuta identify")
      ->required()
      ->check(CLI::ExistingFile);
  std::string parameter_source = "output-error";
  design_cmd
      ->add_option("--parameters", parameter_source,
                   "Which parameters of RESULTS: output-error, lsmi or cad")
      ->check(CLI::IsMember({"output-error", "lsmi", "cad"}));
  design_cmd
      ->add_option("-c,--config", design.config_path,
                   "Rig configuration: the motor (eq. 4), [daemon] period_ns, [identification] "
                   "input_lag_ms, [limits] max_amplitude_duty")
      ->check(CLI::ExistingFile);
  design_cmd
      ->add_option("--supply-v", design.supply_v,
                   "The supply the duty chops [V] (default: the simulated rig's, else the motor's "
                   "nominal voltage)")
      ->check(furuta::app::finite_in(1.0, 100.0));
  design_cmd->add_option("-o,--output", design.output, "The controller file to write (TOML)")
      ->required()
      ->check(not_empty_path());

  furuta::app::ControllerVerifyOptions verify;
  verify.config_path = furuta::config::default_rig_config_path();
  CLI::App* verify_cmd = controller_cmd->add_subcommand(
      "verify",
      "Prove the balancing loop of a controller file keeps the pendulum upright for every "
      "parameter in a box and every start near upright (validated tubes of the sampled-data "
      "loop; docs/control.md); a sampled check and a report. Exit 0 certified, 1 not (the "
      "report says where and why)");
  verify_cmd
      ->add_option("CONTROLLER", verify.controller, "A controller file (furuta controller design)")
      ->required()
      ->check(CLI::ExistingFile);
  verify_cmd
      ->add_option("--parameters", verify.parameters,
                   "A results.json (its output-error estimate +- --sd standard deviations) or a "
                   "box file (.toml: [parameters] mu1 = [lo, hi] ... fv2)")
      ->required()
      ->check(CLI::ExistingFile);
  verify_cmd
      ->add_option("--sd", verify.sd, "Standard deviations each side of the estimate (default 3)")
      ->check(furuta::app::finite_in(0.0, 1000.0));
  verify_cmd
      ->add_option("-c,--config", verify.config_path,
                   "Rig configuration: the encoders' counts, the board's duty ramp, [safety] "
                   "arm_limit_deg")
      ->check(CLI::ExistingFile);
  verify_cmd
      ->add_option("--start-deg", verify.start_deg,
                   "The pendulum within +- this of upright at the start (default 2)")
      ->check(furuta::app::finite_in(0.0, 45.0));
  verify_cmd
      ->add_option("--start-deg-s", verify.start_deg_s,
                   "... and its rate within +- this [deg/s] (default 10); the arm at its centre")
      ->check(furuta::app::finite_in(0.0, 1000.0));
  verify_cmd
      ->add_option("--estimate-error-deg-s", verify.estimate_error_deg_s,
                   "The filter's rates off by at most this at the start [deg/s] (default 1; its "
                   "angles within a count)")
      ->check(furuta::app::finite_in(0.0, 1000.0));
  verify_cmd->add_option(
      "--lag-ms", verify.lag_ms,
      "LO HI: the board takes each duty this long after its sample, anywhere in the "
      "interval, each period (default: the controller's lag)");
  verify_cmd->add_option("--reading-age-ms", verify.reading_age_ms,
                         "The angles were read this long before each sample (default: the "
                         "controller's reading_age_s)");
  verify_cmd
      ->add_option("--upright-deg", verify.upright_deg,
                   "The angle from upright proven never reached (default: the controller's "
                   "fall_deg)")
      ->check(furuta::app::finite_in(0.1, 90.0));
  verify_cmd->add_option("--horizon", verify.horizon_s, "Seconds to prove (default 10)")
      ->check(furuta::app::finite_in(0.016, 3600.0));
  verify_cmd->add_flag("--start-region", verify.start_region,
                       "Also find the largest start (the given one scaled) that is certified");
  verify_cmd
      ->add_option("--max-pieces", verify.max_pieces,
                   "Pieces of the start and parameter boxes at most (default 32)")
      ->check(CLI::Range(1, 4096));
  verify_cmd
      ->add_option("--handover", verify.handover_s,
                   "Seconds the pieces run before one run from the hull of their states takes "
                   "over, when it is certified (default 0: the pieces run to the horizon)")
      ->check(furuta::app::finite_in(0.0, 3600.0));
  verify_cmd
      ->add_option("--sampled", verify.sampled,
                   "Trajectories of the sampled check (default 40: 32 corners, then random)")
      ->check(CLI::Range(0, 100000));
  verify_cmd
      ->add_option("-o,--output", verify.output_dir,
                   "Directory for report.html, verification.json and verification.svg (default "
                   "verification), replaced whole")
      ->check(not_empty_path());
  verify.output_dir = "verification";

  furuta::app::ReportCommandOptions report;
  CLI::App* report_cmd = app.add_subcommand(
      "report",
      "Balance sessions' report from their logs: report.html (figures, plots over time) and "
      "balance.json; exit 1 when a log is not intact or not a balance session (named)");
  report_cmd->add_option("LOG", report.logs, "Session logs (.lcmlog) of balance sessions")
      ->required()
      ->check(CLI::ExistingFile);
  report_cmd
      ->add_option("-o,--output", report.output_dir,
                   "Directory for the report's files, replaced whole: new, empty or a previous "
                   "run's")
      ->required()
      ->check(not_empty_path());

  furuta::app::ProcessLogsOptions process_logs;
  process_logs.config_path = furuta::config::default_rig_config_path();
  CLI::App* process_logs_cmd = app.add_subcommand(
      "process-logs",
      "Identify the complete session logs in a directory as [automation] groups them; move each "
      "to done/ or failed/ (what furuta-identify@.service runs)");
  process_logs_cmd->add_option("DIR", process_logs.logs_dir,
                               "Logs directory, which must exist (default: the configuration's "
                               "[daemon] logs_dir)");
  process_logs_cmd
      ->add_option("-c,--config", process_logs.config_path,
                   "Rig configuration (TOML): its [automation], [daemon] logs_dir and, when named, "
                   "its rig and [identification] for every batch, as identify -c (not named: each "
                   "batch is fitted with the configuration its logs carry)")
      ->check(CLI::ExistingFile);
  process_logs_cmd
      ->add_option("-o,--output", process_logs.identifications_dir,
                   "Where identifications go (default: the configuration's [automation] "
                   "identifications_dir)")
      ->check(not_empty_path());
  process_logs_cmd->add_flag("--watch", process_logs.watch,
                             "Keep watching: a pass whenever a log lands (machines without "
                             "systemd)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return furuta::app::usage_exit_status(app.exit(e));
  }
  remote.wait = !no_wait;

  try {
    using furuta::app::RemoteKind;
    if (*start_cmd) {
      return furuta::app::run_remote_command(RemoteKind::start, remote, start, std::cout,
                                             std::cerr);
    }
    if (*stop_cmd) {
      return furuta::app::run_remote_command(RemoteKind::stop, remote, start, std::cout, std::cerr);
    }
    if (*estop_cmd) {
      return furuta::app::run_remote_command(RemoteKind::estop, remote, start, std::cout,
                                             std::cerr);
    }
    if (*status_cmd) {
      return furuta::app::run_remote_command(RemoteKind::status, remote, start, std::cout,
                                             std::cerr);
    }
    if (*run_cmd) {
      return furuta::app::run_session_command(run, std::cout, std::cerr);
    }
    if (*info_cmd) return furuta::app::run_log_info_command(log_path, std::cout, std::cerr);
    if (*export_cmd) {
      return furuta::app::run_log_export_csv_command(log_path, csv_path, std::cout, std::cerr);
    }
    if (*replay_cmd) {
      return furuta::app::run_replay_command(log_path, replay_config, std::cout, std::cerr);
    }
    if (*devices_cmd) return furuta::app::run_devices_command(devices, std::cout, std::cerr);
    if (*process_logs_cmd) {
      process_logs.config_named = process_logs_cmd->get_option("--config")->count() > 0;
      return furuta::app::run_process_logs_command(process_logs, std::cout, std::cerr);
    }
    if (*identify_cmd) return furuta::app::run_identify_command(identify, std::cout, std::cerr);
    if (*report_cmd) return furuta::app::run_report_command(report, std::cout, std::cerr);
    if (*design_cmd) {
      using furuta::app::ControllerParameters;
      design.parameters = parameter_source == "lsmi"  ? ControllerParameters::lsmi
                          : parameter_source == "cad" ? ControllerParameters::cad
                                                      : ControllerParameters::output_error;
      return furuta::app::run_controller_design_command(design, std::cout, std::cerr);
    }
    if (*verify_cmd)
      return furuta::app::run_controller_verify_command(verify, std::cout, std::cerr);
    if (*simulate_cmd) {
      if (scenario_choice != "all") {
        std::size_t used = 0;
        int n = 0;
        try {
          n = std::stoi(scenario_choice, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used != scenario_choice.size() || scenario_choice.empty()) {
          std::cerr << "furuta simulate: --scenario " << scenario_choice
                    << ": expected 1, 2, 3, 4 or all\n";
          return 2;
        }
        simulate.scenarios.push_back(n);
      }
      return furuta::app::run_simulate_command(simulate, std::cout, std::cerr);
    }
  } catch (const furuta::config::ConfigError& e) {
    std::cerr << "furuta: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "furuta: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
