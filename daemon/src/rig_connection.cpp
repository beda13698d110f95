#include "furuta/daemon/rig_connection.hpp"

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "furuta/firmware_bridge/board_roles.hpp"
#include "furuta/firmware_bridge/replay_transport.hpp"
#include "furuta/firmware_bridge/usb_backends.hpp"
#include "furuta/session_log/session_log.hpp"

namespace furuta::daemon {

using bridge::TransportStatus;

namespace {

void open_or_throw(bridge::Transport& transport, const bridge::UsbIdentity& usb,
                   const std::optional<std::string>& serial, const char* what) {
  const TransportStatus status = transport.open({usb.vendor_id, usb.product_id, serial});
  if (status == TransportStatus::ok) return;
  std::string message = std::string("cannot open the ") + what + " (" +
                        std::string(bridge::phidget_product_name(usb.product_id)) +
                        (serial ? ", serial " + *serial : std::string()) +
                        "): " + std::string(bridge::to_string(status));
  if (status == TransportStatus::access_denied) {
    message +=
        "; install systemd/70-furuta-phidgets.rules into /etc/udev/rules.d/, run "
        "`udevadm control --reload`, replug, and add the user to group furuta";
  } else if (status == TransportStatus::not_found) {
    message += "; `furuta devices` lists what is connected";
  }
  throw std::runtime_error(message);
}

// A board whose firmware the codecs do not know is refused, or opened with a warning when the
// configuration allows it: its reports might be laid out otherwise and decode as wrong angles.
void check_firmware(const bridge::DeviceInfo& info, const config::BoardSelection& selection,
                    const char* what, const char* section, std::vector<std::string>& warnings) {
  if (bridge::firmware_known(info.product_id, info.vendor_class_interface, info.firmware_version)) {
    return;
  }
  const std::optional<bridge::FirmwareRange> known =
      bridge::known_firmware(info.product_id, info.vendor_class_interface);
  std::string message = std::string("the ") + what + " (" + info.product_name + ", serial " +
                        (info.serial.empty() ? std::string("?") : info.serial) + ", " +
                        (info.vendor_class_interface ? "vendor-class" : "HID") +
                        " interface) has firmware " + std::to_string(info.firmware_version) +
                        ", which furuta's codecs do not know (" +
                        (known ? "they know " + std::to_string(known->first) + "-" +
                                     std::to_string(known->last) + " for this board and interface"
                               : std::string("none for this board and interface")) +
                        ")";
  if (!selection.allow_untested_firmware) {
    throw std::runtime_error(message + ": its reports may be laid out otherwise. Set " + section +
                             " allow_untested_firmware = true to try it anyway, and check it "
                             "as docs/hardware-checklist.md says");
  }
  warnings.push_back(message +
                     "; opened anyway (allow_untested_firmware): check its decoded "
                     "angles and duty against docs/hardware-checklist.md");
}

}  // namespace

RigConnection connect_rig(const config::RigConfig& config, const ConnectOptions& options) {
  RigConnection c;
  const bool virtual_time = options.virtual_time && options.backend != BackendChoice::from_config;
  if (virtual_time) {
    c.clock = std::make_unique<bridge::VirtualClock>(options.virtual_start_ns);
  } else if (options.backend == BackendChoice::replay) {
    // The recorded reports carry the recording's times: play them at the pace they came.
    c.base_clock = std::make_unique<bridge::MonotonicClock>();
    c.clock = std::make_unique<bridge::OffsetClock>(
        *c.base_clock, options.virtual_start_ns - c.base_clock->now_ns());
  } else {
    c.clock = std::make_unique<bridge::MonotonicClock>();
  }

  bool threaded = false;
  if (options.backend == BackendChoice::replay) {
    const session_log::SessionLog log = session_log::load_session_log(options.replay_log);
    if (!log.start) {
      throw std::runtime_error(options.replay_log.string() + ": no session start record to replay");
    }
    c.motor = std::make_unique<bridge::ReplayTransport>(
        session_log::usb_trace_from_log(log, furuta::rig_usb_report_t::BOARD_MOTOR), *c.clock,
        bridge::ReplayTransport::OutputMode::record);
    c.encoder = std::make_unique<bridge::ReplayTransport>(
        session_log::usb_trace_from_log(log, furuta::rig_usb_report_t::BOARD_ENCODER), *c.clock,
        bridge::ReplayTransport::OutputMode::record);
    c.description = "replay of " + options.replay_log.string();
  } else if (options.backend == BackendChoice::simulated ||
             config.backend == config::UsbBackend::simulated) {
    c.simulated_rig = std::make_unique<sim::SimulatedRig>(config.simulation, *c.clock);
    c.motor = c.simulated_rig->make_transport();
    c.encoder = c.simulated_rig->make_transport();
    c.description = "simulated rig";
  } else {
    const bool libusb = config.backend == config::UsbBackend::libusb;
    c.motor = libusb ? bridge::make_libusb_transport() : bridge::make_hidapi_transport();
    c.encoder = libusb ? bridge::make_libusb_transport() : bridge::make_hidapi_transport();
    c.description = libusb ? "libusb" : "hidapi";
    threaded = true;  // hardware: stamp each report at its arrival
  }
  open_or_throw(*c.motor, bridge::motor_board_kind(config.motor_board.model).usb,
                config.motor_board.serial, "motor board");
  open_or_throw(*c.encoder, bridge::encoder_board_kind(config.encoder_board.model).usb,
                config.encoder_board.serial, "encoder board");
  // A replay plays what was recorded from boards that were accepted then.
  if (options.backend != BackendChoice::replay) {
    check_firmware(c.motor->device_info(), config.motor_board, "motor board", "[boards.motor]",
                   c.warnings);
    check_firmware(c.encoder->device_info(), config.encoder_board, "encoder board",
                   "[boards.encoder]", c.warnings);
  }
  if (threaded) {
    c.motor_link = std::make_unique<ThreadedBoardLink>(*c.motor);
    c.encoder_link = std::make_unique<ThreadedBoardLink>(*c.encoder);
  } else {
    c.motor_link = std::make_unique<DirectBoardLink>(*c.motor);
    c.encoder_link = std::make_unique<DirectBoardLink>(*c.encoder);
  }
  return c;
}

ExcitationSpec excitation_from_config(const config::ExcitationConfig& e) {
  ExcitationSpec s;
  s.kind = parse_profile_kind(e.profile).value_or(ProfileKind::bang_bang);
  s.amplitude_duty = e.amplitude_duty;
  s.duration_s = e.duration_s;
  s.seed = static_cast<std::uint64_t>(e.seed);
  s.switch_period_s = e.switch_period_s;
  s.switch_period_jitter = e.switch_period_jitter;
  s.arm_switch_rad = e.arm_switch_rad;
  s.step_time_s = e.step_time_s;
  s.prbs_bit_period_s = e.prbs_bit_period_s;
  s.prbs_order = e.prbs_order;
  s.chirp_f0_hz = e.chirp_f0_hz;
  s.chirp_f1_hz = e.chirp_f1_hz;
  s.multisine_components = e.multisine_components;
  s.multisine_f_min_hz = e.multisine_f_min_hz;
  s.multisine_f_max_hz = e.multisine_f_max_hz;
  return s;
}

DaemonSettings daemon_settings_from_config(const config::RigConfig& config) {
  DaemonSettings d;
  d.rig_name = config.name;
  LoopSettings& loop = d.loop;
  loop.period_ns = config.daemon.period_ns;
  loop.safety.arm_limit_rad = config.safety.arm_limit_rad;
  loop.safety.max_duty = config.safety.max_duty;
  loop.safety.stale_report_cycles = config.safety.stale_report_cycles;
  loop.safety.min_supply_v = config.safety.min_supply_v;
  loop.safety.max_supply_v = config.safety.max_supply_v;
  loop.safety.stuck_arm_cycles = config.safety.stuck_arm_cycles;
  loop.safety.stuck_arm_min_duty = config.safety.stuck_arm_min_duty;
  loop.safety.stuck_pendulum_arm_travel_rad = config.safety.stuck_pendulum_arm_travel_rad;
  loop.stop_braking_fraction = config.safety.stop_braking_fraction;
  loop.arm_encoder = config.arm_encoder;
  loop.pendulum_encoder = config.pendulum_encoder;
  loop.pendulum_channel = config.pendulum_channel;
  loop.motor_board = config.motor_board.model;
  loop.encoder_board = config.encoder_board.model;
  loop.rest_check_s = config.daemon.rest_check_s;
  loop.reconnect_interval_ns = config.daemon.reconnect_interval_ms * 1'000'000;
  loop.acceleration_pct_per_s = config.excitation.board_acceleration_pct_per_s;

  d.recorder.logs_dir = config.daemon.logs_dir;
  d.recorder.flush_interval = std::chrono::milliseconds(config.daemon.flush_interval_ms);
  d.recorder.rig_config_toml = config.source_text;
  d.recorder.software_version = kSoftwareVersion;

  d.command_limits.max_amplitude_duty = config.limits.max_amplitude_duty;
  d.command_limits.max_duration_s = config.limits.max_duration_s;
  d.command_limits.max_arm_switch_rad = config.limits.max_arm_switch_rad;
  d.command_limits.max_commands_per_s = config.limits.max_commands_per_s;
  d.default_excitation = excitation_from_config(config.excitation);
  d.command_limits.max_stops_per_s = config.limits.max_stops_per_s;
  d.command_auth.window =
      std::chrono::nanoseconds(std::llround(config.daemon.command_window_s * 1e9));
  d.command_auth.max_ahead =
      std::chrono::nanoseconds(std::llround(config.daemon.command_clock_skew_s * 1e9));

  d.realtime.enabled = config.daemon.realtime;
  d.realtime.fifo_priority = config.daemon.fifo_priority;
  d.realtime.cpu = config.daemon.cpu;
  d.realtime.lock_memory = config.daemon.lock_memory;
  d.queue_capacity = static_cast<std::size_t>(config.daemon.queue_capacity);
  return d;
}

}  // namespace furuta::daemon
