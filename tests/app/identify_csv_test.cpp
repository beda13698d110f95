// `furuta identify --csv FILE... --import-spec SPEC`: CSV recordings of a voltage-driven rig
// (another rig, another logger) through the command, and the command's errors for CSV inputs.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/identification/identify.hpp"
#include "furuta/identification/physical_inputs.hpp"
#include "furuta/model/model.hpp"
#include "simulated_logs.hpp"
#include "temp_dir.hpp"
#include "voltage_rig_csv.hpp"

namespace furuta::app {
namespace {

namespace fs = std::filesystem;
using furuta::testing::TempDir;
constexpr double kPi = std::numbers::pi;

model::Parameters<double> truth() {
  return furuta::testing::voltage_rig_truth();
}

constexpr const char* kSpec =
    "[csv]\n"                                                         // 1
    "time = \"t\"\ntime_unit = \"s\"\n"                               // 2-3
    "arm_angle = \"q1\"\npendulum_angle = \"q2\"\n"                   // 4-5
    "angle_unit = \"rad\"\npendulum_zero = \"down\"\n"                // 6-7
    "input = \"volts\"\ninput_kind = \"voltage\"\n"                   // 8-9
    "\n[motor]\n"                                                     // 10-11
    "torque_constant_nm_per_a = 0.03\nback_emf_v_s_per_rad = 0.03\n"  // 12-13
    "resistance_ohm = 3\ngear_ratio = 4\nefficiency = 0.9\n";         // 14-16

fs::path record(const fs::path& dir, const std::string& name, double phase,
                double input_delay_s = 0) {
  return furuta::testing::write_voltage_rig_csv(dir / name, phase, input_delay_s);
}

fs::path write(const fs::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

std::string read(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The CSV with each data row's cell `column` (0-based) replaced by change(cell).
void rewrite_column(const fs::path& csv, std::size_t column,
                    const std::function<std::string(const std::string&)>& change) {
  std::istringstream in(read(csv));
  std::string line, text;
  std::getline(in, line);
  text = line + "\n";
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
    cells.at(column) = change(cells.at(column));
    for (std::size_t i = 0; i < cells.size(); ++i) text += (i ? "," : "") + cells[i];
    text += "\n";
  }
  write(csv, text);
}

// The combined estimate of `name` in results.json.
double combined_estimate(const std::string& json, const std::string& name) {
  const auto combined = json.find("\"combined\": {\"estimate\": {");
  if (combined == std::string::npos) return NAN;
  const auto at = json.find("\"" + name + "\": ", combined);
  return std::strtod(json.c_str() + at + name.size() + 4, nullptr);
}

class IdentifyCsv : public ::testing::Test {
 protected:
  void SetUp() override {
    a_ = record(dir_.path(), "a.csv", 0.0);
    b_ = record(dir_.path(), "b.csv", 1.3);
    c_ = record(dir_.path(), "c.csv", 2.9);
    spec_ = write(dir_.path() / "import.toml", kSpec);
    options_.csvs = {a_, b_};
    options_.import_spec = spec_;
    options_.output_dir = dir_.path() / "out";
    // The output-error refinement is what the OutputError* and negative-lag tests are about; the
    // others test the command around it, and run in a fraction of the time without it.
    options_.no_output_error = true;
  }
  int run() { return run_identify_command(options_, out_, err_); }

  TempDir dir_;
  fs::path a_, b_, c_, spec_;
  IdentifyCommandOptions options_;
  std::ostringstream out_, err_;
};

TEST_F(IdentifyCsv, VoltageRigWithoutAConfigurationWritesTableResultsAndFigures) {
  options_.validate = c_;
  ASSERT_EQ(run(), 0) << err_.str();
  EXPECT_NE(out_.str().find("all experiments"), std::string::npos) << out_.str();
  EXPECT_NE(out_.str().find("held-out torque on c.csv"), std::string::npos) << out_.str();
  EXPECT_EQ(out_.str().find("truth"), std::string::npos);  // no simulation behind a CSV
  for (const char* name : {"results.json", "table.txt", "signals_1.svg", "signals_2.svg",
                           "torque_validation.svg", "report.html"}) {
    EXPECT_TRUE(fs::exists(options_.output_dir / name)) << name;
  }
  const std::string json = read(options_.output_dir / "results.json");
  for (const fs::path& input : {a_, b_, c_, spec_}) {
    EXPECT_NE(json.find(identification::sha256_file(input.string())), std::string::npos) << input;
  }
  // The configuration's input lag is the daemon's; a CSV's defaults to none.
  EXPECT_NE(json.find("\"input_lag_s\": 0,"), std::string::npos);
  const model::Parameters<double> expected = truth();
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const double estimate = combined_estimate(json, model::kParameterNames[k]);
    std::printf("[ measured ] command, 15 Hz default cut-off: %s %+.2f %%\n",
                model::kParameterNames[k], 100 * (estimate / expected[k] - 1));
    EXPECT_NEAR(estimate / expected[k], 1.0, 0.05) << model::kParameterNames[k];
  }
}

// The output-error section of the run's results.json against the voltage rig's truth: converged,
// physical, every mu and fv1 within 1 %, fv2 within 5 % (and the truth within 3 of its standard
// deviations when `within_3_sd`), the held-out pendulum predicted better than by LSMI. The
// section, for more checks.
nlohmann::json expect_refined_voltage_rig(const fs::path& output_dir, const std::string& what,
                                          bool within_3_sd) {
  const nlohmann::json j = nlohmann::json::parse(read(output_dir / "results.json"));
  EXPECT_TRUE(j.contains("output_error")) << what;
  if (!j.contains("output_error")) return {};
  const nlohmann::json& oe = j["output_error"];
  EXPECT_TRUE(oe["converged"].get<bool>()) << oe["message"];
  EXPECT_TRUE(oe["physical"].get<bool>());
  const model::Parameters<double> expected = truth();
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const char* name = model::kParameterNames[k];
    const double estimate = oe["estimate"][name].get<double>();
    const double sd = oe["std_dev"][name].get<double>();
    std::printf("[ measured ] output error on %s: %s %+.3f %% (%.2f sd)\n", what.c_str(), name,
                100 * (estimate / expected[k] - 1), (estimate - expected[k]) / sd);
    EXPECT_NEAR(estimate / expected[k], 1.0, k == 6 ? 0.05 : 0.01) << name;
    if (within_3_sd) {
      EXPECT_LT(std::abs(estimate - expected[k]), 3 * sd) << name;
    }
  }
  const nlohmann::json& free_run = oe["held_out_free_run"];
  EXPECT_LT(free_run["refined_rmse_rad"]["q2"].get<double>(),
            free_run["lsmi_rmse_rad"]["q2"].get<double>());
  return oe;
}

// The output-error refinement runs on CSVs too (the recorded input, linear between samples by
// default), within the bounds of the truth. (Not the truth within 3 sd: these angles have
// neither noise nor quantisation, so the sd are tiny, and linear chords shrink the voltage's
// peaks.)
TEST_F(IdentifyCsv, OutputErrorRefinesTheVoltageRig) {
  options_.no_output_error = false;
  options_.validate = c_;
  ASSERT_EQ(run(), 0) << err_.str();
  expect_refined_voltage_rig(options_.output_dir, "the voltage rig's CSV", false);
}

// The CSV target: the voltage rig recorded as a real logger would, its angles quantised by
// encoders (2000 counts a turn on the arm, 4096 on the pendulum) and its voltage reaching the motor
// 5 ms after it was recorded; the refinement comes within the same bounds as on the simulated rig,
// the truth within 3 of its standard deviations, and finds the lag.
TEST_F(IdentifyCsv, OutputErrorRecoversAQuantisedLaggedVoltageRig) {
  options_.no_output_error = false;
  const furuta::testing::CsvEncoders encoders{2000, 4096};
  const auto recorded = [&](const char* name, double phase) {
    return furuta::testing::write_voltage_rig_csv(dir_.path() / name, phase, -5e-3, {}, 10,
                                                  encoders);
  };
  options_.csvs = {recorded("qa.csv", 0.0), recorded("qb.csv", 1.3)};
  options_.validate = recorded("qc.csv", 2.9);
  // A sampled smooth voltage: a curve through the samples, not chords.
  std::string spec = kSpec;
  spec.insert(spec.find("\n[motor]"), "input_between_samples = \"cubic\"\n");
  write(spec_, spec);
  ASSERT_EQ(run(), 0) << err_.str() << out_.str();
  const nlohmann::json oe =
      expect_refined_voltage_rig(options_.output_dir, "the quantised, lagged CSV", true);
  ASSERT_TRUE(oe.contains("input_lag_s"));
  EXPECT_NEAR(oe["input_lag_s"].get<double>(), 5e-3, 0.2e-3);
}

// An arm with almost no mechanical friction (fv1 = 2e-5 N m s; the back-EMF damps it) whose
// voltage reaches the motor 5 ms after it is recorded, as on the QUBE-Servo: LSMI, which takes the
// input as on time, puts fv1 below zero by several sd and is not physical. The refinement runs
// all the same (it estimates the lag) and recovers the rig: the truth within 3 sd, exit 0.
TEST_F(IdentifyCsv, WhereLsmiIsNotPhysicalTheRefinementStillRunsAndRecoversTheRig) {
  options_.no_output_error = false;
  model::Parameters<double> rig = furuta::testing::voltage_rig_truth();
  rig.fv1 = 2e-5;
  const auto recorded = [&](const char* name, double phase) {
    return furuta::testing::write_voltage_rig_csv(dir_.path() / name, phase, -5e-3, {}, 10,
                                                  {2048, 2048}, rig);
  };
  options_.csvs = {recorded("fa.csv", 0.0), recorded("fb.csv", 1.3)};
  std::string spec = kSpec;
  spec.insert(spec.find("\n[motor]"), "input_between_samples = \"cubic\"\n");
  write(spec_, spec);
  ASSERT_EQ(run(), 0) << err_.str() << out_.str();
  const nlohmann::json j = nlohmann::json::parse(read(options_.output_dir / "results.json"));
  ASSERT_TRUE(j.contains("physical")) << "LSMI was expected not physical here";
  EXPECT_LT(j["combined"]["estimate"]["fv1"].get<double>(), 0.0);
  ASSERT_TRUE(j.contains("output_error")) << out_.str();
  const nlohmann::json& oe = j["output_error"];
  EXPECT_TRUE(oe["converged"].get<bool>()) << oe["message"];
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const char* name = model::kParameterNames[k];
    const double estimate = oe["estimate"][name].get<double>();
    const double sd = oe["std_dev"][name].get<double>();
    std::printf("[ measured ] output error where LSMI is not physical: %s %+.3f %% (%.2f sd)\n",
                name, 100 * (estimate / rig[k] - 1), (estimate - rig[k]) / sd);
    EXPECT_LT(std::abs(estimate - rig[k]), 3 * sd) << name;
    if (k < 5) {
      EXPECT_NEAR(estimate / rig[k], 1.0, 0.01) << name;
    }
  }
  EXPECT_NEAR(oe["input_lag_s"].get<double>(), 5e-3, 0.3e-3);
}

