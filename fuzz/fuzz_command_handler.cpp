// The daemon's command path on commands decoded from arbitrary LCM bytes. An input is
//   [repeats] [milliseconds between them] <rig_command_t as LCM encodes it>
// The command goes once through Daemon::handle_command (the path an LCM message takes, on a daemon
// built from the shipped rig.toml, its loop not running), then `repeats` times through a fresh
// CommandValidator on a clock stepping by the given interval (a flood). Invariants:
// - every refusal says why, in bounded printable text, and a reply names its request;
// - an e-stop is always accepted; accepted commands never exceed the token bucket's allowance;
// - an accepted start makes an excitation whose duty, at every cycle of its duration, is finite and
//   within the command's amplitude, the configured command limit and the safety limit, and that
//   the 1065 wire format carries within the safety limit.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>
#include <vector>

#include "furuta/config/rig_config.hpp"
#include "furuta/daemon/daemon.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/daemon/safety.hpp"
#include "furuta/firmware_bridge/clock.hpp"
#include "furuta/firmware_bridge/codec_1065.hpp"
#include "furuta/firmware_bridge/phidget_ids.hpp"
#include "furuta/simulator/simulated_rig.hpp"

using namespace furuta;
using namespace furuta::daemon;

namespace {

void check(bool condition) {
  if (!condition) std::abort();  // an invariant broken: libFuzzer reports it as a crash
}

void check_reason(const std::string& reason) {
  check(!reason.empty() && reason.size() < 512);
  for (char c : reason) check(c >= 0x20 && c < 0x7f);
}

// One daemon for the whole run: constructing it per input would drown the fuzzing in set-up.
struct Rig {
  config::RigConfig config = config::load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
  bridge::VirtualClock clock{1'000'000'000};
  std::unique_ptr<sim::SimulatedRig> sim;
  std::unique_ptr<bridge::Transport> motor_usb, encoder_usb;
  std::unique_ptr<DirectBoardLink> motor, encoder;
  DaemonSettings settings;
  lcm::LCM lcm{"memq://"};
  std::unique_ptr<Daemon> daemon;

  Rig() {
    sim = std::make_unique<sim::SimulatedRig>(config.simulation, clock);
    motor_usb = sim->make_transport();
    encoder_usb = sim->make_transport();
    check(motor_usb->open({bridge::kPhidgetsVendorId, bridge::kProductMotorControl1065, {}}) ==
          bridge::TransportStatus::ok);
    check(encoder_usb->open({bridge::kPhidgetsVendorId, bridge::kProductEncoder1047, {}}) ==
          bridge::TransportStatus::ok);
    motor = std::make_unique<DirectBoardLink>(*motor_usb);
    encoder = std::make_unique<DirectBoardLink>(*encoder_usb);
    settings = daemon_settings_from_config(config);
    const auto logs =
        std::filesystem::temp_directory_path() / ("furuta-fuzz-logs-" + std::to_string(getpid()));
    std::filesystem::create_directories(logs);
    settings.recorder.logs_dir = logs;
    // The loop never runs here, so its clock never moves: without this every command after the
    // first burst would only meet the rate limit. The flood below uses the real limits.
    settings.command_limits.max_commands_per_s = 1'000'000'000;
    settings.command_limits.max_stops_per_s = 1'000'000'000;
    settings.command_limits.max_status_requests_per_s = 1'000'000'000;
    daemon = std::make_unique<Daemon>(settings, *motor, *encoder, clock, lcm);
  }
};

Rig& rig() {
  static Rig r;
  return r;
}

void check_excitation(const rig_command_t& command, const Rig& r, const CommandLimits& limits) {
  const ExcitationSpec spec = spec_from_command(command, r.settings.default_excitation);
  check(check_spec_limits(spec, limits).empty());
  std::unique_ptr<Excitation> excitation;
  try {
    excitation = std::make_unique<Excitation>(spec);
  } catch (const std::invalid_argument&) {
    return;  // the daemon refuses it with this message
  }
  const double max_duty = r.config.safety.max_duty;
  const double period_s = static_cast<double>(r.settings.loop.period_ns) * 1e-9;
  const double step = std::max(period_s, spec.duration_s / 4000);
  double arm = 0;
  for (double t = 0; t < spec.duration_s + step; t += step) {
    const double duty = excitation->duty(t, arm);
    check(std::isfinite(duty));
    check(std::fabs(duty) <= spec.amplitude_duty);
    check(std::fabs(duty) <= limits.max_amplitude_duty);
    check(std::fabs(duty) <= max_duty);
    bridge::MotorCommand1065 wire;
    wire.duty_cycle = duty;
    bridge::MotorOutput1065 out;
    check(bridge::to_output_1065(wire, out) == bridge::CodecStatus::ok);
    check(std::fabs(out.duty_cycle()) <= max_duty);
    arm = std::sin(t) * 3.0;  // the arm swings through both bang-bang thresholds
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2 || size > 1 << 16) return 0;
  Rig& r = rig();
  const int repeats = 1 + data[0] % 64;
  const std::int64_t step_ns = std::int64_t{data[1]} * 1'000'000;
  const std::vector<std::uint8_t> bytes(data + 2, data + size);
  rig_command_t command{};
  if (command.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) return 0;

  const rig_status_t reply = r.daemon->handle_command(command);
  check(reply.reply_to_request_id == command.request_id);
  if (!reply.request_accepted) check_reason(reply.request_reason);
  if (command.kind == rig_command_t::KIND_ESTOP) check(reply.request_accepted);

  CommandLimits limits = daemon_settings_from_config(r.config).command_limits;
  CommandValidator validator(limits);
  std::int64_t now = 5'000'000'000;
  int accepted = 0;
  for (int i = 0; i < repeats; ++i, now += step_ns) {
    const CommandDecision d = validator.validate(command, now);
    if (!d.accepted) {
      check_reason(d.reason);
      continue;
    }
    check(d.reason.empty());
    if (command.kind == rig_command_t::KIND_ESTOP ||
        command.kind == rig_command_t::KIND_STATUS_REQUEST) {
      continue;
    }
    ++accepted;
    if (command.kind == rig_command_t::KIND_START_SESSION && i == 0) {
      check_excitation(command, r, limits);
    }
  }
  if (command.kind == rig_command_t::KIND_ESTOP) check(accepted == 0);
  if (command.kind != rig_command_t::KIND_ESTOP &&
      command.kind != rig_command_t::KIND_STATUS_REQUEST) {
    // The burst, plus one token per 1/rate of the time the flood lasted; each kind its own.
    const double rate = command.kind == rig_command_t::KIND_STOP ? limits.max_stops_per_s
                                                                 : limits.max_commands_per_s;
    const double elapsed_s = static_cast<double>(step_ns) * (repeats - 1) * 1e-9;
    check(accepted <= rate + elapsed_s * rate + 1e-6);
  }
  if (command.kind == rig_command_t::KIND_ESTOP) {
    for (int i = 0; i < repeats; ++i) check(validator.validate(command, now).accepted);
  }
  return 0;
}
