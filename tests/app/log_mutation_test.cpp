// A sealed session log changed in any way (bits flipped, bytes overwritten or cut, events
// duplicated, swapped or removed, a sample's time or value changed, the log joined to itself) is
// never called intact by `log info` or accepted whole by `identify` without saying what is wrong
// or that nothing proves it whole: the property fuzz/fuzz_log_mutation.cpp fuzzes, here on fixed
// cases and seeded random scripts so that every CI run checks it.
#include "log_mutation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "furuta/pipeline/intake.hpp"
#include "furuta/rig_session_t.hpp"
#include "furuta/session_log/log_integrity.hpp"
#include "furuta/session_log/session_log.hpp"
#include "log_events.hpp"
#include "simulated_logs.hpp"
#include "temp_dir.hpp"

namespace furuta::app::log_mutation_test {
namespace {

namespace fs = std::filesystem;
using furuta::testing::Event;
using furuta::testing::LogMutation;
using furuta::testing::ScriptWriter;
using furuta::testing::TempDir;

// Long enough for identify to accept the unchanged log (the output-error refinement alone, from
// the configuration's CAD values, needs a few dozen samples), so that its half of the check runs.
constexpr double kSessionSeconds = 1.5;

std::vector<std::uint8_t> bytes_of(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class LogMutationCheck : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    made_ = std::make_unique<TempDir>("furuta-log-mutation");
    log_ = furuta::testing::simulated_session_log(made_->path(), "fit", 23, kSessionSeconds);
    original_ = bytes_of(log_);
    events_ = furuta::testing::events_of(log_);
  }
  static void TearDownTestSuite() { made_.reset(); }

  // The script applied to the sealed log and checked; a failure names the script's operations.
  void expect_never_called_intact(const std::vector<std::uint8_t>& script,
                                  const std::string& name) const {
    std::string done;
    const std::vector<std::uint8_t> mutated = furuta::testing::mutate_log(original_, script, &done);
    const auto violation =
        furuta::testing::changed_log_called_intact(original_, mutated, dir_.path());
    EXPECT_FALSE(violation) << name << ": " << *violation << "\nafter:\n" << done;
  }
  // The problems `log info` names in the log the script makes.
  std::string problems_after(const std::vector<std::uint8_t>& script) const {
    const std::vector<std::uint8_t> mutated = furuta::testing::mutate_log(original_, script);
    const fs::path path = dir_.path() / "problems.lcmlog";
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(mutated.data()),
               static_cast<std::streamsize>(mutated.size()));
    return session_log::describe(
        session_log::integrity_problems(session_log::load_session_log(path)));
  }
  // The byte offset where event `index` starts.
  static std::uint32_t offset_of(std::size_t index) {
    const std::vector<Event> before(events_.begin(),
                                    events_.begin() + static_cast<std::ptrdiff_t>(index));
    return static_cast<std::uint32_t>(furuta::testing::encode_log(before).size());
  }
  static std::vector<std::size_t> samples() {
    return furuta::testing::events_on(events_, session_log::kChannelSample);
  }

  static std::unique_ptr<TempDir> made_;
  static fs::path log_;
  static std::vector<std::uint8_t> original_;
  static std::vector<Event> events_;
  TempDir dir_{"furuta-log-mutation-case"};
};

std::unique_ptr<TempDir> LogMutationCheck::made_;
fs::path LogMutationCheck::log_;
std::vector<std::uint8_t> LogMutationCheck::original_;
std::vector<Event> LogMutationCheck::events_;

TEST_F(LogMutationCheck, TheUnchangedLogIsIntactAndAcceptedWhole) {
  ASSERT_FALSE(original_.empty());
  const session_log::SessionLog log = session_log::load_session_log(log_);
  EXPECT_TRUE(log.seal.has_value());
  EXPECT_EQ(session_log::describe(session_log::integrity_problems(log)), "");
  EXPECT_TRUE(session_log::integrity_notes(log).empty());
  pipeline::BatchRequest request;
  request.logs = {log_};
  const pipeline::Intake intake = pipeline::load_batch(request);
  ASSERT_TRUE(intake.batch.has_value()) << ::testing::PrintToString(intake.refusals);
  ASSERT_EQ(intake.batch->fit.size(), 1u);
  // An empty script changes nothing, and the check says nothing of an unchanged log.
  EXPECT_EQ(furuta::testing::mutate_log(original_, {}), original_);
  EXPECT_FALSE(furuta::testing::changed_log_called_intact(original_, original_, dir_.path()));
  // The check is not empty: the sealed log, posing as a change of other bytes, is a violation.
  const auto violation = furuta::testing::changed_log_called_intact({0x00}, original_, dir_.path());
  ASSERT_TRUE(violation);
  EXPECT_NE(violation->find("log info calls"), std::string::npos) << *violation;
}

