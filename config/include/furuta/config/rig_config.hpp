#pragma once
// The rig configuration (TOML): boards, encoder geometry, motor data, the simulated rig.
// Unknown keys are errors, not ignored: a mistyped limit must never become a silent default.

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "furuta/config/config_error.hpp"
#include "furuta/firmware_bridge/board_roles.hpp"
#include "furuta/firmware_bridge/encoder_geometry.hpp"
#include "furuta/model/model.hpp"
#include "furuta/simulator/simulated_rig.hpp"

namespace furuta::config {

enum class UsbBackend : std::uint8_t { simulated, hidapi, libusb };

struct BoardSelection {
  // The board's adapter (bridge::make_motor_board, make_encoder_board) by its configuration name:
  // one built in or registered (bridge::motor_board_kinds, encoder_board_kinds).
  std::string model;
  std::optional<std::string> serial;  // none: the first board of that product
  // Open a board whose firmware version is outside what the codecs know (bridge::known_firmware),
  // with a warning, instead of refusing it.
  bool allow_untested_firmware = false;
};

// The daemon's own settings ([daemon], [daemon.realtime]).
struct DaemonConfig {
  std::int64_t period_ns = 16'000'000;
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";  // ttl=0: traffic stays on this host
  std::string logs_dir = "/var/lib/furuta/logs";
  std::int64_t flush_interval_ms = 1000;
  double rest_check_s = 1.0;
  std::int64_t reconnect_interval_ms = 200;  // a lost board is asked for back this often
  std::int64_t queue_capacity = 4096;
  // Commands that move the motor are signed with this key (docs/security.md); furutad creates it
  // when missing. Signed commands are taken if signed at most command_window_s before the
  // daemon's clock and command_clock_skew_s after it, once; the replay floor survives restarts in
  // command_state_file.
  std::string command_key_file = "/etc/furuta/command.key";
  double command_window_s = 30.0;
  double command_clock_skew_s = 2.0;
  std::string command_state_file = "/var/lib/furuta/command-replay.state";
  // The daemon signs every status it publishes with this key; tools check the signature with the
  // public half (docs/security.md). furutad --create-command-key makes both when missing.
  std::string daemon_key_file = "/etc/furuta/daemon.key";
  std::string daemon_public_key_file = "/etc/furuta/daemon.pub";
  bool realtime = false;
  int fifo_priority = 80;
  int cpu = -1;
  bool lock_memory = true;
};

// [safety]: what stops a session.
// The defaults are the values config/rig.toml states (RigConfig.TheShippedFileStatesTheDefaults).
struct SafetyConfig {
  double arm_limit_rad = 150.0 * 3.14159265358979323846 / 180.0;
  double max_duty = 0.6;
  int stale_report_cycles = 4;
  double min_supply_v = 7.0;
  double max_supply_v = 34.0;
  double stop_braking_fraction = 1.0;
  int stuck_arm_cycles = 4;
  double stuck_arm_min_duty = 0.1;
  double stuck_pendulum_arm_travel_rad = 360.0 * 3.14159265358979323846 / 180.0;
};

// [limits]: what a command may ask for.
struct CommandLimitsConfig {
  double max_amplitude_duty = 0.5;
  double max_duration_s = 600.0;
  double max_arm_switch_rad = 135.0 * 3.14159265358979323846 / 180.0;
  int max_commands_per_s = 5;  // starts
  int max_stops_per_s = 20;
};

// [excitation]: defaults for sessions (a command overrides profile, amplitude, duration, seed).
// [identification]: how sessions of this rig are preprocessed for identification.
struct IdentificationConfig {
  // Low-pass cut-off; the differentiator's pass band ends there and its stop band starts at twice
  // it, which must stay below the Nyquist frequency.
  double cutoff_hz = 15.0;
  int butterworth_order = 8;
  int differentiator_taps = 31;
  // The lag between the logged input and the angles (USB, board and sampling phase), a property of
  // the rig's data path: calibrate it once on a gentle session (`furuta identify` estimates it when
  // this is absent) and set it here.
  std::optional<double> input_lag_ms;
};

// [output_error]: the output-error refinement after LSMI (identification::refine_output_error).
struct OutputErrorConfig {
  bool enabled = true;
  double segment_s = 0.25;   // multiple shooting's segment length
  double substep_s = 1e-3;   // the RK4 substeps' longest
  bool estimate_lag = true;  // the data path's lag as a parameter (else held at the core's 1 ms)
  // A cap only: the fit ends on Levenberg-Marquardt's tolerances, which real data reach later
  // than simulated data do.
  int max_iterations = 200;
};

// [sivia] inner_test: how SIVIA proves a box inside the feasible set (identification::InnerTest),
// spelled in rig.toml as the value's name.
enum class SiviaInnerTest : std::uint8_t { witness, intermediate_value, for_all_data, none };

// [sivia]: guaranteed identification (furuta identify --sivia).
struct SiviaConfig {
  // Which of mu1, mu2, mu3, mu4, mug, fv1, fv2 are unknowns (bisected); the others are carried as
  // intervals: the LSMI estimate +- mu_uncertainty_pct (the paper's Table II).
  std::vector<std::string> unknowns = {"fv1", "fv2"};
  std::array<double, 5> mu_uncertainty_pct = {12, 12, 10, 12, 15};
  std::array<double, 2> fv1_prior = {-1.5, 1.5};
  std::array<double, 2> fv2_prior = {-1.5, 1.5};
  double epsilon = 0.01;
  bool epsilon_relative = true;  // to each unknown's prior width; else absolute
  bool contract = true;
  SiviaInnerTest inner_test = SiviaInnerTest::witness;
  int q = 0;        // samples allowed to be inconsistent
  int threads = 0;  // 0: all cores
  // Error bounds of the preprocessed data, [absolute, relative] per channel (SI units):
  // |error| <= absolute + relative * |value|.
  std::array<double, 2> q2_bound = {0.0, 0.0};
  std::array<double, 2> dq1_bound = {0.0, 0.0};
  std::array<double, 2> dq2_bound = {0.0, 0.0};
  std::array<double, 2> ddq1_bound = {0.0, 0.0};
  std::array<double, 2> ddq2_bound = {0.0, 0.0};
  std::array<double, 2> tau_bound = {0.0, 0.0};
};

// [guaranteed]: the physical inputs of a guaranteed identification that no recording gives
// (identification::physical_inputs). Everything else it bounds comes from the encoders' counts,
// the board's ramp and duty steps, the supply readings and the rest check.
struct GuaranteedConfig {
  double prior_percent = 50.0;  // mu1, mu2, mu3, mu4, mug: [nominal] (CAD) +- this
  std::array<double, 2> friction_prior = {0.0, 1.0};  // fv1 and fv2 [N m s]: never negative
  // The data path: an angle's host time minus the time of the state it shows, against the times
  // the duty commands were written.
  std::array<double, 2> lag_ms = {0.0, 2.0};
  // Relative tolerances [%] of [motor]'s eq. 4 figures: no_load_speed_rpm,
  // speed_torque_gradient_rpm_per_nm, motor_efficiency, gear_efficiency.
  std::array<double, 4> motor_tolerance_pct = {1.0, 1.0, 1.0, 1.0};
  // The windowed set inversion (identify --guaranteed): the search box is the output-error
  // estimate +- search_sd of its standard deviations; each recording is inverted over `windows`
  // chained windows of window_s from its first command, which starts from rest with the arm's
  // speed within arm_rest_speed_rad_s (the daemon's rest check watches the pendulum only).
  double search_sd = 5.0;
  double window_s = 0.25;
  int windows = 8;
  double arm_rest_speed_rad_s = 0.01;
};

// [automation]: what the identification trigger (`furuta process-logs`, furuta-identify.path) does
// with the session logs that are complete. Sessions are told apart by the label they were started
// with (`--label`), as their start record carries it.
struct AutomationConfig {
  std::vector<std::string> fit_labels = {"bang-bang"};  // sessions fitted together
  int fit_sessions = 2;  // how many (the oldest pending first) form one identification
  // Plus the oldest pending session with this label, held out; empty: identify without one.
  std::string validation_label = "validation";
  bool sivia = true;        // guaranteed identification after the LSMI, with [sivia]'s settings
  bool guaranteed = false;  // the windowed set inversion ([guaranteed]; minutes per batch)
  bool simulate = true;     // the paper's scenarios by guaranteed simulation (Table III)
  double simulate_seconds = 4.0;  // each scenario's duration
  std::string identifications_dir = "/var/lib/furuta/identifications";
};

// The excitation profiles [excitation] profile may name, in daemon::ProfileKind's order: the one
// list the configuration, the daemon and the start command's checks take their names from.
inline constexpr std::array<const char*, 6> kExcitationProfiles = {
    "bang_bang", "free_decay", "step", "prbs", "chirp", "multisine"};

struct ExcitationConfig {
  std::string profile = "bang_bang";
  double amplitude_duty = 0.3;
  double duration_s = 10.0;
  std::int64_t seed = 1;
  double switch_period_s = 0.5;
  double switch_period_jitter = 0.0;
  double arm_switch_rad = 86.0 * 3.14159265358979323846 / 180.0;
  double step_time_s = 0.5;
  double prbs_bit_period_s = 0.048;
  int prbs_order = 9;
  double chirp_f0_hz = 0.2;
  double chirp_f1_hz = 5.0;
  int multisine_components = 8;
  double multisine_f_min_hz = 0.2;
  double multisine_f_max_hz = 5.0;
  // The motor board's duty ramp (its adapter's acceleration).
  double board_acceleration_pct_per_s = 6250.0;
};

struct RigConfig {
  std::string name;
  UsbBackend backend = UsbBackend::simulated;
  BoardSelection motor_board{.model = std::string(bridge::kShippedMotorBoard),
                             .serial = {},
                             .allow_untested_firmware = false};
  BoardSelection encoder_board{.model = std::string(bridge::kShippedEncoderBoard),
                               .serial = {},
                               .allow_untested_firmware = false};
  int pendulum_channel = 0;
  bridge::EncoderGeometry arm_encoder;  // gear_ratio = motor.total_ratio()
  bridge::EncoderGeometry pendulum_encoder;
  model::MotorData motor;
  sim::SimulatedRigConfig simulation;                // geometry and motor copied in from the above
  std::optional<model::Parameters<double>> nominal;  // CAD values, for comparison only
  DaemonConfig daemon;
  SafetyConfig safety;
  CommandLimitsConfig limits;
  ExcitationConfig excitation;
  IdentificationConfig identification;
  OutputErrorConfig output_error;
  SiviaConfig sivia;
  GuaranteedConfig guaranteed;
  AutomationConfig automation;
  std::string source_text;  // the file verbatim, so logs can carry it
  std::string source_name;
};

RigConfig load_rig_config(const std::filesystem::path& path);  // throws ConfigError
// A configuration file's text; ConfigError naming the file when it cannot be opened or read.
std::string read_config_text(const std::filesystem::path& path);
RigConfig parse_rig_config(const std::string& text, const std::string& source_name);
// The configuration tools read without --config: the installed one (/etc/furuta/rig.toml), or,
// for a program run from the build tree it was built in, the source tree's config/rig.toml.
std::filesystem::path default_rig_config_path();
// The steps the motor board's readings move in, from its adapter ([boards.motor] model).
bridge::MotorResolution motor_resolution(const RigConfig& rig);
// One count of the pendulum's encoder, in radians of the pendulum ([encoders.pendulum]).
double pendulum_resolution_rad(const RigConfig& rig);
// The joint angles the daemon logs for a sample's counts: the counts through [encoders.arm] and
// [encoders.pendulum].
double arm_angle_rad(const RigConfig& rig, std::int64_t arm_counts);
double pendulum_angle_rad(const RigConfig& rig, std::int64_t pendulum_counts);

}  // namespace furuta::config
