#pragma once
// Data from other rigs and loggers (MATLAB exports, other programs) as CSV, mapped by a small
// import spec (TOML) onto the quantities identification needs.

#include <array>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "furuta/identification/board_clock.hpp"
#include "furuta/identification/physical_inputs.hpp"

namespace furuta::identification {

// A voltage-driven motor (other rigs): tau = ratio * efficiency * k_t (V - k_e omega_motor) / R.
struct VoltageMotor {
  double torque_constant_nm_per_a = 0;
  double back_emf_v_s_per_rad = 0;
  double resistance_ohm = 0;
  double gear_ratio = 1;
  double efficiency = 1;
};

enum class AngleUnit { rad, deg, counts };
enum class InputKind { duty, voltage, torque };
enum class PendulumZero { down, up };
// What the recorded input did between two samples, for the output-error fit's simulation: held
// (a logger of step commands, a DAC), linear (a ramped duty) or a smooth curve through the
// samples (cubic Hermite with Catmull-Rom slopes: a measured continuous voltage).
enum class InputBetweenSamples { held, linear, cubic };

struct CsvColumn {
  std::string name;    // header name (or 1-based index as text when the file has no header)
  double scale = 1.0;  // multiplied after unit conversion (e.g. -1 for a flipped encoder)
};

// [csv] section of an import spec, e.g.
//   [csv]
//   delimiter = ","          time = "t"        time_unit = "s" | "ms" | "us"
//   arm_angle = "theta"      pendulum_angle = "alpha"     angle_unit = "deg" | "rad" | "counts"
//   arm_counts_per_rev = 4096   pendulum_counts_per_rev = 4096     (angle_unit = "counts")
//   pendulum_zero = "up" | "down"
//   input = "u"   input_kind = "voltage" | "duty" | "torque"
// and optionally each reading's own time (docs/csv-import.md, "Each reading at its own time"):
//   arm_time = "t_arm"   pendulum_time = "t_pend"   input_time = "t_cmd"   (in time_unit)
//   input_rate_limit = 62.5   (the actuator slews towards each new input at most this fast, per s)
//   supply = "v_bus"          (duty only: the supply [V], scaling the duty by it / nominal)
//   input_scale_sd = 0.05     (the input's scale known to 5 %: fitted, its sd carried)
//   arm_board_time = "arm_ticks"  pendulum_board_time = "enc_us"  (each board's own clock)
//   input_at_start = 0        (the input before its first time: a start at rest)
// and, for input_kind = "voltage" only, the rig's DC motor:
//   [motor]
//   torque_constant_nm_per_a = 0.05   back_emf_v_s_per_rad = 0.05   resistance_ohm = 2.5
//   gear_ratio = 5 (default 1)        efficiency = 0.9 (default 1, in (0, 1])
// and, for a guaranteed identification (duty input only), the recording's bounds
// (docs/csv-import.md, "Guaranteed identification"):
//   [guaranteed]
//   arm_angle_error = 0.5  pendulum_angle_error = 0.5  pendulum_zero_error = 2.5  (angle_unit)
//   lag_ms = [0, 2]   arm_rest_speed_rad_s = 0.01   supply_error_v = 0.02 | supply_v = [11.9, 12.1]
struct CsvImportSpec {
  char delimiter = ',';
  bool has_header = true;
  CsvColumn time, arm_angle, pendulum_angle, input;
  double time_scale_s = 1.0;  // 1 s, 1e-3 ms, 1e-6 us
  // Where time_unit was read ("import.toml:3"), for import_csv's refusal of an implausible sample
  // period; empty for a spec built in code.
  std::string time_unit_at;
  AngleUnit angle_unit = AngleUnit::rad;
  double arm_counts_per_rev = 0, pendulum_counts_per_rev = 0;
  // Each angle's resolution [rad] (arm, pendulum): one count with angle_unit = "counts", else
  // arm_resolution / pendulum_resolution in the angle unit when the spec states them; 0 when it
  // does not say.
  std::array<double, 2> resolution_rad = {0, 0};
  PendulumZero pendulum_zero = PendulumZero::down;
  InputKind input_kind = InputKind::duty;
  InputBetweenSamples input_between_samples = InputBetweenSamples::linear;
  // The [motor] table: set exactly when input_kind = voltage (pass *voltage_motor to preprocess or
  // identify).
  std::optional<VoltageMotor> voltage_motor;
  // Optional columns (an empty name: not in the file): when each angle was read and when the input
  // took effect, on the time column's clock; the supply voltage behind a duty.
  CsvColumn arm_time, pendulum_time, input_time, supply;
  // Optional: each angle's stamp on its board's own clock, in any unit (its rate is fitted); the
  // angle's times are then mapped from it onto the host's (fit_board_clock).
  CsvColumn arm_board_time, pendulum_board_time;
  // The input, after its scale, changes towards each new value at most this fast [unit/s] (a motor
  // board's ramp); 0: as input_between_samples says.
  double input_rate_limit_per_s = 0;
  // How well the input's scale is known, as a relative standard deviation (a torque command of
  // uncertain gain, a voltage read through a divider): the refinement fits the input's gain around
  // 1 with it as its prior, so the standard deviations carry it. 0: the scale is exact.
  double input_scale_sd = 0;
  // The input in force before its first recorded time (after input_scale): a recording that
  // starts at rest before its first command. Unset: the first value, held back.
  std::optional<double> input_at_start;
  // The [guaranteed] table, in radians, seconds and volts, each with the spec's file, line and key
  // as its provenance: what `furuta identify --guaranteed` takes from the recording.
  std::optional<RecordingBounds> bounds;
};

// Parses the [csv], [motor] and [guaranteed] tables of an import spec file; errors name file, line
// and field (ConfigError).
CsvImportSpec load_csv_import_spec(const std::filesystem::path& path);
CsvImportSpec parse_csv_import_spec(const std::string& text, const std::string& source_name);

// The recording as it was, before any resampling, in the project's units: each angle and the input
// at their own times (the row's time unless the spec names a column for it). A reading whose time
// repeats the previous one's is the same reading (a logger that copies the last value into every
// row) and is kept once. The output-error refinement takes every reading at its own time.
struct RecordedSeries {
  std::vector<double> q1_t_s, q1_rad, q2_t_s, q2_rad, input_t_s, input;
  std::vector<double> supply_v;          // every row's supply reading, when the spec names one
  std::optional<double> input_at_start;  // the spec's: the input before its first time
  // Per angle: the board clock its times were mapped from (the spec's *_board_time), or nothing.
  std::array<std::optional<BoardClock>, 2> board_clock;
  std::vector<std::string> warnings;  // a board clock that did not keep time
  bool empty() const { return q1_t_s.empty(); }
};

// A recording in the project's conventions: seconds, radians, pendulum zero hanging down, on a
// uniform time grid (the angles and input interpolated to the row times where they have their own).
struct ImportedSeries {
  double sample_period_s = 0;
  std::vector<double> t_s, q1_rad, q2_rad;
  std::vector<double> input;  // duty [-1, 1], volts, or N m at the arm, per input_kind
  InputKind input_kind = InputKind::duty;
  std::vector<std::string>
      warnings;  // e.g. "irregular time stamps (max gap 23 ms): resampled to 10 ms"
  RecordedSeries recorded;
  double input_rate_limit_per_s = 0;  // the spec's
  double input_scale_sd = 0;          // the spec's
};

class CsvImportError : public std::runtime_error {
 public:
  CsvImportError(const std::string& file, int line, const std::string& field,
                 const std::string& problem);
  const std::string& file() const { return file_; }
  int line() const { return line_; }
  const std::string& field() const { return field_; }

 private:
  std::string file_;
  int line_;
  std::string field_;
};

// The sample periods a Furuta pendulum recording can have (docs/csv-import.md says why): outside,
// time_unit is most likely wrong and import_csv refuses the file.
inline constexpr double kMinSamplePeriodS = 1e-4;
inline constexpr double kMaxSamplePeriodS = 0.1;

// Reads a CSV per the spec. Sample period = median time step; when time steps vary by more than 1 %
// of it, the series is resampled (linear interpolation) onto the uniform grid and a warning says
// so. Errors (missing column, non-numeric cell, repeated or decreasing time, too few rows, a sample
// period outside [kMinSamplePeriodS, kMaxSamplePeriodS]) name file, line and column.
ImportedSeries import_csv(const std::filesystem::path& csv, const CsvImportSpec& spec);

}  // namespace furuta::identification