// Each parameter of the refinement within 3 of its standard deviations of `truth`.
void expect_within_3_sd(const nlohmann::json& oe, const model::Parameters<double>& truth,
                        const std::string& what) {
  EXPECT_TRUE(oe["converged"].get<bool>()) << what;
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const char* name = model::kParameterNames[k];
    const double error = oe["estimate"][name].get<double>() - truth[k];
    const double sd = oe["std_dev"][name].get<double>();
    std::printf("[ measured ] %s: %s %+.3f %% (%.2f sd)\n", what.c_str(), name,
                100 * error / truth[k], error / sd);
    EXPECT_LT(std::abs(error), 3 * sd) << what << " " << name;
  }
}

// The import spec of `furuta log export-csv`'s columns as docs/csv-import.md gives it for the
// project's own rig: each angle at its report's time, the command as the board received it, the
// board's ramp from the rest before the first command, the supply.
std::string own_export_spec(const config::RigConfig& rig) {
  std::ostringstream spec;
  spec << std::setprecision(17) << "[csv]\ninput_at_start = 0\n"
       << "time = \"t_s\"\ntime_unit = \"s\"\n"
       << "arm_angle = \"q1_rad\"\narm_time = \"arm_time_s\"\n"
       << "pendulum_angle = \"q2_rad\"\npendulum_time = \"pendulum_time_s\"\n"
       << "angle_unit = \"rad\"\npendulum_zero = \"down\"\n"
       << "input = \"written_duty\"\ninput_time = \"written_s\"\ninput_kind = \"duty\"\n"
       << "input_rate_limit = " << rig.excitation.board_acceleration_pct_per_s / 100 << "\n"
       << "supply = \"supply_v\"\n"
       << "arm_resolution = " << 2 * kPi / rig.arm_encoder.counts_per_joint_rev() << "\n"
       << "pendulum_resolution = " << 2 * kPi / rig.pendulum_encoder.counts_per_joint_rev() << "\n";
  return spec.str();
}

