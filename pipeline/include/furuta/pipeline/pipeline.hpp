#pragma once
// The identification as one call: preprocessing and LSMI over the fitted recordings, the check on
// the held-out one, the output-error refinement, SIVIA, the paper's scenarios as guaranteed tubes.
// Numbers in, numbers out: no text, JSON, SVG or HTML is made here; report/ writes every output
// from a Run.
//
//   pipeline::Batch batch;                                  // the recordings, loaded
//   batch.fit.push_back(pipeline::log_recording(log, pipeline::Role::fit, rig));
//   batch.rig = rig;
//   pipeline::Settings settings = pipeline::settings_for(rig);
//   settings.sivia.run = true;
//   const pipeline::Run run = pipeline::run(batch, settings);

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "furuta/config/rig_config.hpp"
#include "furuta/identification/csv_import.hpp"
#include "furuta/identification/diagnosis.hpp"
#include "furuta/identification/guaranteed.hpp"
#include "furuta/identification/identify.hpp"
#include "furuta/identification/output_error.hpp"
#include "furuta/identification/physical.hpp"
#include "furuta/identification/windowed_set.hpp"
#include "furuta/interval/box.hpp"
#include "furuta/model/model.hpp"
#include "furuta/pipeline/balance.hpp"
#include "furuta/session_log/session_log.hpp"
#include "furuta/validated/scenarios.hpp"

