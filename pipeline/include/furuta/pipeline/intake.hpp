#pragma once
// What to identify, as a user names it (`furuta identify`'s arguments, the trigger's batch),
// loaded and checked into a Batch and the Settings to run it with. Every caller goes through
// here, so a log is refused, cut or accepted the same way whoever asked.
//
//   pipeline::BatchRequest request;
//   request.logs = {"logs/a.lcmlog"};
//   const pipeline::Intake intake = pipeline::load_batch(request);
//   if (intake.batch) const pipeline::Run run = pipeline::run(*intake.batch, intake.settings);

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "furuta/config/rig_config.hpp"
#include "furuta/identification/identify.hpp"
#include "furuta/pipeline/pipeline.hpp"

namespace furuta::pipeline {

// What the caller changes of the configuration's settings (settings_for(rig)).
struct SettingsOverrides {
  std::optional<double> cutoff_hz;         // [identification] cutoff_hz
  std::optional<double> input_lag_ms;      // [identification] input_lag_ms
  bool estimate_input_lag = false;         // estimate it even when the configuration gives it
  bool no_output_error = false;            // skip the refinement [output_error] enables
  bool diagnose = false;                   // refit the candidate mistakes whatever the fit
  bool sivia = false;                      // SIVIA after LSMI
  bool guaranteed = false;                 // the windowed set around the output-error estimate
  std::optional<int> threads;              // SIVIA's ([sivia] threads otherwise)
  bool simulate = false;                   // the paper's scenarios after the fit
  std::optional<double> simulate_seconds;  // each scenario's duration
};

// Session logs or CSV recordings (not both: they are fitted together as one rig), the held-out
// one, and the rig they are read with.
struct BatchRequest {
  std::vector<std::filesystem::path> logs;  // session logs to fit
  std::vector<std::filesystem::path> csvs;  // or CSV recordings, mapped by import_spec
  std::filesystem::path import_spec;        // required with CSV recordings
  std::filesystem::path validate;           // held out: a log, or a CSV (its name ends .csv)
  // Empty: the configuration the first log carries (all logs must carry the same rig); with
  // CSV recordings optional (duty input needs its motor).
  std::filesystem::path config_path;
  // A log that is not intact is refused unless this is set; then each run of its samples
  // between gaps is a recording of its own.
  bool use_intact_part = false;
  std::filesystem::path files_listed_in;  // Batch::files_listed_in
  SettingsOverrides overrides;
};

// The request loaded: the batch and its settings, or the reasons it cannot be identified, each
// naming the file and what to do.
struct Intake {
  std::optional<Batch> batch;
  Settings settings;
  std::vector<std::string> refusals;
};

// Loads and checks every file. Refuses (in Intake::refusals, nothing thrown): a mix of kinds,
// a CSV without its import spec, a log not intact (without use_intact_part), logs of different
// rigs, recordings too short for every method that would run, a CSV input that never moves,
// a cut-off above a recording's Nyquist band, SIVIA without data bounds, and configuration or
// import-spec errors. Throws what reading an unreadable file throws.
Intake load_batch(const BatchRequest& request);

// settings_for(rig) with the caller's overrides.
Settings settings_for(const config::RigConfig& rig, const SettingsOverrides& overrides);

}  // namespace furuta::pipeline