// A session of the simulated rig exported with `furuta log export-csv` and read back through an
// import spec as docs/csv-import.md writes it for the project's own rig (each angle at its
// report's time, the command as the board received it, the board's ramp, the supply): the
// refinement converges with the truth within 3 sd and the angles within their noise of the model,
// as from the log itself.
TEST_F(IdentifyCsv, ASessionExportedAndImportedBackIsIdentifiedWithinThreeSd) {
  const fs::path log = furuta::testing::simulated_session_log(dir_.path() / "logs", "rt", 1);
  ASSERT_FALSE(log.empty());
  const fs::path csv = dir_.path() / "session.csv";
  ASSERT_EQ(run_log_export_csv_command(log, csv, out_, err_), 0) << err_.str();
  const config::RigConfig rig = config::load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
  write(spec_, own_export_spec(rig));
  options_.csvs = {csv};
  options_.config_path = FURUTA_SOURCE_DIR "/config/rig.toml";
  options_.no_output_error = false;
  ASSERT_EQ(run(), 0) << err_.str() << out_.str();
  const nlohmann::json oe =
      nlohmann::json::parse(read(options_.output_dir / "results.json"))["output_error"];
  EXPECT_TRUE(oe["converged"].get<bool>()) << oe["message"];
  const model::Parameters<double>& truth = rig.simulation.parameters;
  expect_within_3_sd(oe, truth, "exported and imported back");
  EXPECT_LT(oe["residual_sigma"].get<double>(), 1.5);  // within the angles' noise

  // The same recording from 3 s on: it starts in motion, the refinement fits its first state.
  {
    std::istringstream in(read(csv));
    std::string line, cut;
    std::getline(in, line);
    cut = line + "\n";
    while (std::getline(in, line)) {
      if (std::stod(line.substr(line.find(',') + 1)) >= 3.0) cut += line + "\n";
    }
    write(dir_.path() / "in_motion.csv", cut);
  }
  options_.csvs = {dir_.path() / "in_motion.csv"};
  ASSERT_EQ(run(), 0) << err_.str() << out_.str();
  expect_within_3_sd(
      nlohmann::json::parse(read(options_.output_dir / "results.json"))["output_error"], truth,
      "started in motion");
}

