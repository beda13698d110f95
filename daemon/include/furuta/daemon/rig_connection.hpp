#pragma once
// From a rig configuration to a running daemon's parts: the boards opened through the configured
// backend (hidapi, libusb, the simulated rig, or a session log replayed), the clock that goes with
// them, and the daemon's settings.

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "furuta/config/rig_config.hpp"
#include "furuta/daemon/board_link.hpp"
#include "furuta/daemon/daemon.hpp"
#include "furuta/firmware_bridge/clock.hpp"
#include "furuta/firmware_bridge/transport.hpp"
#include "furuta/simulator/simulated_rig.hpp"

namespace furuta::daemon {

enum class BackendChoice { from_config, simulated, replay };

struct ConnectOptions {
  BackendChoice backend = BackendChoice::from_config;
  std::filesystem::path replay_log;  // for BackendChoice::replay
  bool virtual_time = false;         // simulated/replay: a VirtualClock instead of real time
  // Where that clock starts. A replay in real time shifts the monotonic clock so that this is now.
  std::int64_t virtual_start_ns = 0;
};

struct RigConnection {
  std::unique_ptr<bridge::Clock> base_clock;  // what `clock` is built on, when it is shifted
  std::unique_ptr<bridge::Clock> clock;
  std::unique_ptr<sim::SimulatedRig> simulated_rig;  // when simulated
  std::unique_ptr<bridge::Transport> motor;
  std::unique_ptr<bridge::Transport> encoder;
  std::unique_ptr<BoardLink> motor_link;
  std::unique_ptr<BoardLink> encoder_link;
  std::string description;  // "simulated rig", "hidapi", "replay of ...", for messages
  // What the caller must show the user: a board opened although its firmware is untested.
  std::vector<std::string> warnings;
};

// Opens both boards. Throws std::runtime_error with a message naming the board and the status (and,
// for access_denied, the udev rule to install), or naming the board, its serial and firmware when
// the codecs do not know that firmware and the configuration does not allow it.
RigConnection connect_rig(const config::RigConfig& config, const ConnectOptions& options);

ExcitationSpec excitation_from_config(const config::ExcitationConfig& config);
DaemonSettings daemon_settings_from_config(const config::RigConfig& config);

// "furuta <version> (git <commit>)": what the binaries were built from, as --version prints it and
// session logs and results.json record it.
extern const char* const kSoftwareVersion;

}  // namespace furuta::daemon
