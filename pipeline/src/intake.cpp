#include "furuta/pipeline/intake.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>
#include <sstream>

#include "furuta/identification/csv_import.hpp"
#include "furuta/session_log/log_integrity.hpp"
#include "furuta/session_log/session_log.hpp"

namespace furuta::pipeline {

namespace {

using Refusals = std::vector<std::string>;

// A CSV recording rather than a session log: decided by the name alone, as the user sees it.
bool is_csv(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".csv";
}

// Every log fitted as one rig with the first log's configuration: its motor (the torque, eq. 4) and
// encoders. A log that ran with other values would be fitted with the wrong ones, and nothing would
// show it. With a configuration named, the user names the rig for all of them.
bool same_rig_as_first(const std::vector<session_log::SessionLog>& logs,
                       const std::optional<session_log::SessionLog>& held_out,
                       const config::RigConfig& first, Refusals& refusals) {
  std::vector<const session_log::SessionLog*> others;
  for (std::size_t i = 1; i < logs.size(); ++i) others.push_back(&logs[i]);
  if (held_out) others.push_back(&*held_out);
  bool same = true;
  for (const session_log::SessionLog* log : others) {
    if (!log->start) continue;  // refused elsewhere as not a session log
    const config::RigConfig rig =
        config::parse_rig_config(log->start->rig_config_toml, log->path.string());
    std::string differs;
    const auto differ = [&](bool equal, const char* section) {
      if (!equal) differs += (differs.empty() ? "" : ", ") + std::string(section);
    };
    differ(rig.motor == first.motor, "[motor]");
    differ(rig.arm_encoder == first.arm_encoder, "[encoders.arm]");
    differ(rig.pendulum_encoder == first.pendulum_encoder, "[encoders.pendulum]");
    if (differs.empty()) continue;
    refusals.push_back(log->path.string() + " ran with another rig configuration than " +
                       logs.front().path.string() + ": " + differs +
                       " differ. Fitted together, every log would be read with the first's; "
                       "identify them separately, or pass --config to name the rig for all");
    same = false;
  }
  return same;
}

// Every value a fit reads from a sample, checked where it enters: finite, the duties within
// [-1, 1], and each angle its counts through the encoder geometry the log ran with (the daemon
// computes them so). A value that is not was changed after it was logged, which a log written
// before logs were sealed cannot show otherwise; the first such sample is named.
std::optional<std::string> sample_value_problem(const session_log::SessionLog& log) {
  if (!log.start) return std::nullopt;
  config::RigConfig rig;
  try {
    rig = config::parse_rig_config(log.start->rig_config_toml, log.path.string());
  } catch (const config::ConfigError&) {
    return std::nullopt;  // refused elsewhere, with the configuration's own error
  }
  const auto angle_off = [](double logged, double expected) {
    // The daemon's own arithmetic gives exactly this; a rounding's worth is allowed for another
    // compiler or platform.
    return !(std::fabs(logged - expected) <= 1e-9 * (1.0 + std::fabs(expected)));
  };
  for (const furuta::rig_sample_t& s : log.samples) {
    std::string field;
    if (angle_off(s.arm_angle_rad, config::arm_angle_rad(rig, s.arm_counts))) {
      field = "arm_angle_rad " + std::to_string(s.arm_angle_rad) + " is not its arm_counts " +
              std::to_string(s.arm_counts) + " through the log's [encoders.arm]";
    } else if (angle_off(s.pendulum_angle_rad,
                         config::pendulum_angle_rad(rig, s.pendulum_counts))) {
      std::ostringstream text;
      text << "pendulum_angle_rad " << s.pendulum_angle_rad << " is not its pendulum_counts "
           << s.pendulum_counts << " through the log's [encoders.pendulum]";
      field = text.str();
    } else if (!(std::fabs(s.commanded_duty) <= 1.0) || !(std::fabs(s.applied_duty) <= 1.0)) {
      std::ostringstream text;
      text << "duty " << s.commanded_duty << " commanded, " << s.applied_duty
           << " applied: outside [-1, 1]";
      field = text.str();
    } else if (!std::isfinite(s.motor_current_a) || !std::isfinite(s.supply_voltage_v)) {
      field = "current or supply not a finite number";
    }
    if (!field.empty()) {
      return log.path.string() + ": sample seq " + std::to_string(s.seq) + ": " + field +
             "; the value was changed after it was logged (or the log is not this project's)";
    }
  }
  return std::nullopt;
}

// Each log once: by its digest (SessionLog::digest_hex), whatever its file is called. A log fitted
// twice counts its data twice (the standard deviations shrink by the square root of two for
// nothing); a held-out log that was fitted makes the hold-out's error the fit's own.
bool distinct_logs(const std::vector<session_log::SessionLog>& logs,
                   const std::optional<session_log::SessionLog>& held_out, Refusals& refusals) {
  bool distinct = true;
  for (std::size_t i = 0; i < logs.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (logs[i].digest_hex != logs[j].digest_hex) continue;
      refusals.push_back(logs[i].path.string() + " is the same log as " + logs[j].path.string() +
                         " (sha256:" + logs[i].digest_hex.substr(0, 16) +
                         "...): fitted twice, its data would count twice and the standard "
                         "deviations shrink for nothing; give each log once");
      distinct = false;
      break;
    }
    if (held_out && logs[i].digest_hex == held_out->digest_hex) {
      refusals.push_back("the held-out " + held_out->path.string() +
                         " is the same log as the fitted " + logs[i].path.string() +
                         " (sha256:" + logs[i].digest_hex.substr(0, 16) +
                         "...): its error would be the fit's own, not a hold-out's; hold out a "
                         "session the fit does not see");
      distinct = false;
    }
  }
  return distinct;
}

// The differentiator's stop band (twice the cut-off) must fit below every recording's Nyquist
// frequency; a recording slower than the rig's loop needs a lower cut-off than its default.
bool cutoff_fits(const Batch& in, const BatchRequest& request, Refusals& refusals) {
  const double cutoff_hz = request.overrides.cutoff_hz.value_or(in.rig.identification.cutoff_hz);
  std::vector<const identification::RawExperiment*> all;
  for (const auto& r : in.fit) all.push_back(&r.experiment);
  if (in.held_out) all.push_back(&in.held_out->experiment);
  for (const auto* e : all) {
    const double nyquist_hz = 0.5 / e->sample_period_s;
    if (!(2 * cutoff_hz < nyquist_hz)) {
      std::ostringstream text;
      text << e->name << ": the cut-off " << cutoff_hz
           << " Hz puts the differentiator's stop band (" << 2 * cutoff_hz
           << " Hz) above the Nyquist frequency " << nyquist_hz << " Hz; pass --cutoff below "
           << nyquist_hz / 2;
      refusals.push_back(text.str());
      return false;
    }
  }
  return true;
}

// Session logs: the rig is the one the first log carries, unless a configuration is named. A log
// that is not intact is refused (or, with use_intact_part, cut at its gaps); one too short for
// every method that would run is refused, naming the file and the length needed.
std::optional<Batch> batch_from_logs(const BatchRequest& request, Refusals& refusals) {
  std::vector<session_log::SessionLog> logs;
  for (const auto& path : request.logs) logs.push_back(session_log::load_session_log(path));
  std::optional<session_log::SessionLog> held_out_log;
  if (!request.validate.empty()) held_out_log = session_log::load_session_log(request.validate);

  std::vector<const session_log::SessionLog*> all_logs;
  for (const auto& log : logs) all_logs.push_back(&log);
  if (held_out_log) all_logs.push_back(&*held_out_log);
  bool refused = false;
  // Why a log that is not intact is refused, from the problems it has: a gap inside its samples
  // (damaged or undecodable bytes, missing, repeated or reordered samples, a count that is not the
  // end record's), an end missing (truncated, cut short), events that are not the ones recorded
  // (changed, joined, a seal lost, a replay of a damaged log), or not a session log at all; each
  // said only when some log has it.
  bool gaps = false, ends = false, intact_parts_help = false, foreign_any = false,
       untrusted_any = false;
  const auto check_intact = [&](const session_log::SessionLog& log) {
    using Kind = session_log::LogProblem::Kind;
    const auto problems = session_log::integrity_problems(log);
    if (problems.empty()) return;
    const bool in_part = session_log::usable_in_part(problems);
    if (request.use_intact_part && in_part) return;
    const bool foreign = session_log::has_problem(problems, Kind::not_a_session_log);
    refusals.push_back(log.path.string() + (foreign ? ": " : " is not intact: ") +
                       session_log::describe(problems) +
                       (in_part || foreign ? ""
                                           : "; no part of it is known to be what was recorded, "
                                             "so --use-intact-part cannot use it either"));
    refused = true;
    foreign_any = foreign_any || foreign;
    if (foreign) return;
    if (!in_part) {
      untrusted_any = true;
      return;
    }
    const bool gap = session_log::has_problem(problems, Kind::damaged) ||
                     session_log::has_problem(problems, Kind::undecodable) ||
                     session_log::has_problem(problems, Kind::missing_samples) ||
                     session_log::has_problem(problems, Kind::out_of_order) ||
                     session_log::has_problem(problems, Kind::time_goes_back) ||
                     session_log::has_problem(problems, Kind::count_mismatch);
    gaps = gaps || gap;
    ends = ends || session_log::has_problem(problems, Kind::truncated) ||
           session_log::has_problem(problems, Kind::cut_short);
    intact_parts_help = intact_parts_help || !log.samples.empty();
  };
  for (const auto& log : logs) check_intact(log);
  if (held_out_log) check_intact(*held_out_log);
  if (refused) {
    if (gaps) {
      refusals.push_back(
          "refused: filtering and differentiating across a gap gives wrong parameters without a "
          "sign of it");
    }
    if (ends) {
      refusals.push_back(
          "refused: a log without its end is not known to hold what its session recorded");
    }
    if (intact_parts_help) {
      refusals.push_back(
          "Pass --use-intact-part to fit only the intact parts (each run of samples between gaps "
          "on its own), or leave the log out");
    } else if (foreign_any) {
      refusals.push_back(
          "refused: only session logs (or CSV recordings, with --csv and --import-spec) are "
          "fitted");
    } else if (!untrusted_any) {
      refusals.push_back("refused: the log has no samples to fit; leave it out");
    }
    return std::nullopt;
  }
  if (!distinct_logs(logs, held_out_log, refusals)) return std::nullopt;
  for (const auto* log : all_logs) {
    if (const auto problem = sample_value_problem(*log)) {
      refusals.push_back(*problem);
      refused = true;
    }
  }
  if (refused) return std::nullopt;

  if (!logs.front().start && request.config_path.empty()) {
    refusals.push_back(request.logs.front().string() +
                       " has no session start record (and so no configuration); pass --config");
    return std::nullopt;
  }
  Batch in;
  in.rig = request.config_path.empty()
               ? config::parse_rig_config(logs.front().start->rig_config_toml,
                                          request.logs.front().string() + " (rig configuration)")
               : config::load_rig_config(request.config_path);
  if (request.config_path.empty()) {
    in.config_carried_by = request.logs.front();
    if (!same_rig_as_first(logs, held_out_log, in.rig, refusals)) return std::nullopt;
  } else {
    in.config_file = request.config_path;
  }
  const identification::IdentifyOptions identify = settings_for(in.rig, request.overrides).identify;
  // The refinement needs no derivatives: with the CAD values to start from, a log too short for
  // LSMI's filters is fitted by it alone (pipeline::run).
  const bool refinement_alone = !request.overrides.no_output_error && in.rig.output_error.enabled &&
                                in.rig.nominal.has_value();
  const std::size_t min_samples = refinement_alone ? identification::kRefinementMinimumSamples
                                                   : identification::minimum_samples(identify);
  // Each log as one recording, or as its intact parts; nothing when it cannot be used.
  const auto recordings = [&](const session_log::SessionLog& log, Role role) {
    std::vector<Recording> out;
    // Refused above unless every problem leaves parts that can be trusted.
    if (request.use_intact_part && !session_log::integrity_problems(log).empty()) {
      // Runs LSMI can take; only when there is none, the shorter ones the refinement can.
      IntactParts parts =
          intact_part_recordings(log, role, identification::minimum_samples(identify), in.rig);
      if (parts.recordings.empty() && refinement_alone) {
        parts = intact_part_recordings(log, role, min_samples, in.rig);
      }
      if (parts.recordings.empty()) {
        refusals.push_back(parts.account);
        refused = true;
      } else {
        in.used_in_part.push_back(parts.account);
      }
      return std::move(parts.recordings);
    }
    if (log.samples.size() < 2) {
      refusals.push_back(log.path.string() + ": no samples to identify (" +
                         std::to_string(log.samples.size()) + ")");
      refused = true;
      return out;
    }
    out.push_back(log_recording(log, role, in.rig));
    const std::size_t samples = out.back().experiment.t_s.size();
    if (samples < min_samples) {
      std::string text = log.path.string() + ": " +
                         identification::length_problem(out.back().experiment, identify);
      if (refinement_alone) {
        text += "; the output-error refinement alone needs " + std::to_string(min_samples);
      } else {
        text += std::string(
                    " (the output-error refinement, which needs no derivatives, would fit "
                    "it alone, ") +
                (request.overrides.no_output_error ? "but --no-output-error turns it off"
                 : !in.rig.output_error.enabled    ? "but [output_error] turns it off"
                                                   : "but it starts from the CAD values and the "
                                                     "configuration has no [nominal]") +
                ")";
      }
      refusals.push_back(text);
      refused = true;
      out.clear();
    }
    return out;
  };
  for (const auto& log : logs) {
    for (auto& r : recordings(log, Role::fit)) in.fit.push_back(std::move(r));
  }
  in.files = request.logs;
  if (held_out_log) {
    auto held_out = recordings(*held_out_log, Role::held_out);
    if (!held_out.empty()) in.held_out = std::move(held_out.front());
    in.files.push_back(request.validate);
  }
  if (refused) return std::nullopt;
  if (!cutoff_fits(in, request, refusals)) return std::nullopt;
  in.nominal = in.rig.nominal;
  if (in.rig.backend == config::UsbBackend::simulated) in.truth = in.rig.simulation.parameters;
  in.angle_resolution_rad = config::pendulum_resolution_rad(in.rig);
  return in;
}

// A fitted recording whose input never changes gives equations without a scale: LSMI answers
// every parameter 0 +- 0, which looks like a result. Refused, naming the files and the column.
bool excited(const std::vector<Recording>& fit, const identification::CsvImportSpec& spec,
             const BatchRequest& request, Refusals& refusals) {
  std::vector<std::string> constant;
  double value = 0;
  for (const Recording& r : fit) {
    const std::vector<double>& u = r.experiment.input;
    const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
    if (lo != u.end() && *lo == *hi) {
      if (constant.empty()) value = *lo;
      constant.push_back(r.experiment.name);
    }
  }
  if (constant.empty()) return true;
  std::string files;
  for (const std::string& name : constant) files += (files.empty() ? "" : ", ") + name;
  const std::string column = "the input column '" + spec.input.name + "'";
  std::ostringstream text;
  if (constant.size() == fit.size()) {
    text << (fit.size() == 1 ? files + ": " + column + " is "
                             : "every fitted recording's " + column.substr(4) + " is constant (" +
                                   files + "); in " + constant.front() + " it is ")
         << value << " on every row: nothing to identify (without an input that moves the rig "
         << "every parameter would come out 0 +- 0); check input in "
         << request.import_spec.string() << " or record with an excitation";
  } else {
    text << files << ": " << column << " is constant (" << value
         << " on every row): nothing to identify in " << (constant.size() == 1 ? "it" : "them")
         << " (its Table I column would be 0 +- 0); leave "
         << (constant.size() == 1 ? "it" : "them") << " out of --csv, or check input in "
         << request.import_spec.string();
  }
  refusals.push_back(text.str());
  return false;
}

// CSV recordings, mapped by the import spec. The rig configuration is optional: duty input needs
// its motor (eq. 4); voltage input has its motor in the spec's [motor], torque input needs none.
std::optional<Batch> batch_from_csvs(const BatchRequest& request, Refusals& refusals) {
  const identification::CsvImportSpec spec =
      identification::load_csv_import_spec(request.import_spec);
  if (request.overrides.guaranteed && !spec.bounds) {
    refusals.push_back("--guaranteed: " + request.import_spec.string() +
                       " has no [guaranteed] table: a CSV recording's bounds (each angle's "
                       "error, the pendulum's zero, the lag, the supply) are stated there "
                       "(docs/csv-import.md, \"Guaranteed identification\")");
    return std::nullopt;
  }
  Batch in;
  in.kind = InputKind::csv_recordings;
  if (!request.config_path.empty()) {
    in.rig = config::load_rig_config(request.config_path);
    in.config_file = request.config_path;
    in.nominal = in.rig.nominal;  // no truth: the simulation is not where the CSVs came from
  } else if (spec.input_kind == identification::InputKind::duty) {
    refusals.push_back(request.import_spec.string() +
                       ": input_kind = \"duty\" needs the rig's motor data (eq. 4): pass "
                       "--config RIG.toml");
    return std::nullopt;
  }
  // The configuration's input lag is the daemon's data path; another logger's is unknown, so 0
  // unless the caller gives one (or asks for it to be estimated).
  in.rig.identification.input_lag_ms = 0.0;
  if (spec.voltage_motor) in.voltage_motor = *spec.voltage_motor;
  in.input_between_samples = spec.input_between_samples;
  const auto load = [&](const std::filesystem::path& path) {
    return identification::experiment_from_csv(identification::import_csv(path, spec),
                                               path.filename().string());
  };
  for (const auto& path : request.csvs)
    in.fit.push_back({load(path), std::nullopt, std::nullopt, false});
  if (!excited(in.fit, spec, request, refusals)) return std::nullopt;
  in.files = request.csvs;
  if (!request.validate.empty()) {
    in.held_out = Recording{load(request.validate), std::nullopt, std::nullopt, false};
    in.files.push_back(request.validate);
  }
  in.files.push_back(request.import_spec);
  if (spec.angle_unit == identification::AngleUnit::counts) {
    in.angle_resolution_rad = 2 * std::numbers::pi / spec.pendulum_counts_per_rev;
    in.counts_per_rev = {spec.arm_counts_per_rev, spec.pendulum_counts_per_rev};
  }
  in.encoder_resolution_rad = spec.resolution_rad;
  in.recording_bounds = spec.bounds;

  if (!cutoff_fits(in, request, refusals)) return std::nullopt;
  return in;
}

// The request's shape: one kind of input, and the files each kind needs.
std::optional<std::string> request_problem(const BatchRequest& request) {
  if (request.logs.empty() && request.csvs.empty()) {
    return "give at least one session log, or --csv FILE with --import-spec SPEC";
  }
  for (const auto& path : request.logs) {
    if (is_csv(path)) {
      return path.string() + " is a CSV file: pass it as --csv FILE, with --import-spec SPEC";
    }
  }
  const bool csv_input = !request.csvs.empty();
  if (csv_input && !request.logs.empty()) {
    return "session logs and CSV files are fitted together as one rig; give one kind";
  }
  if (!request.validate.empty() && is_csv(request.validate) != csv_input) {
    return "the held-out " + request.validate.string() + " is " +
           (csv_input ? "not a CSV file" : "a CSV file") + " but the fitted inputs are " +
           (csv_input ? "CSV files" : "session logs") + "; validate on the same kind";
  }
  if (csv_input && request.import_spec.empty()) {
    return "--csv needs --import-spec SPEC (the columns, units and conventions; see "
           "identification/README.md)";
  }
  if (!csv_input && !request.import_spec.empty()) {
    return "--import-spec applies to --csv inputs only";
  }
  return std::nullopt;
}

}  // namespace

