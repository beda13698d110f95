#pragma once
// The safety supervisor's rules (pure, checked every cycle), and the validation of commands that
// arrive over LCM. Neither allocates on the loop's path.

#include <cstdint>
#include <string>
#include <string_view>

#include "furuta/daemon/excitation.hpp"
#include "furuta/rig_command_t.hpp"

namespace furuta::daemon {

// Why a session ended (or a command was refused), as the log and status say it.
enum class StopReason : std::uint8_t {
  none,
  duration_reached,
  stop_command,
  estop_command,
  signal,  // SIGINT / SIGTERM
  arm_angle_limit,
  duty_limit,
  stale_motor_reports,  // no fresh motor board report for N cycles
  stale_encoder_reports,
  usb_error,
  under_voltage,
  over_temperature,
  supply_out_of_range,
  arm_encoder_stuck,       // the arm's count stands still while the motor is driven
  pendulum_encoder_stuck,  // the pendulum's count stands still while the arm swings
  log_error,               // the session log could not be written (disk full, I/O error)
  exception,               // anything thrown inside the loop
  pendulum_fell,           // a balance session: the pendulum left the fall limit after the catch
};
std::string_view to_string(StopReason reason);  // snake_case, stable: logs and tests match on it
bool is_fault(StopReason reason);               // everything but duration/stop/none

struct SafetyLimits {
  double arm_limit_rad = 2.6;   // |q1| beyond this stops the session
  double max_duty = 0.6;        // |duty| commanded beyond this stops it (a bug upstream)
  int stale_report_cycles = 4;  // cycles without a fresh report from a board
  double min_supply_v = 7.0;    // the vendor library's "too low"
  double max_supply_v = 34.0;   // its "warning" threshold
  // A frozen encoder: the arm limit and the bang-bang thresholds read the arm's count, so a count
  // that stops while the motor drives must stop the session before the arm reaches its stop.
  int stuck_arm_cycles = 4;         // fresh motor board reports in a row with the same count...
  double stuck_arm_min_duty = 0.1;  // ...while |applied duty| is at least this
  double stuck_pendulum_arm_travel_rad = 6.283185307179586;  // arm travel with no pendulum count
};

// What the supervisor looks at, once per cycle.
struct SafetyInput {
  double arm_angle_rad = 0.0;
  double commanded_duty = 0.0;
  int cycles_without_motor_report = 0;
  int cycles_without_encoder_report = 0;
  bool motor_over_temperature = false;  // the motor board's protection (bridge::MotorReading)
  bool motor_under_voltage = false;
  double supply_voltage_v = 12.0;
  bool have_supply_reading = false;  // before the first report the supply is unknown
  int arm_still_driven_cycles = 0;   // see SafetyLimits::stuck_arm_cycles
  double arm_travel_pendulum_still_rad = 0.0;
};

// The first rule broken, in a fixed order (board flags, supply, staleness, angle, duty, stuck
// encoders), or none.
StopReason check_safety(const SafetyLimits& limits, const SafetyInput& input) noexcept;

// Each kind of command has a budget of its own (a token bucket, bursts of the rate's size), so a
// flood of one kind never uses up what another needs: e-stops have none and are always taken.
struct CommandLimits {
  double max_amplitude_duty = 0.5;
  double max_duration_s = 600.0;
  double max_arm_switch_rad = 2.4;     // bang-bang thresholds must sit inside the safety limit
  int max_commands_per_s = 5;          // starts (and any other command that moves the motor)
  int max_stops_per_s = 20;            // stops
  int max_status_requests_per_s = 20;  // status requests
  int max_label_chars = 64;
  // Answers the daemon publishes: refusals, and e-stops (each e-stop is acted on, answered or
  // not), so a flood is not echoed onto the group. Accepted starts, stops and status requests
  // are always answered; they have budgets above.
  int max_refusal_replies_per_s = 20;
  int max_estop_replies_per_s = 50;
};

// Why a start's own fields are outside `limits` (profile, amplitude, duration, label, seed; the
// first broken, naming the field: "amplitude_duty: 0.9 above the limit 0.5"), or "": the check
// the daemon refuses a start with before anything else, for callers that check a command line.
std::string start_session_problem(const rig_command_t& command, const CommandLimits& limits);

// Why a command was refused, for the counts in the status.
enum class CommandRefusal : std::uint8_t {
  none,
  start_budget,
  stop_budget,
  status_budget,
  invalid,  // outside the limits, unknown, or a start the daemon cannot take now
};

struct CommandDecision {
  bool accepted = false;
  std::string reason;  // why not, naming the field: "amplitude_duty: 0.9 above the limit 0.5"
  CommandRefusal refusal = CommandRefusal::none;
};

// `per_second` tokens a second, in bursts of that size, full at first use. Time comes from the
// caller, so it runs in virtual time too.
class TokenBucket {
 public:
  bool take(double per_second, std::int64_t now_ns);

 private:
  double tokens_ = -1.0;
  std::int64_t last_refill_ns_ = 0;
};

// Validates commands and rate-limits them (e-stop is never rate-limited: it must always get
// through).
class CommandValidator {
 public:
  explicit CommandValidator(const CommandLimits& limits) : limits_(limits) {}
  CommandDecision validate(const furuta::rig_command_t& command, std::int64_t now_ns);

 private:
  CommandLimits limits_;
  TokenBucket starts_;
  TokenBucket stops_;
  TokenBucket status_requests_;
};

// The excitation for an accepted START_SESSION: the command's profile, amplitude, duration and seed
// over the configured defaults (the profile-specific parameters stay the configured ones).
// Throws std::invalid_argument for an unknown profile or a negative seed (validate() refuses both).
ExcitationSpec spec_from_command(const furuta::rig_command_t& command,
                                 const ExcitationSpec& defaults);

// Where a complete excitation breaks the command limits, naming the field ("" when none): the
// command's amplitude and duration, and the configured bang-bang threshold, which no command
// carries but which must still sit inside max_arm_switch_rad.
std::string check_spec_limits(const ExcitationSpec& spec, const CommandLimits& limits);

}  // namespace furuta::daemon
