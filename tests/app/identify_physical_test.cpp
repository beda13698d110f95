// `furuta identify --csv` on recordings made with a sign, zero or unit wrong: LSMI still reports
// (it is the paper's reference), and a loud warning on the terminal, in results.json and in the
// report names the condition violated and the likely cause. The refinement runs all the same, and
// says that its fit is no answer either: it did not converge (exit 1), or its angles lie far from
// the model, or its own estimate is not physical. The patterns printed here are the table of
// docs/csv-import.md, "When a fit is not physical".
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>

#include "commands.hpp"
#include "furuta/model/model.hpp"
#include "temp_dir.hpp"
#include "voltage_rig_csv.hpp"

namespace furuta::app::identify_physical_test {
namespace {

namespace fs = std::filesystem;
using furuta::testing::TempDir;
using nlohmann::json;
constexpr double kPi = std::numbers::pi;

model::Parameters<double> truth() {
  return furuta::testing::voltage_rig_truth();
}

constexpr const char* kSpec =
    "[csv]\n"
    "time = \"t\"\ntime_unit = \"s\"\n"
    "arm_angle = \"q1\"\npendulum_angle = \"q2\"\n"
    "angle_unit = \"rad\"\npendulum_zero = \"down\"\n"
    "input = \"volts\"\ninput_kind = \"voltage\"\n"
    "\n[motor]\n"
    "torque_constant_nm_per_a = 0.03\nback_emf_v_s_per_rad = 0.03\n"
    "resistance_ohm = 3\ngear_ratio = 4\nefficiency = 0.9\n";

// How a recording went wrong: applied to each row's (q1, q2, volts) in the model's conventions.
using Mistake = furuta::testing::CsvColumns;

fs::path record(const fs::path& path, double phase, const Mistake& mistake) {
  return furuta::testing::write_voltage_rig_csv(path, phase, 0.0, mistake, 12);
}

std::string read(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

struct Outcome {
  int code = -1;
  std::string out, err;
  json results;
  std::string html;
};

Outcome identify(const fs::path& dir, const Mistake& mistake) {
  const fs::path spec = dir / "import.toml";
  std::ofstream(spec) << kSpec;
  IdentifyCommandOptions options;
  options.csvs = {record(dir / "a.csv", 0.0, mistake), record(dir / "b.csv", 1.3, mistake)};
  options.import_spec = spec;
  options.output_dir = dir / "out";
  Outcome o;
  std::ostringstream out, err;
  o.code = run_identify_command(options, out, err);
  o.out = out.str();
  o.err = err.str();
  if (fs::exists(options.output_dir / "results.json")) {
    o.results = json::parse(read(options.output_dir / "results.json"));
    o.html = read(options.output_dir / "report.html");
  }
  return o;
}

// The combined LSMI estimate, relative to the truth, as the measured pattern.
void print_pattern(const std::string& name, const json& results) {
  std::printf("[ measured ] %-24s", name.c_str());
  const model::Parameters<double> p = truth();
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const double estimate = results["combined"]["estimate"][model::kParameterNames[k]];
    std::printf(" %s %+.3g", model::kParameterNames[k], estimate / p[k]);
  }
  std::printf("\n");
}

class IdentifyPhysical : public ::testing::Test {
 protected:
  // Exit 0, the pattern printed, and the warning naming `cause` on the terminal, in results.json
  // (its warnings and its "physical" section) and at the top of the report.
  void expect_warning(const std::string& name, const Mistake& mistake, const std::string& cause,
                      const std::string& key) {
    const Outcome o = identify(dir_.path(), mistake);
    ASSERT_TRUE(o.results.contains("output_error")) << o.err;
    const json& refined = o.results["output_error"];
    ASSERT_EQ(o.code, refined["converged"].get<bool>() ? 0 : 1) << o.err;
    print_pattern(name, o.results);
    const auto at = o.out.find("warning: not physical: ");
    ASSERT_NE(at, std::string::npos) << o.out;
    const std::string line = o.out.substr(at, o.out.find('\n', at) - at);
    std::printf("[ warning  ] %s\n", line.c_str());
    EXPECT_NE(line.find(key), std::string::npos) << line;
    ASSERT_TRUE(o.results.contains("physical")) << o.results.dump();
    EXPECT_EQ(o.results["physical"]["likely_cause"], cause) << o.results["physical"].dump();
    bool in_warnings = false;
    for (const auto& w : o.results["warnings"]) {
      in_warnings = in_warnings || w.get<std::string>().starts_with("not physical: ");
    }
    EXPECT_TRUE(in_warnings) << o.results["warnings"].dump();
    // The refinement ran, and its fit says it is no answer.
    const bool misfit = o.out.find("output error: the angles lie ") != std::string::npos;
    const bool refined_unphysical =
        o.out.find("warning: output error: not physical: the output-error estimate") !=
        std::string::npos;
    std::printf("[ refined  ] %s: %s, residual sigma %.3g%s%s\n", name.c_str(),
                refined["converged"].get<bool>() ? "converged" : "NOT converged",
                refined["residual_sigma"].get<double>(), misfit ? ", misfit warned" : "",
                refined_unphysical ? ", its estimate not physical" : "");
    EXPECT_TRUE(!refined["converged"].get<bool>() || misfit || refined_unphysical) << o.out;
    // And the diagnosis refits the mistake and names it.
    const auto diagnosis = o.out.find("diagnosis: ");
    ASSERT_NE(diagnosis, std::string::npos) << o.out;
    const std::string said = o.out.substr(diagnosis, o.out.find('\n', diagnosis) - diagnosis);
    std::printf("[ diagnosis] %s\n", said.c_str());
    const std::map<std::string, std::string> named = {
        {"pendulum sign", "the pendulum's angle counted the other way"},
        {"pendulum zero", "the pendulum's angle counted from upright, not"},
        {"pendulum zero and sign", "the pendulum's angle counted from upright and the other way"},
        {"angle unit", "both angles in degrees read as radians"},
        {"arm sign", "the arm's angle counted the other way"},
        {"input sign", "the input's sign flipped"}};
    ASSERT_TRUE(named.contains(cause)) << cause;
    EXPECT_NE(said.find("the data fit best with " + named.at(cause)), std::string::npos) << said;
    EXPECT_EQ(o.out.find("BUG"), std::string::npos) << o.out;
    const auto banner = o.html.find("<section id=\"physical\"");
    EXPECT_NE(banner, std::string::npos);
    EXPECT_LT(banner, o.html.find("<nav>"));
  }