// A session exported as CSV runs through the windowed set as its log does, with the daemon's bounds
// stated in the import spec's [guaranteed] table (one window per recording: [guaranteed] windows =
// 1): the set keeps the simulated truth and is about as narrow as the log's.
TEST_F(IdentifyCsv, AnExportedSessionRunsThroughTheGuaranteedSetAsItsLogDoes) {
  const fs::path log = furuta::testing::simulated_session_log(dir_.path() / "logs", "g", 1);
  ASSERT_FALSE(log.empty());
  const fs::path csv = dir_.path() / "session.csv";
  ASSERT_EQ(run_log_export_csv_command(log, csv, out_, err_), 0) << err_.str();
  std::string toml = read(FURUTA_SOURCE_DIR "/config/rig.toml");
  const auto windows = toml.find("\nwindows = 8 ");
  ASSERT_NE(windows, std::string::npos) << "config/rig.toml: no `windows = 8` in [guaranteed]";
  toml.replace(windows, 12, "\nwindows = 1");
  const fs::path config = write(dir_.path() / "one-window.toml", toml);
  const config::RigConfig rig = config::load_rig_config(config);

  IdentifyCommandOptions from_log;
  from_log.logs = {log};
  from_log.config_path = config;
  from_log.output_dir = dir_.path() / "from_log";
  from_log.guaranteed = true;
  ASSERT_EQ(run_identify_command(from_log, out_, err_), 0) << err_.str();
  const nlohmann::json log_set =
      nlohmann::json::parse(read(from_log.output_dir / "results.json"))["guaranteed"];
  ASSERT_EQ(log_set["verdict"], "contracted") << log_set["finding"];

  // The daemon's bounds, as the CSV's logger states them.
  const double arm_count = 2 * kPi / rig.arm_encoder.counts_per_joint_rev();
  const double pendulum_count = 2 * kPi / rig.pendulum_encoder.counts_per_joint_rev();
  std::ostringstream bounds;
  bounds << std::setprecision(17) << "\n[guaranteed]\n"
         << "arm_angle_error = " << arm_count / 2 << "\n"
         << "pendulum_angle_error = " << pendulum_count / 2 << "\n"
         << "pendulum_zero_error = " << 2.5 * pendulum_count << "\n"
         << "lag_ms = [" << rig.guaranteed.lag_ms[0] << ", " << rig.guaranteed.lag_ms[1] << "]\n"
         << "arm_rest_speed_rad_s = " << rig.guaranteed.arm_rest_speed_rad_s << "\n"
         << "supply_error_v = " << 0.5 * 80.0 / 2048.0 << "\n";
  const std::string spec = own_export_spec(rig);
  options_.csvs = {csv};
  options_.config_path = config;
  options_.no_output_error = false;
  options_.guaranteed = true;
  write(spec_, spec);
  EXPECT_EQ(run(), 2);
  EXPECT_NE(err_.str().find("has no [guaranteed] table"), std::string::npos) << err_.str();
  write(spec_, spec + bounds.str());
  ASSERT_EQ(run(), 0) << err_.str() << out_.str();
  const nlohmann::json csv_set =
      nlohmann::json::parse(read(options_.output_dir / "results.json"))["guaranteed"];
  ASSERT_EQ(csv_set["verdict"], "contracted") << csv_set["finding"];

  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const char* name = identification::kScaledParameterNames[k];
    const double truth = log_set["truth_scaled"][name].get<double>();
    const nlohmann::json& c = csv_set["set_scaled"][name];
    const nlohmann::json& l = log_set["set_scaled"][name];
    const double csv_width = c[1].get<double>() - c[0].get<double>();
    const double log_width = l[1].get<double>() - l[0].get<double>();
    std::printf("[ measured ] %s: CSV half-width %.3g %%, log %.3g %% (of the truth)\n", name,
                50 * csv_width / truth, 50 * log_width / truth);
    EXPECT_LE(c[0].get<double>(), truth) << name;
    EXPECT_GE(c[1].get<double>(), truth) << name;
    EXPECT_LT(csv_width, 2 * log_width) << name;
  }
  std::size_t from_spec = 0;
  for (const nlohmann::json& input : csv_set["physical_inputs"]) {
    if (input["source"] != "import_spec") continue;
    ++from_spec;
    EXPECT_NE(input["setting"].get<std::string>().find(spec_.string() + ":"), std::string::npos)
        << input["setting"];
  }
  EXPECT_EQ(from_spec, 5U);  // each angle's error, the pendulum's zero, the lag, the supply
}

// A controller's output as the input: every 10 ms a PD law on the quantised angles adds to the
// excitation and the DAC holds it. The input then carries the angles' noise, which biases a fit
// that treats the input as free of it (LSMI); the refinement simulates the input as recorded.
TEST_F(IdentifyCsv, AClosedLoopInputIsIdentifiedWithinThreeSd) {
  options_.no_output_error = false;
  const auto law = [](double, double q1, double q2) { return -3.0 * q1 - 1.0 * q2; };
  const furuta::testing::CsvEncoders encoders{4096, 4096};
  options_.csvs = {furuta::testing::write_closed_loop_voltage_rig_csv(dir_.path() / "la.csv", 0.0,
                                                                      law, encoders),
                   furuta::testing::write_closed_loop_voltage_rig_csv(dir_.path() / "lb.csv", 1.3,
                                                                      law, encoders)};
  std::string spec = kSpec;
  std::ostringstream keys;
  keys << std::setprecision(17)
       << "input_between_samples = \"held\"\narm_resolution = " << 2 * kPi / 4096
       << "\npendulum_resolution = " << 2 * kPi / 4096 << "\n";
  spec.insert(spec.find("\n[motor]"), keys.str());
  write(spec_, spec);
  ASSERT_EQ(run(), 0) << err_.str();
  expect_within_3_sd(
      nlohmann::json::parse(read(options_.output_dir / "results.json"))["output_error"], truth(),
      "closed loop");
}