Settings settings_for(const config::RigConfig& rig, const SettingsOverrides& overrides) {
  config::RigConfig overridden = rig;
  config::IdentificationConfig& c = overridden.identification;
  if (overrides.cutoff_hz) c.cutoff_hz = *overrides.cutoff_hz;
  if (overrides.estimate_input_lag) {
    c.input_lag_ms.reset();
  } else if (overrides.input_lag_ms) {
    c.input_lag_ms = overrides.input_lag_ms;
  }
  Settings settings = settings_for(overridden);
  if (overrides.no_output_error) settings.output_error.run = false;
  settings.output_error.diagnose = overrides.diagnose;
  settings.sivia.run = overrides.sivia;
  settings.windowed.run = overrides.guaranteed;
  settings.sivia.threads = overrides.threads.value_or(rig.sivia.threads);
  settings.simulation.run = overrides.simulate;
  if (overrides.simulate_seconds) {
    for (validated::Scenario& s : settings.simulation.scenarios) {
      s.duration_s = *overrides.simulate_seconds;
    }
  }
  return settings;
}

Intake load_batch(const BatchRequest& request) {
  Intake intake;
  if (const auto problem = request_problem(request)) {
    intake.refusals.push_back(*problem);
    return intake;
  }
  const bool csv_input = !request.csvs.empty();
  std::optional<Batch> batch;
  try {
    batch = csv_input ? batch_from_csvs(request, intake.refusals)
                      : batch_from_logs(request, intake.refusals);
  } catch (const config::ConfigError& e) {  // the import spec or the rig configuration
    intake.refusals.push_back(e.what());
    return intake;
  } catch (const identification::CsvImportError& e) {
    intake.refusals.push_back(e.what());
    return intake;
  }
  if (!batch) return intake;
  if (request.overrides.sivia && !has_data_error_bounds(batch->rig.sivia)) {
    // Zero bounds claim exact data: SIVIA then finds no consistent parameter, an empty set that
    // reads like a finding about the rig.
    const std::string where =
        !request.config_path.empty()
            ? request.config_path.string() + "'s [sivia]"
            : (csv_input ? std::string("without --config, [sivia]")
                         : "the configuration " + request.logs.front().string() +
                               " carries: its [sivia]");
    intake.refusals.push_back(
        "--sivia needs the data's error bounds, and " + where +
        " has every one at 0 (q2_bound, dq1_bound, dq2_bound, ddq1_bound, ddq2_bound, "
        "tau_bound): SIVIA would find an empty set. Set them in the [sivia] section of a rig "
        "configuration (config/rig.toml shows them) and pass it with --config");
    return intake;
  }
  batch->files_listed_in = request.files_listed_in;
  intake.settings = settings_for(batch->rig, request.overrides);
  intake.batch = std::move(batch);
  return intake;
}

}  // namespace furuta::pipeline
