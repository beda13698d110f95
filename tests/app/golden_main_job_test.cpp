// The main job (scripts/run.sh) end to end against a golden copy of its outputs: two bang-bang
// sessions and a validation session of the simulated rig, then the trigger's pass, must give the
// same results.json (every number, also within text, within kRelativeTolerance) and the same Table
// I and Table III text as the golden files in tests/data/golden/. A refactoring that moves code
// keeps these figures; a change meant to alter them regenerates the files with
// FURUTA_UPDATE_GOLDEN=1 and says why in its commit.

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
#include <vector>

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

// Not 1e-12: glibc picks its exp/sin/cos by the processor (FMA or not), and the last bit they
// differ in is amplified by the chaotic free runs, the validated tubes near their blow-up and the
// output-error solver's stopping point (measured: up to 3e-9 relative between processors, and
// between GLIBC_TUNABLES=glibc.cpu.hwcaps=-FMA,-AVX2 and the default on one). A refactoring that
// changes what is computed moves the figures by far more.
constexpr double kRelativeTolerance = 1e-6;

bool same_number(double g, double a) {
  return g == a || std::fabs(g - a) <= kRelativeTolerance * std::max(std::fabs(g), std::fabs(a));
}

// Text with its numbers compared as numbers: the words and their order exactly, each number
// within the tolerance.
void expect_same_text(const std::string& golden, const std::string& actual,
                      const std::string& where) {
  static const std::regex number(R"([-+]?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)?)");
  const auto numbers = [](const std::string& text) {
    std::vector<double> out;
    for (auto it = std::sregex_iterator(text.begin(), text.end(), number);
         it != std::sregex_iterator(); ++it) {
      out.push_back(std::stod(it->str()));
    }
    return out;
  };
  const std::string g = without_times(golden), a = without_times(actual);
  EXPECT_EQ(std::regex_replace(g, number, "#"), std::regex_replace(a, number, "#")) << where;
  const std::vector<double> gn = numbers(g), an = numbers(a);
  if (gn.size() != an.size()) return;  // the words differ already
  for (std::size_t i = 0; i < gn.size(); ++i) {
    EXPECT_TRUE(same_number(gn[i], an[i])) << where << ": number " << i << ": golden " << gn[i]
                                           << ", now " << an[i] << " in \"" << a << "\"";
  }
}

void expect_same(const json& golden, const json& actual, const std::string& where) {
  if (golden.is_number() && actual.is_number()) {
    const double g = golden.get<double>();
    const double a = actual.get<double>();
    EXPECT_TRUE(same_number(g, a))
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
    expect_same_text(golden.get<std::string>(), actual.get<std::string>(), where);
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
