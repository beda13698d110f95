// `furuta identify LOG... [--validate LOG]`: LSMI on session logs, Table I, results.json, figures.
#include <fstream>
#include <ostream>

#include "commands.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/identification/identify.hpp"
#include "furuta/session_log/session_log.hpp"

namespace furuta::app {

namespace {

void write_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

}  // namespace

identification::IdentifyOptions identify_options_for(const config::RigConfig& rig,
                                                     const IdentifyCommandOptions& options) {
  identification::IdentifyOptions identify_options;
  const double cutoff_hz = options.cutoff_hz.value_or(rig.identification.cutoff_hz);
  identify_options.preprocess.cutoff_hz = cutoff_hz;
  identify_options.preprocess.differentiator_passband_hz = cutoff_hz;
  identify_options.preprocess.differentiator_stopband_hz = 2 * cutoff_hz;
  identify_options.preprocess.butterworth_order = rig.identification.butterworth_order;
  identify_options.preprocess.differentiator_taps = rig.identification.differentiator_taps;
  const std::optional<double> lag_ms =
      options.estimate_input_lag
          ? std::nullopt
          : (options.input_lag_ms ? options.input_lag_ms : rig.identification.input_lag_ms);
  identify_options.estimate_input_lag = !lag_ms.has_value();
  identify_options.preprocess.input_lag_s = lag_ms.value_or(0.0) * 1e-3;
  return identify_options;
}

int run_identify_command(const IdentifyCommandOptions& options, std::ostream& out,
                         std::ostream& err) {
  if (options.logs.empty()) {
    err << "furuta identify: give at least one session log\n";
    return 2;
  }
  std::vector<session_log::SessionLog> logs;
  for (const auto& path : options.logs) logs.push_back(session_log::load_session_log(path));
  std::optional<session_log::SessionLog> held_out;
  if (!options.validate.empty()) held_out = session_log::load_session_log(options.validate);

  // The rig the data came from: the configuration its first log carries, unless one is given.
  if (!logs.front().start && options.config_path.empty()) {
    err << "furuta identify: " << options.logs.front().string()
        << " has no session start record (and so no configuration); pass --config\n";
    return 2;
  }
  const config::RigConfig rig =
      options.config_path.empty()
          ? config::parse_rig_config(logs.front().start->rig_config_toml,
                                     options.logs.front().string() + " (rig configuration)")
          : config::load_rig_config(options.config_path);

  std::vector<identification::RawExperiment> experiments;
  for (const auto& log : logs) experiments.push_back(identification::experiment_from_log(log));
  std::optional<identification::RawExperiment> validation;
  if (held_out) validation = identification::experiment_from_log(*held_out);

  const identification::IdentifyOptions identify_options = identify_options_for(rig, options);
  identification::Identification id =
      identification::identify(experiments, validation, identify_options, rig.motor);
  if (rig.nominal) id.nominal = identification::to_vector(*rig.nominal);
  if (rig.backend == config::UsbBackend::simulated) {
    id.truth = identification::to_vector(rig.simulation.parameters);
  }

  std::filesystem::create_directories(options.output_dir);
  std::vector<identification::InputFile> inputs;
  for (const auto& path : options.logs) {
    inputs.push_back({path.string(), identification::sha256_file(path.string())});
  }
  if (!options.validate.empty()) {
    inputs.push_back(
        {options.validate.string(), identification::sha256_file(options.validate.string())});
  }
  const std::string table = identification::format_table_one(id);
  write_file(options.output_dir / "table.txt", table);
  write_file(options.output_dir / "results.json",
             identification::results_json(id, inputs, daemon::kSoftwareVersion));
  const double resolution = bridge::resolution_rad(rig.pendulum_encoder);
  for (std::size_t i = 0; i < id.processed.size(); ++i) {
    write_file(options.output_dir / ("signals_" + std::to_string(i + 1) + ".svg"),
               identification::svg_signals(id.raw[i], id.processed[i], resolution));
  }
  if (id.validation) {
    write_file(options.output_dir / "torque_validation.svg",
               identification::svg_torque_validation(*id.validation));
  }
  out << table;
  out << "wrote " << (options.output_dir / "results.json").string() << " and figures in "
      << options.output_dir.string() << "\n";
  return 0;
}

}  // namespace furuta::app
