// The main job (scripts/run.sh) end to end against a golden copy of its outputs: two bang-bang
// sessions and a validation session of the simulated rig, then the trigger's pass, must give the
// same results.json (every number within 1e-12 relative) and the same Table I and Table III text as
// the golden files in tests/data/golden/. A refactoring that moves code keeps these figures; a
// change meant to alter them regenerates the files with FURUTA_UPDATE_GOLDEN=1 and says why in
// its commit.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "furuta/config/rig_config.hpp"
#include "log_processor.hpp"
#include "simulated_logs.hpp"
#include "temp_dir.hpp"

namespace furuta::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const fs::path kGoldenDir = fs::path(FURUTA_TEST_DATA_DIR) / "golden";

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Session names carry the wall-clock time they ran at (Table I lists them whole above its E1, E2
// columns; the pattern still takes any tail of the date), and a "-2" when two sessions of one
// label started in the same second. Runs of blanks are one: a table's columns may shift with the
// names' lengths.
std::string without_times(const std::string& text) {
  static const std::regex stamp(
      R"([0-9-]*T[0-9]{2}-[0-9]{2}-[0-9]{2}Z_([A-Za-z]+(-[A-Za-z]+)*)(-[0-9]+)?)");
  static const std::regex blanks(" +");
  return std::regex_replace(std::regex_replace(text, stamp, "<time>_$1"), blanks, " ");
}

// What differs between two runs of the same job: where the logs were, their hashes (the logs hold
// wall-clock times), how long things took, and the software version.
const std::set<std::string> kNotCompared = {"path", "sha256", "seconds", "software_version"};

void expect_same(const json& golden, const json& actual, const std::string& where) {
  if (golden.is_number() && actual.is_number()) {
    const double g = golden.get<double>();
    const double a = actual.get<double>();
    const double tolerance = 1e-12 * std::max(std::fabs(g), std::fabs(a));
    EXPECT_TRUE(g == a || std::fabs(g - a) <= tolerance)
        << where << ": golden " << golden.dump() << ", now " << actual.dump();
    return;
  }
  ASSERT_EQ(golden.type_name(), std::string(actual.type_name())) << where;
  if (golden.is_object()) {
    for (const auto& [key, value] : golden.items()) {
      if (kNotCompared.count(key) > 0) continue;
      ASSERT_TRUE(actual.contains(key)) << where << "." << key << " is missing";
      expect_same(value, actual.at(key), where + "." + key);
    }
    for (const auto& [key, value] : actual.items()) {
      EXPECT_TRUE(golden.contains(key)) << where << "." << key << " is new";
    }
  } else if (golden.is_array()) {
    ASSERT_EQ(golden.size(), actual.size()) << where;
    for (std::size_t i = 0; i < golden.size(); ++i) {
      expect_same(golden[i], actual[i], where + "[" + std::to_string(i) + "]");
    }
  } else if (golden.is_string()) {
    EXPECT_EQ(without_times(golden.get<std::string>()), without_times(actual.get<std::string>()))
        << where;
  } else {
    EXPECT_EQ(golden, actual) << where;
  }
}

TEST(GoldenMainJob, ResultsAndTablesAreTheGoldenOnes) {
  testing::TempDir dir;
  const fs::path logs = dir.path() / "logs";
  ASSERT_FALSE(testing::simulated_session_log(logs, "bang-bang", 1).empty());
  ASSERT_FALSE(testing::simulated_session_log(logs, "bang-bang", 2).empty());
  ASSERT_FALSE(testing::simulated_session_log(logs, "validation", 3).empty());

  const config::RigConfig config = config::load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
  LogProcessorOptions options;
  options.logs_dir = logs;
  options.identifications_dir = dir.path() / "identifications";
  options.automation = config.automation;
  std::ostringstream out, err;
  const ProcessingPass pass = process_logs(options, out, err);
  ASSERT_EQ(pass.identifications.size(), 1u) << out.str() << err.str();
  const fs::path identification = pass.identifications.front();

  const char* files[] = {"results.json", "table.txt", "table3.txt"};
  if (std::getenv("FURUTA_UPDATE_GOLDEN") != nullptr) {
    fs::create_directories(kGoldenDir);
    for (const char* file : files) {
      fs::copy_file(identification / file, kGoldenDir / file, fs::copy_options::overwrite_existing);
    }
    GTEST_SKIP() << "golden files written to " << kGoldenDir;
  }
  for (const char* file : files) ASSERT_TRUE(fs::exists(kGoldenDir / file)) << file;

  expect_same(json::parse(read_text(kGoldenDir / "results.json")),
              json::parse(read_text(identification / "results.json")), "results");
  EXPECT_EQ(without_times(read_text(kGoldenDir / "table.txt")),
            without_times(read_text(identification / "table.txt")));
  EXPECT_EQ(without_times(read_text(kGoldenDir / "table3.txt")),
            without_times(read_text(identification / "table3.txt")));
}

}  // namespace
}  // namespace furuta::app