// An input whose scale is known to 5 % only (here recorded 3 % high): with input_scale_sd the
// refinement fits the gain with that prior and the standard deviations carry it, so the truth lies
// within them; without it the scale counts as exact and every inertia is off by many sd.
TEST_F(IdentifyCsv, AnInputScaleKnownToFivePercentIsCarriedByTheStandardDeviations) {
  options_.no_output_error = false;
  furuta::testing::CsvColumns high;
  high.volts = [](double v) { return 1.03 * v; };
  options_.csvs = {furuta::testing::write_voltage_rig_csv(dir_.path() / "ga.csv", 0.0, 0.0, high),
                   furuta::testing::write_voltage_rig_csv(dir_.path() / "gb.csv", 1.3, 0.0, high)};
  std::string spec = kSpec;
  write(spec_, spec);
  ASSERT_EQ(run(), 0) << err_.str();
  const auto mu1 = [&] {
    const nlohmann::json oe =
        nlohmann::json::parse(read(options_.output_dir / "results.json"))["output_error"];
    return std::pair{oe["estimate"]["mu1"].get<double>(), oe["std_dev"]["mu1"].get<double>()};
  };
  const auto [exact, exact_sd] = mu1();
  std::printf("[ measured ] input 3 %% high, scale taken as exact: mu1 %+.2f %% (%.1f sd)\n",
              100 * (exact / truth().mu1 - 1), (exact - truth().mu1) / exact_sd);
  EXPECT_GT(std::abs(exact - truth().mu1), 3 * exact_sd);

  spec.insert(spec.find("\n[motor]"), "input_scale_sd = 0.05\n");
  write(spec_, spec);
  ASSERT_EQ(run(), 0) << err_.str();
  expect_within_3_sd(
      nlohmann::json::parse(read(options_.output_dir / "results.json"))["output_error"], truth(),
      "input scale known to 5 %");
}

// The project's rig.toml with 1 ms of USB jitter on every report, written into `dir`.
fs::path jittered_rig_config(const fs::path& dir) {
  std::string toml = read(FURUTA_SOURCE_DIR "/config/rig.toml");
  const std::string still = "\nusb_latency_jitter_ns = 0\n";
  const auto at = toml.find(still);
  EXPECT_NE(at, std::string::npos) << "config/rig.toml: no `" << still << "`";
  if (at != std::string::npos)
    toml.replace(at, still.size(), "\nusb_latency_jitter_ns = 1000000\n");
  return write(dir / "jittered.toml", toml);
}

// Host time stamps late by up to 1 ms at random: the boards' own clocks (the 1065's report
// counter, the 1047's packet ticks) put every reading back at its time, from the log and from its
// CSV export with the board columns named; the CSV without them is fitted on the host's stamps and
// the misfit is said.
TEST_F(IdentifyCsv, JitteredHostTimesAreReplacedByTheBoardsClocks) {
  const fs::path config = jittered_rig_config(dir_.path());
  const fs::path log =
      furuta::testing::simulated_session_log(dir_.path() / "logs", "jit", 1, {}, {}, {}, config);
  ASSERT_FALSE(log.empty());
  const config::RigConfig rig = config::load_rig_config(config);
  const model::Parameters<double>& truth = rig.simulation.parameters;
  const auto refined = [&](const char* what) {
    const nlohmann::json oe =
        nlohmann::json::parse(read(options_.output_dir / "results.json"))["output_error"];
    EXPECT_TRUE(oe["converged"].get<bool>()) << what;
    std::printf("[ measured ] 1 ms jitter, %s: residual sigma %.2f, times %s\n", what,
                oe["residual_sigma"].get<double>(), oe["time_stamps"]["q1"].dump().c_str());
    return oe;
  };
  const auto within_3_sd = [&](const nlohmann::json& oe, const char* what) {
    for (std::size_t k = 0; k < model::kParameterCount; ++k) {
      const char* name = model::kParameterNames[k];
      const double error = oe["estimate"][name].get<double>() - truth[k];
      EXPECT_LT(std::abs(error), 3 * oe["std_dev"][name].get<double>()) << what << " " << name;
    }
  };
  options_.no_output_error = false;
  options_.config_path = config;

  IdentifyCommandOptions from_log = options_;
  from_log.csvs.clear();
  from_log.import_spec.clear();
  from_log.logs = {log};
  ASSERT_EQ(run_identify_command(from_log, out_, err_), 0) << err_.str();
  const nlohmann::json logged = refined("log");
  EXPECT_EQ(logged["time_stamps"]["q1"], "board_clock");
  EXPECT_EQ(logged["time_stamps"]["q2"], "board_clock");
  EXPECT_NEAR(logged["host_delay_max_s"]["q2"].get<double>(), 1e-3, 0.1e-3);
  EXPECT_LT(logged["residual_sigma"].get<double>(), 3.0);
  within_3_sd(logged, "log");
  EXPECT_NE(out_.str().find("times: the boards' clocks (the host's stamps were on average"),
            std::string::npos)
      << out_.str();

  const fs::path csv = dir_.path() / "jittered.csv";
  ASSERT_EQ(run_log_export_csv_command(log, csv, out_, err_), 0) << err_.str();
  const std::string spec = own_export_spec(rig);
  write(spec_, spec);
  options_.csvs = {csv};
  ASSERT_EQ(run(), 0) << err_.str();
  const nlohmann::json host = refined("CSV, host stamps");
  EXPECT_EQ(host["time_stamps"]["q1"], "host");
  EXPECT_GT(host["residual_sigma"].get<double>(), 10.0);
  EXPECT_NE(host["warnings"].dump().find("further from the fitted model"), std::string::npos);

  write(spec_, spec +
                   "arm_board_time = \"arm_board_reports\"\n"
                   "pendulum_board_time = \"pendulum_board_ticks\"\n");
  ASSERT_EQ(run(), 0) << err_.str();
  const nlohmann::json board = refined("CSV, board columns");
  EXPECT_EQ(board["time_stamps"]["q2"], "board_clock");
  EXPECT_LT(board["residual_sigma"].get<double>(), 1.5);
  within_3_sd(board, "CSV");
}