// Without a key, a log whose seal was removed and whose start record names a version before seals
// is what that version wrote: not a violation, because both commands say nothing proves it whole.
TEST_F(LogMutationCheck, ALogPosingAsOneWrittenBeforeSealsIsNotedNotCalledIntact) {
  std::vector<Event> events = events_;
  ASSERT_EQ(events.back().channel, session_log::kChannelSeal);
  events.pop_back();
  rig_session_t start;
  Event& first = events.front();
  ASSERT_GT(start.decode(first.data.data(), 0, static_cast<int>(first.data.size())), 0);
  start.software_version = "furuta 0.1.0 (git 114f8895c6d5)";
  first.data.assign(static_cast<std::size_t>(start.getEncodedSize()), 0);
  start.encode(first.data.data(), 0, static_cast<int>(first.data.size()));
  const std::vector<std::uint8_t> posing = furuta::testing::encode_log(events);

  const fs::path path = furuta::testing::write_events(dir_.path() / "posing.lcmlog", events);
  const session_log::SessionLog log = session_log::load_session_log(path);
  EXPECT_TRUE(session_log::integrity_problems(log).empty());
  ASSERT_EQ(session_log::integrity_notes(log).size(), 1u);
  pipeline::BatchRequest request;
  request.logs = {path};
  const pipeline::Intake intake = pipeline::load_batch(request);
  ASSERT_TRUE(intake.batch.has_value()) << ::testing::PrintToString(intake.refusals);
  const auto& warnings = intake.batch->fit.at(0).experiment.warnings;
  EXPECT_TRUE(std::any_of(warnings.begin(), warnings.end(), [](const std::string& w) {
    return w.find("no seal") != std::string::npos;
  })) << ::testing::PrintToString(warnings);
  EXPECT_FALSE(furuta::testing::changed_log_called_intact(original_, posing, dir_.path()));
}

TEST_F(LogMutationCheck, NamedChangesAreNeverCalledIntact) {
  const std::vector<std::size_t> at = samples();
  ASSERT_GE(at.size(), 40u);
  struct Case {
    const char* name;
    ScriptWriter script;
    const char* problem;  // words of the problem `log info` names
  };
  const Case cases[] = {
      // An exponent bit of one sample's pendulum angle: well formed, only the seal sees it.
      {"bit flip in a sample's double",
       ScriptWriter().op(LogMutation::change_sample_double).u16(20).u8(1).u8(2 * 61).u64(0),
       "altered"},
      {"the log joined to itself", ScriptWriter().op(LogMutation::join), "joined"},
      {"the first samples cut out",
       ScriptWriter()
           .op(LogMutation::delete_range)
           .u32(offset_of(at[0]))
           .u16(static_cast<std::uint16_t>(offset_of(at[5]) - offset_of(at[0]) - 1)),
       "missing (sequence numbers 0-"},
      {"a sample duplicated",
       ScriptWriter()
           .op(LogMutation::duplicate_event)
           .u8(0)
           .u16(10)
           .u16(static_cast<std::uint16_t>(at[10] + 1)),
       "a sample repeated"},
      {"two samples swapped", ScriptWriter().op(LogMutation::swap_events).u8(0).u16(30).u16(31),
       "out of order"},
      {"a sample one nanosecond later",
       ScriptWriter().op(LogMutation::move_sample_time).u16(7).u32(1), "altered"},
      {"the seal removed",
       ScriptWriter()
           .op(LogMutation::delete_event)
           .u8(1)
           .u16(static_cast<std::uint16_t>(events_.size() - 1)),
       "seal missing"},
      {"one bit of the file",
       ScriptWriter().op(LogMutation::flip_bit).u32(offset_of(at[3]) + 40).u8(0), ""},
  };
  for (const Case& c : cases) {
    const std::string problems = problems_after(c.script.bytes());
    EXPECT_NE(problems, "") << c.name;
    EXPECT_NE(problems.find(c.problem), std::string::npos)
        << c.name << ": no '" << c.problem << "' in: " << problems;
    expect_never_called_intact(c.script.bytes(), c.name);
  }
}

// Seeded random scripts of one to six operations, each its own seed: a failure names the seed
// and what the script did, and the fuzzer's reproducer format is the script's bytes.
TEST_F(LogMutationCheck, SeededRandomScriptsAreNeverCalledIntact) {
  constexpr std::uint32_t kScripts = 300;
  std::size_t changed = 0;
  for (std::uint32_t seed = 1; seed <= kScripts; ++seed) {
    std::mt19937 random(seed);
    const std::size_t operations = 1 + seed % furuta::testing::kMaxOperations;
    const std::vector<std::uint8_t> script = furuta::testing::random_script(random, operations);
    const std::vector<std::uint8_t> mutated = furuta::testing::mutate_log(original_, script);
    if (mutated != original_) ++changed;
    expect_never_called_intact(script, "seed " + std::to_string(seed));
  }
  // Nearly every script changes the log; one that does not checks nothing.
  EXPECT_GE(changed, kScripts * 9 / 10);
}

}  // namespace
}  // namespace furuta::app::log_mutation_test
