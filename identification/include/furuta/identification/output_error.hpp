#pragma once
// Output-error refinement: the model simulated with the input as the board applied it,
// fitted to the measured angles at their own times by multiple shooting (Bock 1981), starting from
// LSMI. No accelerations are formed, so the 16 ms sampling's differentiation bias is gone. The fit
// stays in the physical region (docs/model.md) by its parametrisation.

#include <array>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "furuta/config/rig_config.hpp"
#include "furuta/identification/board_clock.hpp"
#include "furuta/identification/csv_import.hpp"
#include "furuta/identification/preprocessing.hpp"
#include "furuta/model/model.hpp"
#include "furuta/session_log/session_log.hpp"

namespace furuta::identification {

// One measured angle: joint 0 is q1 (arm), 1 is q2 (pendulum).
struct OeObservation {
  double t_s = 0;  // when the host got it: the state's time plus the data path's lag
  int joint = 0;
  double angle_rad = 0;
};

// One experiment as the output-error fit needs it: the angles at their own times and the input
// the actuator applied, as a piecewise-linear function of time on the same clock.
// Where an angle's assumed noise came from: the encoder's resolution (a log's configuration, a
// CSV's counts or stated resolution), or, when a CSV does not say, its readings' own scatter
// (angle_noise_from_readings).
enum class AngleNoiseSource { encoder_resolution, estimated_from_readings };
// Where a joint's observation times came from: the host's stamps, the board's clock mapped onto
// the host's (fit_board_clock), or some experiments each.
enum class TimeStamps { host, board_clock, mixed };

struct OeExperiment {
  std::string name;
  std::vector<OeObservation> observations;  // time order
  // The applied input at the breakpoints (linear between, held outside): duty, volts or N m.
  std::vector<double> input_t_s, input;
  // Its slope at each breakpoint [1/s] for a cubic Hermite curve between them; empty: linear.
  std::vector<double> input_slope;
  // Duty only, per breakpoint (in force from it to the next): what an applied duty of exactly 0
  // does, as a fraction of eq. 4's braking at zero duty (0: the motor coasts).
  std::vector<double> braking_fraction;
  InputKind input_kind = InputKind::duty;
  double supply_scale = 1.0;  // duty: effective duty = duty * supply voltage / nominal voltage
  VoltageMotor voltage_motor;
  // The input's gain is fitted around 1 with this relative standard deviation as its prior (the
  // uncertainty of the supply reading or of a recorded voltage's scale); 0 holds it at 1. The
  // motor board reports its supply in steps of 80/2048 V (its adapter's step), 0.33 % of 12 V,
  // and every inertia scales with the gain, so without it the standard deviations would ignore
  // the largest error there is.
  double input_gain_sigma = 0.0;
  // Standard deviation of each joint's angle noise [rad]: one count / sqrt(12) for a quantising
  // encoder; and where each came from (the misfit warning says it).
  std::array<double, 2> angle_sigma_rad = {0, 0};
  std::array<AngleNoiseSource, 2> angle_noise_source = {AngleNoiseSource::encoder_resolution,
                                                        AngleNoiseSource::encoder_resolution};
  std::vector<std::string> warnings;
  // Session logs: every supply reading of the motor board's reports [V] (the guaranteed
  // identification's drive, physical_inputs.hpp); empty for other recordings.
  std::vector<double> supply_readings_v;
  // Per joint: the board's clock its observations' times were mapped from, or nothing where they
  // are the host's stamps (no board time, or one that does not keep time).
  std::array<std::optional<BoardClock>, 2> board_clock;
};

// From a session log: the angles of every report of both boards at its time, the board's own clock
// mapped onto the host's (fit_board_clock) where it keeps time, else the host's; the input rebuilt
// from every command written to the motor board (session_log::motor_command_writes) and the
// board's ramp towards it, scaled by the mean supply reading of the motor board's reports. `rig`
// gives the encoders' geometry, the motor's nominal voltage and the braking before the first
// command (the log's carried configuration, or the one the user named).
OeExperiment oe_experiment_from_log(const session_log::SessionLog& log,
                                    const config::RigConfig& rig);

// From a recording (a CSV, or any RawExperiment): each angle at its own time as recorded (or at the
// sample times when `raw.recorded` is empty); the input from its own times, ramped at
// `raw.input_rate_limit_per_s` when it has one, else as recorded with `between` samples (held: a
// logger that records what it wrote; linear; cubic: a sampled smooth signal, where linear's chords
// shrink every peak and so bias every parameter).
// `angle_sigma_rad` as in OeExperiment (one count / sqrt(12)). A duty with supply readings is
// scaled by their mean over `nominal_supply_v` (the rig configuration's motor voltage).
OeExperiment oe_experiment_from_raw(const RawExperiment& raw, std::array<double, 2> angle_sigma_rad,
                                    InputBetweenSamples between,
                                    const VoltageMotor& voltage_motor = {},
                                    double nominal_supply_v = 0);

// An angle's noise [rad] from its own readings, for a recording that states no resolution: the
// spread of their fourth differences, which remove a smooth motion up to its third derivative and
// multiply white noise's variance by 70 (1 + 16 + 36 + 16 + 1), taken robustly (the median
// absolute deviation, so that the few samples around a switch of the input do not count); never
// below one smallest step between readings / sqrt(12), since an encoder's readings scatter at
// least by its count. Readings in time order at about one rate; fewer than 5 give that floor.
double angle_noise_from_readings(std::span<const double> q_rad);

struct OutputErrorOptions {
  // Multiple shooting: each experiment is cut into segments of about this length, each with its
  // own initial state. 0.25 s, a third of a pendulum period (0.84 s): short enough that an LSMI
  // start far off (a pendulum spinning over at amplitude 0.5) keeps each segment's simulation in
  // phase with the data, where segments twice as long lose it and stop far off
  // (docs/measurements/identification.md, "Output-error refinement: five seed triples per
  // excitation"); long enough that the 4 state unknowns are few against the segment's ~60 angles.
  // The continuity residuals make the optimum one trajectory whatever the length: it decides
  // whether the fit gets there.
  double segment_s = 0.25;
  // Fixed RK4 substeps at most this long between observations; the arm's time constant is 4.4 ms.
  double substep_s = 1e-3;
  // The data path's lag (host time of an angle minus the time of the state it shows, relative to
  // the command writes' times): estimated in [min_lag_s, 50 ms] from `input_lag_s` as start, or
  // held at it. A session log's angles cannot lead the commands written (0); another logger may
  // stamp its input after the angles it drives (a CSV: -50 ms, and a negative estimate warns).
  bool estimate_lag = true;
  double input_lag_s = 1e-3;
  double min_lag_s = 0.0;
  // The pendulum's zero: an offset added to every measured q2 (a quantising encoder reads half a
  // count low on average; a rig zeroed slightly off its rest). Estimated, or held at 0.
  bool estimate_q2_offset = true;
  // Continuity between consecutive segments as residuals: the state defect over
  // (angle sigma / continuity_weight), velocities over the same per 10 ms, so that at the optimum
  // the trajectory is one continuous simulation to well within the angle noise.
  double continuity_weight = 30.0;
  // A cap only: the fit ends on the solver's function and parameter tolerances.
  int max_iterations = 200;
  // A residual sigma above this (the angles this many times further from the model than their
  // assumed noise) is a warning: the model does not describe the data as recorded.
  double misfit_sigma = 10.0;
  int num_threads = 2;
};

struct OutputErrorResult {
  model::Parameters<double> estimate{};
  // Local standard deviations: sqrt(diag(J^T J)^-1) at the optimum, J the Jacobian of the residuals
  // weighted by the assumed angle noise, scaled by the residuals' estimated sigma (the weighted
  // RMS over degrees of freedom), or where larger the cluster-robust ones (the sandwich over the
  // segments: quantisation of a slow angle repeats its error over many samples, which the first
  // counts as independent), carried to the natural parameters by the chain rule. Both are local:
  // the model and the input are taken as exact.
  model::Parameters<double> std_dev{};
  model::Parameters<double> local_std_dev{};  // the first of the two alone (<= std_dev)
  double input_lag_s = 0, input_lag_std_s = 0;
  double q2_offset_rad = 0;
  std::vector<double> input_gain;                // per experiment (1 when held)
  std::array<double, 2> angle_rms_rad = {0, 0};  // fitted minus measured, per joint
  double continuity_rms = 0;  // the weighted continuity defects' RMS (<< 1: continuous)
  double residual_sigma = 0;  // estimated sigma of the weighted angle residuals (1: as assumed)
  // The angle noise assumed per joint (the largest over the experiments) and where it came from
  // (estimated_from_readings when any experiment's was).
  std::array<double, 2> angle_noise_rad = {0, 0};
  std::array<AngleNoiseSource, 2> angle_noise_source = {AngleNoiseSource::encoder_resolution,
                                                        AngleNoiseSource::encoder_resolution};
  // Per joint, whose times the observations carry, and where the board's clock was used, how late
  // the host's stamps were beside it (the mean and the largest over the experiments) [s].
  std::array<TimeStamps, 2> time_stamps = {TimeStamps::host, TimeStamps::host};
  std::array<double, 2> host_delay_mean_s = {0, 0}, host_delay_max_s = {0, 0};
  std::size_t segments = 0;
  std::size_t observations = 0;
  int iterations = 0;
  bool converged = false;
  std::string message;                // Ceres' summary line
  std::vector<std::string> warnings;  // e.g. the start moved into the physical region
};

// Throws std::invalid_argument for an experiment without observations or input, or a start that is
// not finite.
OutputErrorResult refine_output_error(const std::vector<OeExperiment>& experiments,
                                      const model::Parameters<double>& start,
                                      const model::MotorData& motor,
                                      const OutputErrorOptions& options = {});

// The fewest samples a recording needs for the refinement alone: more angle readings (two a
// sample) than one segment's unknowns (its starting state, the parameters, the lag, the pendulum's
// zero and the input's gain). A fit from a few samples more has wide sd, and its sd say so.
inline constexpr std::size_t kRefinementMinimumSamples = (4 + model::kParameterCount + 3) / 2 + 1;

// A free-run simulation of a whole experiment (no re-shooting): the initial state is fitted to the
// first `options.segment_s` with the parameters held, then the model runs to the end.
struct FreeRun {
  std::vector<double> t_s;       // the observations' times
  std::vector<int> joint;        // per observation
  std::vector<double> measured;  // angle_rad (+ the q2 offset for the pendulum)
  std::vector<double> simulated;
  std::array<double, 2> rmse_rad = {0, 0};  // per joint
  // The measured angle's standard deviation about its mean, per joint: the RMSE of a model that
  // predicts nothing but the mean, which a free run worth reporting must beat.
  std::array<double, 2> measured_sd_rad = {0, 0};
};
FreeRun simulate_free_run(const OeExperiment& experiment, const model::Parameters<double>& p,
                          const model::MotorData& motor, double input_lag_s, double q2_offset_rad,
                          double input_gain = 1.0, const OutputErrorOptions& options = {});

}  // namespace furuta::identification