// An interpolating encoder (angles with 2e-4 rad of white noise, so steps between samples far
// below it): without a stated resolution the refinement's noise model is estimated from the
// readings, which results.json says; it comes out near the true noise, the residual sigma about 1
// and the truth within 3 sd. With arm_resolution and pendulum_resolution stated (noise x sqrt(12))
// the noise model is the encoder's.
TEST_F(IdentifyCsv, AnInterpolatingEncodersNoiseIsEstimatedFromItsReadingsOrStated) {
  options_.no_output_error = false;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 2e-4);
  furuta::testing::CsvColumns noisy;
  noisy.q1 = [&](double q) { return q + noise(rng); };
  noisy.q2 = [&](double q) { return q + noise(rng); };
  options_.csvs = {furuta::testing::write_voltage_rig_csv(dir_.path() / "na.csv", 0.0, 0.0, noisy),
                   furuta::testing::write_voltage_rig_csv(dir_.path() / "nb.csv", 1.3, 0.0, noisy)};
  const auto refined = [&](const fs::path& out) {
    const nlohmann::json j = nlohmann::json::parse(read(out / "results.json"));
    EXPECT_TRUE(j["output_error"]["converged"].get<bool>());
    return j["output_error"];
  };
  // The sampled smooth voltage, as it was (linear chords would bias every parameter).
  std::string spec = kSpec;
  spec.insert(spec.find("\n[motor]"), "input_between_samples = \"cubic\"\n");
  write(spec_, spec);
  options_.output_dir = dir_.path() / "unstated";
  ASSERT_EQ(run(), 0) << err_.str();
  const nlohmann::json unstated = refined(options_.output_dir);
  EXPECT_EQ(unstated["angle_noise_source"]["q1"], "estimated_from_readings");
  EXPECT_EQ(unstated["angle_noise_source"]["q2"], "estimated_from_readings");
  const double q1_noise = unstated["angle_noise_rad"]["q1"].get<double>();
  const double q2_noise = unstated["angle_noise_rad"]["q2"].get<double>();
  std::printf(
      "[ measured ] angle noise estimated from the readings: q1 %.3g, q2 %.3g rad (true "
      "2e-4)\n",
      q1_noise, q2_noise);
  EXPECT_NEAR(q1_noise, 2e-4, 2e-5);
  EXPECT_NEAR(q2_noise, 2e-4, 2e-5);
  const double sigma_unstated = unstated["residual_sigma"].get<double>();
  EXPECT_GT(sigma_unstated, 0.8);
  EXPECT_LT(sigma_unstated, 1.25);
  expect_within_3_sd(unstated, truth(), "noise estimated");

  spec.insert(spec.find("\n[motor]"), "arm_resolution = 6.93e-4\npendulum_resolution = 6.93e-4\n");
  write(spec_, spec);
  options_.output_dir = dir_.path() / "stated";
  ASSERT_EQ(run(), 0) << err_.str();
  const nlohmann::json stated = refined(options_.output_dir);
  EXPECT_EQ(stated["angle_noise_source"]["q1"], "encoder_resolution");
  EXPECT_NEAR(stated["angle_noise_rad"]["q2"].get<double>(), 2e-4, 1e-6);
  const double sigma_stated = stated["residual_sigma"].get<double>();
  std::printf(
      "[ measured ] residual sigma with the noise estimated %.3g, with the stated resolution "
      "%.3g\n",
      sigma_unstated, sigma_stated);
  EXPECT_GT(sigma_stated, 0.7);
  EXPECT_LT(sigma_stated, 1.5);
  expect_within_3_sd(stated, truth(), "resolution stated");
}

// A voltage-driven rig's torque is not eq. 4's, and it came with no configuration: the report says
// both.
TEST_F(IdentifyCsv, TheReportSaysTheTorqueCameFromTheVoltageAndThereIsNoConfiguration) {
  ASSERT_EQ(run(), 0) << err_.str();
  const std::string html = read(options_.output_dir / "report.html");
  EXPECT_NE(html.find("the motor torque (from the recorded voltage via the import spec&#39;s "
                      "[motor]"),
            std::string::npos);
  EXPECT_EQ(html.find("eq. 4"), std::string::npos);
  EXPECT_NE(html.find("<th scope=\"row\">configuration</th><td>none"), std::string::npos);
}

TEST_F(IdentifyCsv, SpecWithoutResistanceNamesFileLineAndField) {
  std::string spec = kSpec;
  spec.erase(spec.find("resistance_ohm = 3\n"), 19);
  write(spec_, spec);
  EXPECT_EQ(run(), 2);
  EXPECT_NE(err_.str().find(spec_.string() + ":11: motor.resistance_ohm: missing"),
            std::string::npos)
      << err_.str();
  EXPECT_FALSE(fs::exists(options_.output_dir / "results.json"));
}