namespace furuta::pipeline {

// --- what goes in ---

enum class Role { fit, held_out };

// What a session log says about itself, as `furuta log info` prints it: the basis of the
// report's sessions table and lost-sample warnings.
struct SessionSummary {
  std::string file;  // the log's file name
  std::string role;  // "fit" or "held out"
  std::string label, profile;
  double amplitude_duty = 0;
  double duration_s = 0;
  double period_s = 0;
  std::int64_t seed = 0;
  std::size_t samples = 0;
  std::size_t missing_samples = 0;        // sequence numbers absent between the first and the last
  std::int64_t motor_lost_reports = 0;    // the motor board's
  std::int64_t encoder_lost_reports = 0;  // the encoder board's
  std::int64_t overruns = 0;              // missed loop cycles
  std::size_t faults = 0;
  std::vector<std::string> fatal_faults;  // "reason (detail)"
  bool complete = false;                  // start and end records present
  std::string end_reason;             // the end record's ("arm_angle_limit", ...); "" without one
  std::uint64_t damaged_regions = 0;  // skipped by the checked reader
  bool truncated_tail = false;
  // A balance session's figures and cycles (summarize_balance); none for an excitation session.
  std::optional<BalanceSummary> balance;
};
SessionSummary summarize_session(const session_log::SessionLog& log, std::string role);

// One fitted or held-out recording, loaded.
struct Recording {
  identification::RawExperiment experiment;
  std::optional<SessionSummary> session;  // session logs only
  // The angles at their own times and the input as the board applied it (session logs, from their
  // raw reports and command writes, an intact part's cut to its time); absent for CSVs (run()
  // makes it from `experiment`).
  std::optional<identification::OeExperiment> oe;
  // The input came from a controller closing the loop on the measured angles (a balance
  // session's cycles): least squares is then biased, which the physical check must know.
  bool closed_loop = false;
};
// A session log as a recording (its samples resampled, its summary, its OeExperiment read with
// `rig`'s encoders and motor).
Recording log_recording(const session_log::SessionLog& log, Role role,
                        const config::RigConfig& rig);

// A log that is not intact (session_log::integrity_problems), used as far as it is: its samples
// cut at every gap (session_log::contiguous_sample_runs), each run a recording of its own, so that
// nothing is filtered or differentiated across a gap. Runs shorter than min_samples (the fit's
// identification::minimum_samples) are dropped; held out, only the longest run is kept. The first
// recording carries the session summary and, as a warning, `account`. Each has its OeExperiment
// (read with `rig`), with the commands written within its time.
struct IntactParts {
  std::vector<Recording> recordings;  // empty: no run is long enough
  std::string account;  // what was used and what was dropped, naming the file and the samples
};
IntactParts intact_part_recordings(const session_log::SessionLog& log, Role role,
                                   std::size_t min_samples, const config::RigConfig& rig);

enum class InputKind { session_logs, csv_recordings };

struct Batch {
  InputKind kind = InputKind::session_logs;
  std::vector<Recording> fit;
  std::optional<Recording> held_out;
  // The files the recordings came from (and an import spec), in the order results.json lists
  // them with their SHA-256.
  std::vector<std::filesystem::path> files;
  // Logs used in part (BatchRequest::use_intact_part on a log that is not intact): each one's
  // account of what was used and what was dropped (IntactParts::account). The run is then done in
  // part, whatever it finds.
  std::vector<std::string> used_in_part;
  // Where the outputs name the files: empty, where they are; else this directory (the trigger
  // moves a batch's logs there once its identification is written).
  std::filesystem::path files_listed_in;
  config::RigConfig rig;  // [identification], [sivia], the motor for eq. 4, the simulated rig
  // Where `rig` came from: the file given (--config), or the log whose start record carried it;
  // neither for CSV recordings identified without a configuration.
  std::filesystem::path config_file, config_carried_by;
  std::optional<model::Parameters<double>> nominal;  // CAD values
  std::optional<model::Parameters<double>> truth;    // simulated sessions: the rig's parameters
  identification::VoltageMotor voltage_motor;        // CSV recordings with voltage input
  // CSV recordings: what the input did between samples (the import spec's input_between_samples).
  identification::InputBetweenSamples input_between_samples =
      identification::InputBetweenSamples::linear;
  double angle_resolution_rad = 0;  // the pendulum's quantisation
  // CSV recordings: each angle's resolution [rad] (arm, pendulum) as the import spec gives it
  // (counts, or arm_resolution / pendulum_resolution); 0 where it does not say.
  std::array<double, 2> encoder_resolution_rad = {0, 0};
  // CSV recordings in counts: each angle's counts per revolution as the import spec gives them
  // (session logs: the configuration's encoders); 0 otherwise.
  std::array<double, 2> counts_per_rev = {0, 0};
  // CSV recordings: their bounds for the guaranteed set (the import spec's [guaranteed]); session
  // logs take identification::session_log_bounds(rig).
  std::optional<identification::RecordingBounds> recording_bounds;
};

struct SiviaSettings {
  bool run = false;
  config::SiviaConfig config;  // prior, unknowns, data bounds, paver (also Table II without SIVIA)
  int threads = 0;             // 0: every core
};

struct SimulationSettings {
  bool run = false;
  std::vector<validated::Scenario> scenarios = validated::paper_scenarios();
  std::size_t pieces = 1;  // tubes per run (validated::scenario_split_options)
  // The most pieces a Taylor-model set's run is cut into where it fails (the windowed set's):
  // each cut doubles the work from the cut on.
  std::size_t taylor_model_pieces = 2;
};

struct OutputErrorSettings {
  bool run = false;
  identification::OutputErrorOptions options;
  // The diagnosis by refitting candidate mistakes (identification/diagnosis.hpp): always runs
  // when the fit is no rig's answer; `diagnose` runs it for every fit (`furuta identify
  // --diagnose`: the check of a new recording's signs, zero and units).
  bool diagnose = false;
};

// The windowed set inversion (identification/windowed_set.hpp) over the output-error estimate +-
// search_sd standard deviations: it runs after the refinement, and only when that converged.
struct WindowedSettings {
  bool run = false;
  double search_sd = 5.0;
  identification::WindowedSetOptions options;
};

struct Settings {
  identification::IdentifyOptions identify;  // preprocessing, LSMI, the input lag
  OutputErrorSettings output_error;
  SiviaSettings sivia;
  WindowedSettings windowed;
  SimulationSettings simulation;
};

// The configuration's settings: [identification] as IdentifyOptions, [output_error] (run as
// its `enabled` says), [sivia], [guaranteed]'s windows; SIVIA, the windows and the scenarios off.
Settings settings_for(const config::RigConfig& rig);
// [sivia]'s bounds on the preprocessed data (SIVIA's data boxes, the figures' bands), and
// whether the configuration gives any (a configuration without them leaves them all 0).
identification::DataErrorBounds data_error_bounds(const config::SiviaConfig& sivia);
bool has_data_error_bounds(const config::SiviaConfig& sivia);
// The box SIVIA starts from (Table II): the mu's around the LSMI estimate +- [sivia]
// mu_uncertainty_pct, the frictions' priors as [sivia] gives them.
interval::Box sivia_prior(const config::SiviaConfig& sivia, const model::Parameters<double>& lsmi);

// Told what the long steps are doing; the caller decides whether and how to show it.
class Progress {
 public:
  virtual ~Progress() = default;
  // LSMI is done (Table I is ready; SIVIA and the scenarios may take minutes yet). `id` has the
  // CAD values and the truth filled in, as Run::identification will.
  virtual void lsmi_done(const identification::Identification& /*id*/) {}
  virtual void output_error_started(std::size_t /*experiments*/) {}
  // The fit is done (Table I with its output-error column is ready): after the refinement, or
  // right after LSMI when it does not run; `refined` is null then.
  virtual void fit_done(const identification::Identification& /*id*/,
                        const identification::OutputErrorResult* /*refined*/) {}
  virtual void sivia(std::size_t /*tested*/, std::size_t /*pending*/) {}  // per generation
  virtual void sivia_done() {}
  // The windowed set inversion: after each of its steps (the k-th windows of every recording).
  virtual void windows(std::size_t /*done*/, std::size_t /*total*/) {}
  virtual void windows_done() {}
  virtual void scenario(const validated::Scenario& /*scenario*/,
                        const std::string& /*parameter_set*/) {}  // before each tube
  virtual void scenarios_done() {}
};

// --- what comes out ---

// SIVIA's result and the data it was given.
struct Guaranteed {
  identification::GuaranteedResult result;
  std::vector<identification::IntervalSample> samples;  // the data boxes, in constraint order
  identification::DataErrorBounds bounds;
};

// The windowed set inversion's result with what it started from. Its set is in the scaled
// parameters (physical_inputs.hpp), which the data determine; the rig's follow with the drive's
// tolerance.
struct WindowedGuaranteed {
  identification::PhysicalInputs inputs;
  double search_sd = 0;
  // The estimate's own drive: what its scaled parameters are computed with.
  double gain_nm = 0, back_emf_nm_s = 0;
  model::Parameters<double> estimate_scaled, std_dev_scaled;
  // Simulated sessions: their truth scaled with the estimate's drive (the rig's, up to the
  // refinement's input gains).
  std::optional<model::Parameters<double>> truth_scaled;
  identification::WindowedSet result;
  // rig_parameters(result.set, inputs.drive): every rig parameter the set allows for every drive.
  model::Parameters<interval::Interval> rig_set;
  // The part of rig_set's widths a point scaled set would still have (the drive's alone), per
  // parameter, as a fraction of rig_set's width.
  model::Parameters<double> drive_share{};
};

// Where the scenarios' "measurements" came from (the simulated rig with these parameters).
struct MeasurementSource {
  enum class Kind {
    sessions_truth,  // the simulated sessions' truth
    configured_rig,  // the configuration's simulated rig (the sessions carry no truth)
    paper_default,   // the simulated rig's default, the paper's run 1
    results_truth,   // the truth recorded in a results.json (`file`)
  };
  Kind kind = Kind::paper_default;
  std::string file;
};

// One step of a tube: every solution is in `over` over [t0, t1] and in `end` at t1 (all of the
// tube's state components: q1, dq1, q2, dq2, then carried parameters if any).
struct StepBoxes {
  double t0_s = 0, t1_s = 0;
  interval::Box over, end;
};
// One piece of a tube set: the sub-box of the initial box its solutions start from at
// t_start_s, and its steps. A piece made by a split shares the steps before the split with an
// earlier piece: its first `inherited_steps` steps are the first ones of piece `inherits_from`, and
// `steps` holds only the rest (each step is held once, not copied into every piece).
struct TubePiece {
  double t_start_s = 0;
  interval::Box start;
  std::optional<std::size_t> inherits_from;
  std::size_t inherited_steps = 0;
  std::vector<StepBoxes> steps;
};
// A scenario run's tube set (one piece unless the run was split), with what the integrator was
// given: the start box (the pieces' start boxes cover it) and the constant arm torque.
struct TubeSet {
  interval::Box initial;
  interval::Interval torque_nm;
  std::vector<TubePiece> pieces;
  std::size_t dimension = 0;

