#pragma once
// The `furuta` command's subcommands, each a function over plain options so tests can call them.

#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>

namespace furuta::app {

struct DevicesOptions {
  bool simulated = false;  // list the simulated rig's boards instead of the USB bus
};
// Lists connected Phidget boards; says clearly when there are none or access is denied.
// Returns 0 when at least one board was listed, 1 when none, 2 when USB could not be read.
int run_devices_command(const DevicesOptions& options, std::ostream& out, std::ostream& err);

struct SimulateOptions {
  std::filesystem::path config_path;  // rig configuration (TOML)
  std::filesystem::path output_dir;   // where the session's CSV and USB traces go
  double duration_s = 10.0;
  double amplitude_duty = 0.3;
  double switch_period_s = 0.5;
  std::optional<std::uint64_t> seed;  // overrides the configuration's
  bool real_time = false;             // pace by the wall clock instead of virtual time
};
// The simulated-rig demo: a bang-bang session through the bridge, decoded samples to CSV, USB
// traces recorded, a summary printed. (The daemon replaces it as the main job.)
int run_simulate_command(const SimulateOptions& options, std::ostream& out, std::ostream& err);

}  // namespace furuta::app
