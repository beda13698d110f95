// The diagnosis by fitting the mistake (identification/diagnosis.hpp) through `furuta identify`:
// a simulated session exported as CSV (docs/csv-import.md, "The project's own export") and read
// back with one mistake in the import spec at a time; each is named with its value and the
// setting to change. The correct spec with --diagnose says the recording fits best as it is.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>

#include "commands.hpp"
#include "furuta/config/rig_config.hpp"
#include "simulated_logs.hpp"
#include "temp_dir.hpp"

namespace furuta::app::diagnosis_test {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;

std::string read(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

class Diagnosis : public ::testing::Test {
 protected:
  // One exported session for the whole suite.
  static const fs::path& csv() {
    static furuta::testing::TempDir dir;
    static const fs::path path = [] {
      const fs::path log =
          furuta::testing::simulated_session_log(dir.path() / "logs", "diagnosis", 3, 6.0);
      std::ostringstream out, err;
      EXPECT_EQ(run_log_export_csv_command(log, dir.path() / "session.csv", out, err), 0)
          << err.str();
      return dir.path() / "session.csv";
    }();
    return path;
  }

  // The spec that reads the export correctly, in radians or in counts, with `extra` keys after
  // it (a key given twice is replaced: `replace` holds "key = value" lines that take its place).
  static std::string spec(bool counts, const std::string& replace = "") {
    const config::RigConfig rig = config::load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
    std::map<std::string, std::string> keys = {
        {"time", "\"t_s\""},
        {"time_unit", "\"s\""},
        {"arm_angle", counts ? "\"arm_counts\"" : "\"q1_rad\""},
        {"arm_time", "\"arm_time_s\""},
        {"pendulum_angle", counts ? "\"pendulum_counts\"" : "\"q2_rad\""},
        {"pendulum_time", "\"pendulum_time_s\""},
        {"angle_unit", counts ? "\"counts\"" : "\"rad\""},
        {"pendulum_zero", "\"down\""},
        {"input", "\"written_duty\""},
        {"input_time", "\"written_s\""},
        {"input_kind", "\"duty\""},
        {"input_rate_limit", std::to_string(rig.excitation.board_acceleration_pct_per_s / 100)},
        {"supply", "\"supply_v\""},
    };
    std::ostringstream number;
    number << std::setprecision(17);
    if (counts) {
      keys["arm_counts_per_rev"] = std::to_string(rig.arm_encoder.counts_per_joint_rev());
      keys["pendulum_counts_per_rev"] = std::to_string(rig.pendulum_encoder.counts_per_joint_rev());
    } else {
      number << 2 * kPi / rig.arm_encoder.counts_per_joint_rev();
      keys["arm_resolution"] = number.str();
      number.str("");
      number << 2 * kPi / rig.pendulum_encoder.counts_per_joint_rev();
      keys["pendulum_resolution"] = number.str();
    }
    std::istringstream lines(replace);
    for (std::string line; std::getline(lines, line);) {
      const auto eq = line.find(" = ");
      keys[line.substr(0, eq)] = line.substr(eq + 3);
    }
    std::string text = "[csv]\n";
    for (const auto& [key, value] : keys) text += key + " = " + value + "\n";
    return text;
  }

  struct Outcome {
    int code = -1;
    std::string out;
    nlohmann::json diagnosis;
  };
  Outcome identify(const std::string& spec_text, bool diagnose = false) {
    const fs::path spec = dir_.path() / "import.toml";
    std::ofstream(spec) << spec_text;
    IdentifyCommandOptions options;
    options.csvs = {csv()};
    options.import_spec = spec;
    options.config_path = FURUTA_SOURCE_DIR "/config/rig.toml";
    options.output_dir = dir_.path() / "out";
    options.diagnose = diagnose;
    std::ostringstream out, err;
    Outcome o;
    o.code = run_identify_command(options, out, err);
    o.out = out.str() + err.str();
    const nlohmann::json results = nlohmann::json::parse(read(options.output_dir / "results.json"));
    o.diagnosis = results["output_error"].value("diagnosis", nlohmann::json());
    return o;
  }

  // The mistake named, its value within `tolerance` (relative), and the setting in the warning.
  void expect_named(const std::string& spec_text, const std::string& mistake, double value,
                    double tolerance, const std::string& setting) {
    const Outcome o = identify(spec_text);
    ASSERT_FALSE(o.diagnosis.is_null()) << o.out;
    ASSERT_FALSE(o.diagnosis["named"].is_null()) << o.out;
    const nlohmann::json& named = o.diagnosis["named"];
    const auto at = o.out.find("diagnosis: ");
    ASSERT_NE(at, std::string::npos) << o.out;
    const std::string line = o.out.substr(at, o.out.find('\n', at) - at);
    std::printf("[ measured ] %s %.4g (residual sigma %.3g, %.3g as recorded): %s\n",
                named["mistake"].get<std::string>().c_str(), named["value"].get<double>(),
                named["residual_sigma"].get<double>(),
                o.diagnosis["as_recorded"]["residual_sigma"].get<double>(), line.c_str());
    EXPECT_EQ(named["mistake"], mistake);
    EXPECT_NEAR(named["value"].get<double>() / value, 1.0, tolerance);
    EXPECT_NE(line.find(setting), std::string::npos) << line;
  }

  furuta::testing::TempDir dir_;
};

TEST_F(Diagnosis, ACorrectRecordingFitsBestAsItIs) {
  const Outcome o = identify(spec(false), true);
  ASSERT_FALSE(o.diagnosis.is_null()) << o.out;
  EXPECT_TRUE(o.diagnosis["named"].is_null()) << o.diagnosis["named"].dump();
  EXPECT_TRUE(o.diagnosis["as_recorded"]["plausible"].get<bool>());
  EXPECT_NE(o.out.find("diagnosis: signs, zero and units as recorded fit best"), std::string::npos)
      << o.out;
  EXPECT_EQ(o.code, 0);
}

TEST_F(Diagnosis, PendulumSign) {
  expect_named(spec(false, "pendulum_angle_scale = -1"), "pendulum_scale", -1.0, 1e-9,
               "pendulum_angle_scale");
}

TEST_F(Diagnosis, PendulumZeroUpright) {
  expect_named(spec(false, "pendulum_zero = \"up\""), "pendulum_zero", kPi, 1e-9,
               "pendulum_zero = \"up\"");
}

TEST_F(Diagnosis, ArmSign) {
  expect_named(spec(false, "arm_angle_scale = -1"), "arm_scale", -1.0, 1e-9, "arm_angle_scale");
}

TEST_F(Diagnosis, InputSign) {
  expect_named(spec(false, "input_scale = -1"), "input_scale", -1.0, 1e-9, "input_scale = -1");
}

TEST_F(Diagnosis, RadiansReadAsDegrees) {
  expect_named(spec(false, "angle_unit = \"deg\""), "angle_unit", kPi / 180, 1e-9, "angle_unit");
}

TEST_F(Diagnosis, PendulumCountsFourTimesTooMany) {
  const config::RigConfig rig = config::load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
  const double counts = rig.pendulum_encoder.counts_per_joint_rev();
  std::ostringstream key;
  key << "pendulum_counts_per_rev = " << 4 * counts;
  std::ostringstream likely;
  likely << "likely " << counts << ", not " << 4 * counts;
  expect_named(spec(true, key.str()), "pendulum_scale", 0.25, 0.01, likely.str());
}

TEST_F(Diagnosis, ArmCountsTwiceTooMany) {
  const config::RigConfig rig = config::load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
  const double counts = rig.arm_encoder.counts_per_joint_rev();
  std::ostringstream key;
  key << "arm_counts_per_rev = " << 2 * counts;
  expect_named(spec(true, key.str()), "arm_scale", 0.5, 1e-9, "arm_counts_per_rev");
}

TEST_F(Diagnosis, InputFiveTimesTooLow) {
  // CAD's magnitudes give the value, to CAD's own accuracy.
  expect_named(spec(false, "input_scale = 0.2"), "input_scale", 0.2, 0.1, "divide the input by");
}

}  // namespace
}  // namespace furuta::app::diagnosis_test