TEST_F(IdentifyCsv, DutyInputNeedsTheRigConfiguration) {
  std::string spec = kSpec;
  spec = spec.substr(0, spec.find("\n[motor]"));
  spec.replace(spec.find("\"voltage\""), 9, "\"duty\"");
  write(spec_, spec + "\n");
  EXPECT_EQ(run(), 2);
  EXPECT_NE(err_.str().find("pass --config"), std::string::npos) << err_.str();
}

TEST_F(IdentifyCsv, MistakesInTheCommandAreRefusedClearly) {
  const auto refused = [&](const IdentifyCommandOptions& options, const std::string& expected) {
    std::ostringstream out, err;
    EXPECT_EQ(run_identify_command(options, out, err), 2) << expected;
    EXPECT_NE(err.str().find(expected), std::string::npos) << err.str();
  };
  IdentifyCommandOptions no_spec = options_;
  no_spec.import_spec.clear();
  refused(no_spec, "--csv needs --import-spec");

  IdentifyCommandOptions positional;
  positional.logs = {a_};
  refused(positional, "a.csv is a CSV file: pass it as --csv");

  IdentifyCommandOptions mixed = options_;
  mixed.logs = {dir_.path() / "session.lcmlog"};
  refused(mixed, "give one kind");

  IdentifyCommandOptions log_validation = options_;
  log_validation.validate = dir_.path() / "session.lcmlog";
  refused(log_validation, "validate on the same kind");

  IdentifyCommandOptions fast = options_;
  fast.cutoff_hz = 30.0;  // stop band 60 Hz, above the 50 Hz Nyquist frequency of 10 ms samples
  refused(fast, "pass --cutoff below 25");

  write(c_, "t,q1,q2,volts\n0,0,0,oops\n");
  IdentifyCommandOptions bad_csv = options_;
  bad_csv.csvs = {c_};
  refused(bad_csv, "c.csv:2: volts: 'oops' is not a finite number");
}

// A time column read in the wrong unit is refused before any filtering, naming the file, the
// time_unit key with its line, and the unit that fits. Before: "cutoff_hz: below 1e-3 of the
// sample rate, liquid-dsp's ..." (seconds read as ms), or "pass --cutoff below 0.025" (ms read
// as seconds), which, followed, fitted nonsense with exit 0.
TEST_F(IdentifyCsv, ATimeUnitThatGivesNoPendulumsSamplePeriodIsNamed) {
  std::string spec = kSpec;
  spec.replace(spec.find("time_unit = \"s\""), 15, "time_unit = \"ms\"");
  write(spec_, spec);
  EXPECT_EQ(run(), 2);
  EXPECT_NE(err_.str().find("furuta identify: " + a_.string() + ": t: time_unit = \"ms\" (" +
                            spec_.string() + ":3) gives a sample period of 10 us"),
            std::string::npos)
      << err_.str();
  EXPECT_NE(err_.str().find("is the column in s?"), std::string::npos) << err_.str();
  EXPECT_EQ(err_.str().find("cutoff"), std::string::npos) << err_.str();

  write(spec_, kSpec);
  rewrite_column(a_, 0, [](const std::string& t) { return std::to_string(std::stod(t) * 1e3); });
  std::ostringstream out, err;
  EXPECT_EQ(run_identify_command(options_, out, err), 2);
  EXPECT_NE(err.str().find(a_.string() + ": t: time_unit = \"s\" (" + spec_.string() +
                           ":3) gives a sample period of 10 s"),
            std::string::npos)
      << err.str();
  EXPECT_NE(err.str().find("is the column in ms? Then write time_unit = \"ms\""), std::string::npos)
      << err.str();
  EXPECT_FALSE(fs::exists(options_.output_dir));
}

// Before: every parameter 0 +- 0 and exit 0.
TEST_F(IdentifyCsv, AnInputThatNeverChangesIsNothingToIdentify) {
  rewrite_column(a_, 3, [](const std::string&) { return "0"; });
  options_.csvs = {a_};
  EXPECT_EQ(run(), 2);
  EXPECT_NE(err_.str().find("furuta identify: a.csv: the input column 'volts' is 0 on every row: "
                            "nothing to identify"),
            std::string::npos)
      << err_.str();
  EXPECT_FALSE(fs::exists(options_.output_dir));

  // One of several: its Table I column would be 0 +- 0.
  options_.csvs = {a_, b_};
  std::ostringstream out, err;
  EXPECT_EQ(run_identify_command(options_, out, err), 2);
  EXPECT_NE(err.str().find("a.csv: the input column 'volts' is constant (0 on every row): nothing "
                           "to identify in it"),
            std::string::npos)
      << err.str();
  EXPECT_NE(err.str().find("leave it out of --csv"), std::string::npos) << err.str();

  // All of them, constant but not zero.
  for (const fs::path& csv : {a_, b_}) {
    rewrite_column(csv, 3, [](const std::string&) { return "1.5"; });
  }
  std::ostringstream out2, err2;
  EXPECT_EQ(run_identify_command(options_, out2, err2), 2);
  EXPECT_NE(err2.str().find("every fitted recording's input column 'volts' is constant (a.csv, "
                            "b.csv); in a.csv it is 1.5 on every row: nothing to identify"),
            std::string::npos)
      << err2.str();
}