  // Every step of piece `piece`, the inherited ones first (std::out_of_range for no such piece).
  std::vector<StepBoxes> all_steps(std::size_t piece) const;
};

struct Simulation {
  MeasurementSource source;
  model::Parameters<double> truth;  // the measurements' parameters
  validated::MeasurementOptions measurement;
  validated::IntegratorOptions integrator;
  validated::StateUncertainty uncertainty;
  std::size_t pieces = 1;
  std::size_t taylor_model_pieces = 1;
  std::vector<validated::ScenarioResult> results;  // per scenario, per parameter set
  std::vector<TubeSet> tubes;                      // tubes[i] is results[i]'s
};

// The held-out recording run free (no re-shooting) with the LSMI and with the refined parameters,
// both with the refinement's lag and pendulum zero offset (properties of the data path, not of
// the parameters) and an input gain of 1.
struct HeldOutFreeRuns {
  std::string name;
  std::optional<identification::FreeRun> lsmi;  // none when LSMI did not run
  identification::FreeRun refined;
};

// Its parameter set's name in the scenarios (Table III) and Table I.
inline constexpr const char* kOutputErrorSetName = "output error";
// SIVIA's hull's (Table III).
inline constexpr const char* kSiviaSetName = "SIVIA";
// The windowed set's (Table III's guaranteed rows from the logs themselves).
inline constexpr const char* kWindowedSetName = "guaranteed";

// The output-error refinement, started from the combined LSMI estimate (and from the CAD values
// too when LSMI is not physical; the better fit kept). It always runs when asked: LSMI's verdict
// is one diagnostic, the fit's residuals another.
struct OutputError {
  identification::OutputErrorResult result;
  // The refined estimate against the physical region: its parametrisation keeps the inertias
  // positive but not mu3's sign, which a sign-flipped pendulum turns (an output_error warning
  // names the cause).
  identification::PhysicalCheck physical;
  std::optional<HeldOutFreeRuns> held_out;
  // The refits with each candidate recording mistake undone, when the fit needed them or they
  // were asked for; and each angle's counts per revolution as configured (0: not in counts), for
  // the named correction's suggestion.
  std::optional<identification::Diagnosis> diagnosis;
  std::array<double, 2> counts_per_rev = {0, 0};
};

// Something that happened that a reader should know of, beyond the numbers: where (the stage),
// what sort of thing (the kind), and the words.
struct Warning {
  // physical: the LSMI estimate is outside the physical region (docs/model.md), or its
  // magnitudes are no rig's; the text names the likely recording mistake.
  enum class Stage { data, lsmi, physical, output_error, sivia, guaranteed, simulation };
  enum class Kind {
    data,     // the recording is short of what it should be: lost, missing, damaged, cut
    skipped,  // the stage did not run; the text says why
    failed,   // the stage ran and its result cannot be used: no convergence, an empty set, a tube
              // that ended early
    suspect,  // a result to doubt: not physical, poorly excited, a misfit, at odds with another
    note,     // how the stage ran, where the reader would otherwise assume the default
  };
  Stage stage = Stage::data;
  Kind kind = Kind::note;
  std::string text;
};
// The stage's latest warning of `kind` (a skipped stage's reason); "" when there is none.
std::string warning_text(const std::vector<Warning>& warnings, Warning::Stage stage,
                         Warning::Kind kind);

// An identification's own warnings with their stage: LSMI's (identify() prefixes them with the
// experiment's name, or "all experiments") and the data's (lost reports, missing samples, a
// cut-short session, a recording too short for LSMI). pipeline::run starts Run::warnings with them.
std::vector<Warning> identification_warnings(const identification::Identification& id);

// A parameter whose output-error estimate lies outside a guaranteed set's hull: either the set
// rests on bounds the data break, or the model does not fit; a reader must be told which parameter
// and by how far.
struct EstimateOutsideSet {
  std::size_t parameter = 0;  // index in model::kParameterNames
  double estimate = 0.0;
  interval::Interval set;  // the set's hull in that parameter
  double sd_away = 0.0;    // the estimate's distance to the hull in its sd (infinite when sd is 0)
};

// The parameters of `estimate` outside `hull` (one interval per parameter, in kParameterNames'
// order), nearest first by sd_away.
std::vector<EstimateOutsideSet> estimates_outside(const interval::Box& hull,
                                                  const model::Parameters<double>& estimate,
                                                  const model::Parameters<double>& std_dev);

struct Run {
  InputKind kind = InputKind::session_logs;
  std::vector<identification::InputFile> inputs;         // Batch::files with their SHA-256
  std::vector<SessionSummary> sessions;                  // session logs: fitted, then held out
  std::string rig_name;                                  // the configuration's name
  std::filesystem::path config_file, config_carried_by;  // Batch's: where the rig came from
  bool simulated_rig = false;                            // the sessions' true parameters are known
  double angle_resolution_rad = 0;
  std::optional<identification::DataErrorBounds> data_bounds;  // when [sivia] gives them
  Settings settings;                                           // as used
  identification::Identification identification;  // LSMI per experiment and combined, validation
  // The combined LSMI estimate against the physical region, with the likely cause; its warning
  // (Stage::physical) is also in identification.warnings, so it reaches every output.
  identification::PhysicalCheck physical;
  std::optional<OutputError> output_error;  // settings.output_error.run, when it could run
  std::optional<Guaranteed> sivia;          // settings.sivia.run
  // SIVIA's set against the output-error estimate (when both ran and the fit converged): the
  // report and the terminal say each.
  std::vector<EstimateOutsideSet> sivia_excludes_output_error;
  // settings.windowed.run, when the refinement converged; and its set against the refinement's
  // estimate (scaled, in its scaled sd).
  std::optional<WindowedGuaranteed> windowed;
  std::vector<EstimateOutsideSet> windowed_excludes_output_error;
  std::optional<Simulation> simulation;  // settings.simulation.run
  std::vector<Warning> warnings;
};

// The whole identification of a batch. Throws what its steps throw (std::invalid_argument for
// inputs the fit cannot use, std::runtime_error for an unreadable file).
Run run(const Batch& batch, const Settings& settings, Progress* progress = nullptr);

// The scenarios measured on the simulated rig with `truth`, then a tube per parameter set
// (`furuta simulate`, and run() after the fit).
Simulation simulate(const std::vector<validated::Scenario>& scenarios,
                    const std::vector<validated::ParameterSet>& sets,
                    const model::Parameters<double>& truth, const MeasurementSource& source,
                    std::size_t pieces = 1, Progress* progress = nullptr,
                    std::size_t taylor_model_pieces = 1);

}  // namespace furuta::pipeline
