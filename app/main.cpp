// furuta: the command-line entry point. Thin: options in, a subcommand function out.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "commands.hpp"
#include "furuta/config/rig_config.hpp"

int main(int argc, char** argv) {
  CLI::App app{"furuta: identification experiments on a rotary inverted pendulum"};
  app.require_subcommand(1);

  furuta::app::DevicesOptions devices;
  CLI::App* devices_cmd = app.add_subcommand("devices", "List connected Phidget boards");
  devices_cmd->add_flag("--simulated", devices.simulated,
                        "List the simulated rig's boards instead");

  furuta::app::SimulateOptions simulate;
  simulate.config_path = furuta::config::default_rig_config_path();
  simulate.output_dir = "furuta-sim-session";
  CLI::App* simulate_cmd = app.add_subcommand(
      "simulate", "Run a bang-bang session on the simulated rig through the bridge");
  simulate_cmd->add_option("--config", simulate.config_path, "Rig configuration (TOML)")
      ->check(CLI::ExistingFile);
  simulate_cmd->add_option("--output", simulate.output_dir, "Directory for the CSV and USB traces");
  simulate_cmd->add_option("--duration", simulate.duration_s, "Session length [s]")
      ->check(CLI::Range(0.1, 3600.0));
  simulate_cmd->add_option("--amplitude", simulate.amplitude_duty, "Bang-bang duty amplitude")
      ->check(CLI::Range(0.0, 1.0));
  simulate_cmd->add_option("--switch-period", simulate.switch_period_s, "Bang-bang half period [s]")
      ->check(CLI::Range(0.016, 60.0));
  simulate_cmd->add_option("--seed", simulate.seed,
                           "Seed for noise and jitter (default: the configuration's)");
  simulate_cmd->add_flag("--real-time", simulate.real_time, "Pace by the wall clock");

  CLI11_PARSE(app, argc, argv);

  try {
    if (*devices_cmd) return furuta::app::run_devices_command(devices, std::cout, std::cerr);
    if (*simulate_cmd) return furuta::app::run_simulate_command(simulate, std::cout, std::cerr);
  } catch (const std::exception& e) {
    std::cerr << "furuta: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