  TempDir dir_;
};

TEST_F(IdentifyPhysical, ACorrectRecordingGivesNoWarning) {
  const Outcome o = identify(dir_.path(), {});
  ASSERT_EQ(o.code, 0) << o.err;
  print_pattern("correct", o.results);
  EXPECT_EQ(o.out.find("not physical"), std::string::npos) << o.out;
  EXPECT_FALSE(o.results.contains("physical"));
  EXPECT_EQ(o.html.find("id=\"physical\""), std::string::npos);
  ASSERT_TRUE(o.results.contains("output_error")) << o.out;
  EXPECT_TRUE(o.results["output_error"]["physical"].get<bool>());
}

TEST_F(IdentifyPhysical, PendulumSignFlipped) {
  Mistake m;
  m.q2 = [](double q) { return -q; };
  expect_warning("pendulum sign flipped", m, "pendulum sign", "pendulum_angle_scale");
}

TEST_F(IdentifyPhysical, PendulumZeroAtTheTop) {
  Mistake m;
  m.q2 = [](double q) { return q - kPi; };  // recorded from upright, imported as from hanging
  expect_warning("zero at the top", m, "pendulum zero", "pendulum_zero");
}

TEST_F(IdentifyPhysical, PendulumZeroAtTheTopAndSignFlipped) {
  Mistake m;
  m.q2 = [](double q) { return kPi - q; };
  expect_warning("zero at the top, flipped", m, "pendulum zero and sign", "pendulum_zero");
}

TEST_F(IdentifyPhysical, DegreesReadAsRadians) {
  Mistake m;
  m.q1 = m.q2 = [](double q) { return q * 180 / kPi; };
  expect_warning("degrees read as radians", m, "angle unit", "angle_unit");
}

TEST_F(IdentifyPhysical, ArmSignFlipped) {
  Mistake m;
  m.q1 = [](double q) { return -q; };
  expect_warning("arm sign flipped", m, "arm sign", "arm_angle_scale");
}

TEST_F(IdentifyPhysical, InputSignFlipped) {
  Mistake m;
  m.volts = [](double v) { return -v; };
  expect_warning("input sign flipped", m, "input sign", "input_scale");
}

}  // namespace
}  // namespace furuta::app::identify_physical_test