// Before: SIVIA ran with every error bound 0 and reported an empty set, exit 0.
TEST_F(IdentifyCsv, SiviaWithoutErrorBoundsIsRefused) {
  options_.sivia = true;
  EXPECT_EQ(run(), 2);
  EXPECT_NE(err_.str().find("furuta identify: --sivia needs the data's error bounds, and without "
                            "--config, [sivia] has every one at 0"),
            std::string::npos)
      << err_.str();
  EXPECT_NE(err_.str().find("pass it with --config"), std::string::npos) << err_.str();
  EXPECT_FALSE(fs::exists(options_.output_dir));
}

// Before: a negative lag was used without a word.
TEST_F(IdentifyCsv, ANegativeEstimatedInputLagIsAWarning) {
  options_.no_output_error = false;
  // The volts written 5 ms late: the angles lead the input column.
  a_ = record(dir_.path(), "a.csv", 0.0, 5e-3);
  b_ = record(dir_.path(), "b.csv", 1.3, 5e-3);
  options_.estimate_input_lag = true;
  ASSERT_EQ(run(), 0) << err_.str();
  EXPECT_NE(out_.str().find("warning: the estimated input lag is negative (-"), std::string::npos)
      << out_.str();
  const std::string json = read(options_.output_dir / "results.json");
  EXPECT_NE(json.find("the angles would move before the input that drives them"),
            std::string::npos);
  const auto lag = json.find("\"input_lag_s\": ");
  ASSERT_NE(lag, std::string::npos);
  EXPECT_NEAR(std::strtod(json.c_str() + lag + 15, nullptr), -5e-3, 1e-3);
  // The refinement finds the same, and says so.
  const nlohmann::json oe = nlohmann::json::parse(json)["output_error"];
  EXPECT_TRUE(oe["converged"].get<bool>()) << oe["message"];
  EXPECT_NEAR(oe["input_lag_s"].get<double>(), -5e-3, 0.2e-3);
  EXPECT_NE(out_.str().find("warning: output error: the angles lead the recorded input by 4.9"),
            std::string::npos)
      << out_.str();
}

// Before: a second run into the same directory left the first run's figures beside its files.
TEST_F(IdentifyCsv, ASecondRunReplacesTheFirstsDirectoryWhole) {
  options_.validate = c_;
  ASSERT_EQ(run(), 0) << err_.str();
  ASSERT_TRUE(fs::exists(options_.output_dir / "torque_validation.svg"));
  options_.validate.clear();
  std::ostringstream out, err;
  ASSERT_EQ(run_identify_command(options_, out, err), 0) << err.str();
  EXPECT_FALSE(fs::exists(options_.output_dir / "torque_validation.svg"));
  EXPECT_TRUE(fs::exists(options_.output_dir / "results.json"));
  EXPECT_NE(out.str().find("the previous run's files in " + options_.output_dir.string() +
                           " were replaced"),
            std::string::npos)
      << out.str();
  // Nothing left beside it: no staging directory, no old run.
  std::vector<std::string> beside;
  for (const auto& entry : fs::directory_iterator(dir_.path())) {
    beside.push_back(entry.path().filename().string());
  }
  EXPECT_EQ(std::count(beside.begin(), beside.end(), "out"), 1);
  for (const std::string& name : beside) EXPECT_EQ(name.find(".out."), std::string::npos) << name;
}

TEST_F(IdentifyCsv, ADirectoryThatIsNotAPreviousRunIsRefusedAndLeftAlone) {
  fs::create_directories(options_.output_dir / "notes");
  write(options_.output_dir / "results.json", "{}");
  write(options_.output_dir / "thesis.tex", "mine");
  EXPECT_EQ(run(), 2);
  EXPECT_NE(err_.str().find("furuta identify: -o " + options_.output_dir.string() + ": " +
                            options_.output_dir.string() +
                            " is not empty and not a previous run's output (it holds"),
            std::string::npos)
      << err_.str();
  EXPECT_NE(err_.str().find("'thesis.tex'"), std::string::npos) << err_.str();
  EXPECT_EQ(read(options_.output_dir / "thesis.tex"), "mine");
  EXPECT_EQ(read(options_.output_dir / "results.json"), "{}");

  // The directory the command runs in is never replaced, even when empty.
  const fs::path here = fs::current_path();
  fs::create_directories(dir_.path() / "empty");
  fs::current_path(dir_.path() / "empty");
  options_.output_dir = ".";
  std::ostringstream out, err;
  const int code = run_identify_command(options_, out, err);
  fs::current_path(here);
  EXPECT_EQ(code, 2);
  EXPECT_NE(err.str().find("is the current directory or holds it"), std::string::npos) << err.str();
}

// Outputs of the commands before the marker file: results.json beside only their own files.
TEST_F(IdentifyCsv, AnOlderRunsDirectoryIsRecognisedAndReplaced) {
  fs::create_directories(options_.output_dir);
  write(options_.output_dir / "results.json", "{}");
  write(options_.output_dir / "sivia.svg", "<svg/>");
  write(options_.output_dir / "scenario_1_lsmi.svg", "<svg/>");
  ASSERT_EQ(run(), 0) << err_.str();
  EXPECT_FALSE(fs::exists(options_.output_dir / "sivia.svg"));
  EXPECT_FALSE(fs::exists(options_.output_dir / "scenario_1_lsmi.svg"));
  EXPECT_NE(read(options_.output_dir / "results.json"), "{}");
}

}  // namespace
}  // namespace furuta::app
