// Bad command lines to `furuta` and `furutad` (issue 8): each ends with a message naming what is
// wrong and a non-zero exit, never a crash and never a session started on a value out of range.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "log_events.hpp"
#include "temp_dir.hpp"

namespace {

namespace fs = std::filesystem;

struct Outcome {
  int exit_code = -1;  // -1: killed by a signal (a crash)
  std::string output;  // stdout and stderr together
};

Outcome run(const std::string& command_line) {
  Outcome o;
  FILE* pipe = popen((command_line + " 2>&1").c_str(), "r");
  if (!pipe) return o;
  std::array<char, 4096> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe)) o.output += buffer.data();
  const int status = pclose(pipe);
  if (WIFEXITED(status)) o.exit_code = WEXITSTATUS(status);
  return o;
}

bool has(const Outcome& o, const std::string& text) {
  return o.output.find(text) != std::string::npos;
}

std::string run_options(const fs::path& logs) {
  return std::string(FURUTA_CLI) + " run --sim --virtual-time --lcm-url memq:// --config " +
         FURUTA_SOURCE_DIR "/config/rig.toml --logs-dir " + logs.string();
}

// A value the configuration can never accept is bad usage (2), as one that is not a number is:
// before, `--amplitude nan` ran into the daemon's refusal (1) while `--amplitude abc` was 2.
TEST(CliArguments, FurutaRunRefusesOutOfRangeSessionValuesWithTheField) {
  furuta::testing::TempDir logs;
  const std::pair<const char*, const char*> cases[] = {
      {"--amplitude nan", "--amplitude: nan is not a finite number"},
      {"--amplitude inf", "--amplitude: inf is not a finite number"},
      {"--amplitude 0.9", "amplitude_duty: 0.9 above the limit 0.5"},
      {"--amplitude -0.2", "amplitude_duty: -0.2 is not above 0"},
      {"--duration -1", "duration_s: -1 is not above 0"},
      {"--duration 1e308", "duration_s: 1e+308 above the limit 600"},
      {"--profile sawtooth", "profile: \"sawtooth\" is not one of"},
      {"--seed -1", "seed: -1 is negative"},
      {"--label ../../etc", "label: \"../../etc\" has 0x2f"},
  };
  for (const auto& [args, reason] : cases) {
    const Outcome o = run(run_options(logs.path()) + " " + args);
    EXPECT_EQ(o.exit_code, 2) << args << "\n" << o.output;
    EXPECT_TRUE(has(o, reason)) << args << "\n" << o.output;
    // Not a number: the option is named; else the configuration, with the keys of its limits.
    const std::string given = args;
    const bool number =
        given.find("nan") == std::string::npos && given.find("inf") == std::string::npos;
    EXPECT_TRUE(number ? has(o, "furuta run: ") && has(o, "[limits] max_amplitude_duty") &&
                             has(o, "config/rig.toml")
                       : has(o, "--amplitude"))
        << args << "\n"
        << o.output;
  }
  // Nothing ran: no log was written.
  EXPECT_TRUE(fs::is_empty(logs.path()));
}

TEST(CliArguments, FurutaRejectsMalformedArgumentsBeforeDoingAnything) {
  furuta::testing::TempDir logs;
  const std::pair<std::string, const char*> cases[] = {
      {run_options(logs.path()) + " --amplitude abc", "--amplitude"},
      {run_options(logs.path()) + " --seed 1.5", "--seed"},
      {run_options(logs.path()) + " --duration", "--duration"},
      {std::string(FURUTA_CLI) + " run --config /nonexistent/rig.toml", "/nonexistent/rig.toml"},
      {std::string(FURUTA_CLI) + " status --timeout 0", "--timeout"},
      // CLI11 checks for the missing subcommand first, so these do not name the stray word.
      {std::string(FURUTA_CLI) + " --no-such-option", "A subcommand is required"},
      {std::string(FURUTA_CLI) + " no-such-command", "A subcommand is required"},
      {std::string(FURUTA_CLI) + " status --no-such-option", "--no-such-option"},
      {std::string(FURUTA_CLI) + " identify --input-lag-ms -2 " FURUTA_SOURCE_DIR "/README.md",
       "--input-lag-ms"},
      // NaN passes every comparison, and -1 reads as an unsigned type's largest value: each
      // number is checked finite and in range where it enters.
      {std::string(FURUTA_CLI) + " identify --input-lag-ms nan " FURUTA_SOURCE_DIR "/README.md",
       "--input-lag-ms: nan is not a finite number"},
      {std::string(FURUTA_CLI) + " identify --cutoff inf " FURUTA_SOURCE_DIR "/README.md",
       "--cutoff: inf is not a finite number"},
      {std::string(FURUTA_CLI) + " identify --scenario-seconds nan " FURUTA_SOURCE_DIR "/README.md",
       "--scenario-seconds: nan is not a finite number"},
      {std::string(FURUTA_CLI) + " status --timeout nan", "--timeout: nan is not a finite number"},
      {std::string(FURUTA_CLI) + " simulate --pieces -1", "--pieces: -1 is not in [1, 64]"},
      {std::string(FURUTA_CLI) + " simulate --scenario-seconds nan",
       "--scenario-seconds: nan is not a finite number"},
      {std::string(FURUTA_CLI) + " controller verify " FURUTA_SOURCE_DIR
                                 "/README.md --parameters " FURUTA_SOURCE_DIR
                                 "/README.md --lag-ms 1",
       "--lag-ms"},
      {std::string(FURUTA_CLI) + " controller verify " FURUTA_SOURCE_DIR
                                 "/README.md --parameters " FURUTA_SOURCE_DIR "/README.md --sd nan",
       "--sd: nan is not a finite number"},
      {std::string(FURUTA_CLI) + " controller verify " FURUTA_SOURCE_DIR
                                 "/README.md --parameters " FURUTA_SOURCE_DIR
                                 "/README.md --max-pieces 0",
       "--max-pieces"},
      {std::string(FURUTA_CLI) + " controller verify " FURUTA_SOURCE_DIR
                                 "/README.md --parameters " FURUTA_SOURCE_DIR
                                 "/README.md --handover nan",
       "--handover: nan is not a finite number"},
  };
  for (const auto& [line, mention] : cases) {
    const Outcome o = run(line);
    EXPECT_EQ(o.exit_code, 2) << line << "\n" << o.output;  // usage: 2, as every command's
    EXPECT_TRUE(has(o, mention)) << line << "\n" << o.output;
  }
  EXPECT_TRUE(fs::is_empty(logs.path()));
}

TEST(CliArguments, FurutadRejectsBadArgumentsAndBadConfigurations) {
  furuta::testing::TempDir dir;
  const fs::path bad = dir.path() / "rig.toml";
  std::ofstream(bad) << "[safety]\n# the limit\nmax_duty = nan\n";
  const std::string daemon = FURUTA_DAEMON;
  const std::pair<std::string, const char*> cases[] = {
      {daemon + " --sim --config " + bad.string(), "rig.toml:3: safety.max_duty: must be finite"},
      {daemon + " --sim --config /nonexistent/rig.toml", "/nonexistent/rig.toml"},
      {daemon + " --no-such-option", "--no-such-option"},
      {daemon + " --sim --replay /nonexistent.lcmlog", "/nonexistent.lcmlog"},
  };
  for (const auto& [line, mention] : cases) {
    const Outcome o = run(line);
    EXPECT_EQ(o.exit_code, 2) << line << "\n" << o.output;
    EXPECT_TRUE(has(o, mention)) << line << "\n" << o.output;
  }
}

// The commit the sources are at, as `git rev-parse` gives it; empty outside a git checkout.
std::string source_commit() {
  const Outcome o = run("git -C " FURUTA_SOURCE_DIR " rev-parse --short=12 HEAD");
  if (o.exit_code != 0 || o.output.size() < 12) return "";
  return o.output.substr(0, 12);
}

TEST(CliArguments, VersionNamesTheVersionAndTheGitCommitOfBothPrograms) {
  const std::string commit = source_commit();
  for (const std::string program : {FURUTA_CLI, FURUTA_DAEMON}) {
    const Outcome o = run(program + " --version");
    EXPECT_EQ(o.exit_code, 0) << program << "\n" << o.output;
    EXPECT_TRUE(has(o, "furuta 0.2.0 (git ")) << program << "\n" << o.output;
    EXPECT_TRUE(has(o, commit.empty() ? "unknown" : commit)) << program << "\n" << o.output;
  }
}

TEST(CliArguments, TheSameThingHasTheSameOptionNameInEveryCommand) {
  const std::string cli = FURUTA_CLI;
  for (const char* command : {"start", "stop", "estop", "status", "run", "replay", "identify",
                              "process-logs", "devices"}) {
    const Outcome o = run(cli + " " + command + " --help");
    EXPECT_EQ(o.exit_code, 0) << command;
    EXPECT_TRUE(has(o, "-c,--config")) << command << "\n" << o.output;
  }
  for (const char* command : {"identify", "simulate", "process-logs", "log export-csv", "report"}) {
    const Outcome o = run(cli + " " + command + " --help");
    EXPECT_TRUE(has(o, "-o,--output")) << command << "\n" << o.output;
  }
  for (const char* command : {"run", "devices"}) {
    EXPECT_TRUE(has(run(cli + " " + command + " --help"), "--sim ")) << command;
  }
  EXPECT_TRUE(has(run(std::string(FURUTA_DAEMON) + " --help"), "--sim "));
}

TEST(CliArguments, HelpDescribesPositionalsShowsDefaultsAndTheExitRule) {
  const std::string cli = FURUTA_CLI;
  const std::pair<const char*, const char*> positionals[] = {
      {"log info", "LOG TEXT:FILE REQUIRED      A session log"},
      {"log export-csv", "LOG TEXT:FILE REQUIRED      A session log"},
      {"replay", "LOG TEXT:FILE REQUIRED      A session log"},
      {"identify", "Session logs (.lcmlog) to fit"},
      {"identify", "--no-output-error           Skip the output-error refinement"},
      {"process-logs", "DIR TEXT                    Logs directory"},
  };
  for (const auto& [command, text] : positionals) {
    const Outcome o = run(cli + " " + command + " --help");
    EXPECT_TRUE(has(o, text)) << command << "\n" << o.output;
  }
  const std::pair<const char*, const char*> defaults[] = {
      {"status", "--timeout FLOAT:NUMBER in [0.1, 60]=2"},
      {"identify", "-o,--output TEXT=identification"},
      {"simulate", "-o,--output TEXT=simulation"},
      {"simulate", "--pieces UINT:INTEGER in [1, 64]=1"},
  };
  for (const auto& [command, text] : defaults) {
    const Outcome o = run(cli + " " + command + " --help");
    EXPECT_TRUE(has(o, text)) << command << "\n" << o.output;
    EXPECT_TRUE(has(o, "Exit status: 0 done; 1 done in part or refused")) << command;
  }
  EXPECT_TRUE(has(run(std::string(FURUTA_DAEMON) + " --help"), "Exit status: 0 stopped as asked"));
}

// Before: furutad's --help had no default for --config, identify said --simulate-seconds where
// simulate said --seconds, and --amplitude said (0, 1] while the configuration's limit is 0.5.
TEST(CliArguments, HelpNamesTheProgramItsDefaultsAndOneNameForOneThing) {
  const Outcome daemon = run(std::string(FURUTA_DAEMON) + " --help");
  EXPECT_EQ(daemon.exit_code, 0);
  EXPECT_TRUE(has(daemon, "furutad")) << daemon.output;
  EXPECT_FALSE(has(daemon, "furuta:")) << daemon.output;
  EXPECT_TRUE(has(daemon, "-c,--config TEXT:FILE=")) << daemon.output;
  EXPECT_TRUE(has(daemon, "rig.toml")) << daemon.output;
  // It starts with an unusable logs directory (and refuses starts): the help says so.
  EXPECT_TRUE(has(daemon, "An unusable logs directory does not stop it")) << daemon.output;
  EXPECT_FALSE(has(daemon, "or the logs directory unusable")) << daemon.output;
  const std::string cli = FURUTA_CLI;
  for (const char* command : {"identify", "simulate"}) {
    const Outcome o = run(cli + " " + command + " --help");
    EXPECT_TRUE(has(o, "--scenario-seconds")) << command << "\n" << o.output;
    EXPECT_FALSE(has(o, "--simulate-seconds")) << command << "\n" << o.output;
    EXPECT_FALSE(has(o, "--seconds ")) << command << "\n" << o.output;
  }
  // The old names still work, hidden.
  EXPECT_TRUE(has(run(cli + " simulate --seconds nan"), "--seconds nan is not a finite number"));
  EXPECT_TRUE(has(run(cli + " identify --simulate-seconds nan " FURUTA_SOURCE_DIR "/README.md"),
                  "--simulate-seconds nan is not a finite number"));
  for (const char* command : {"run", "start"}) {
    const Outcome o = run(cli + " " + command + " --help");
    EXPECT_TRUE(has(o, "[limits] max_amplitude_duty")) << command << "\n" << o.output;
    EXPECT_FALSE(has(o, "(0, 1]")) << command << "\n" << o.output;
  }
}

}  // namespace

namespace {

// furutad with a logs directory it cannot write (under a regular file: that stops root too) says
// so as it starts, naming the directory and the error, rather than at the first start. (It stays
// up, daemon/README.md says why; a replay exits by itself once the replayed session ends.)
TEST(CliArguments, FurutadSaysAtStartUpThatItCannotLog) {
  furuta::testing::TempDir dir;
  const Outcome made = run(run_options(dir.path() / "logs") + " --duration 0.2 --label short");
  ASSERT_EQ(made.exit_code, 0) << made.output;
  fs::path log;
  for (const auto& entry : fs::directory_iterator(dir.path() / "logs")) {
    if (entry.path().extension() == ".lcmlog") log = entry.path();
  }
  ASSERT_FALSE(log.empty()) << made.output;
  std::ofstream(dir.path() / "file") << "not a directory";
  const fs::path logs = dir.path() / "file" / "logs";
  // timeout: a hang guard, in case the replay did not end.
  const Outcome o = run("timeout 60 " + std::string(FURUTA_DAEMON) +
                        " --lcm-url memq:// --config " FURUTA_SOURCE_DIR "/config/rig.toml" +
                        " --logs-dir " + logs.string() + " --replay " + log.string());
  EXPECT_NE(o.exit_code, 124) << o.output;
  EXPECT_TRUE(has(o, "furutad: WARNING: cannot log sessions in " + logs.string())) << o.output;
  EXPECT_TRUE(has(o, "Not a directory")) << o.output;
  EXPECT_TRUE(has(o, "every start is refused until it can")) << o.output;
}

// furutad --replay takes only a whole session unless told otherwise, and the log it writes from
// one that is not says where it came from, so that it never passes for a whole session.
TEST(CliArguments, FurutadReplaysALogThatIsNotIntactOnlyWhenAskedAndSaysSo) {
  furuta::testing::TempDir dir;
  const Outcome made = run(run_options(dir.path() / "logs") + " --duration 0.5 --label short");
  ASSERT_EQ(made.exit_code, 0) << made.output;
  fs::path log;
  for (const auto& entry : fs::directory_iterator(dir.path() / "logs")) {
    if (entry.path().extension() == ".lcmlog") log = entry.path();
  }
  ASSERT_FALSE(log.empty()) << made.output;
  std::vector<furuta::testing::Event> events = furuta::testing::events_of(log);
  const std::vector<furuta::testing::Event> once = events;
  events.insert(events.end(), once.begin(), once.end());
  const fs::path joined = furuta::testing::write_events(dir.path() / "joined.lcmlog", events);
  // The start and end records alone (the end record is the one before the seal).
  const fs::path no_samples = furuta::testing::write_events(dir.path() / "no_samples.lcmlog",
                                                            {once.front(), once[once.size() - 2]});

  const std::string furutad = "timeout 60 " + std::string(FURUTA_DAEMON) +
                              " --lcm-url memq:// --config " FURUTA_SOURCE_DIR "/config/rig.toml" +
                              " --logs-dir " + (dir.path() / "replays").string() + " --replay ";
  for (const fs::path& bad : {joined, no_samples}) {
    const Outcome refused = run(furutad + bad.string());
    EXPECT_EQ(refused.exit_code, 2) << refused.output;
    EXPECT_TRUE(has(refused, "is not intact")) << refused.output;
    EXPECT_TRUE(has(refused, "--replay-not-intact")) << refused.output;
  }
  EXPECT_FALSE(fs::exists(dir.path() / "replays") &&
               std::any_of(fs::directory_iterator(dir.path() / "replays"), fs::directory_iterator(),
                           [](const auto& e) { return e.path().extension() == ".lcmlog"; }));

  const Outcome asked = run(furutad + joined.string() + " --replay-not-intact");
  ASSERT_EQ(asked.exit_code, 0) << asked.output;
  fs::path replayed;
  for (const auto& entry : fs::directory_iterator(dir.path() / "replays")) {
    if (entry.path().extension() == ".lcmlog") replayed = entry.path();
  }
  ASSERT_FALSE(replayed.empty()) << asked.output;
  const Outcome info = run(std::string(FURUTA_CLI) + " log info " + replayed.string());
  EXPECT_EQ(info.exit_code, 1) << info.output;
  EXPECT_TRUE(has(info, "a replay of " + joined.string())) << info.output;
  EXPECT_TRUE(has(info, "replayed from a log that was not intact")) << info.output;
  EXPECT_TRUE(has(info, "joined")) << info.output;
}

}  // namespace

namespace {

std::string create_keys(const fs::path& dir) {
  return "timeout 60 " + std::string(FURUTA_DAEMON) +
         " --config " FURUTA_SOURCE_DIR "/config/rig.toml --command-key " +
         (dir / "command.key").string() + " --daemon-key " + (dir / "daemon.key").string() +
         " --create-command-key";
}

// `furutad --create-command-key` (what the package and the unit run as root): makes the command
// key, the daemon key and its public half where none is; refuses, with exit 2, a key directory
// others may write into and a key it did not write that fails a check, and leaves both as they are.
TEST(CliArguments, FurutadCreatesTheKeysOnlyWhereNobodyElseCouldHavePlantedOne) {
  furuta::testing::TempDir dir;
  const Outcome made = run(create_keys(dir.path()));
  ASSERT_EQ(made.exit_code, 0) << made.output;
  EXPECT_EQ(fs::status(dir.path() / "command.key").permissions(),
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  EXPECT_EQ(fs::status(dir.path() / "daemon.key").permissions(),
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  EXPECT_EQ(fs::status(dir.path() / "daemon.pub").permissions(),
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read |
                fs::perms::others_read);
  const auto text = [](const fs::path& path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string key = text(dir.path() / "command.key");
  ASSERT_EQ(run(create_keys(dir.path())).exit_code, 0);  // kept
  EXPECT_EQ(text(dir.path() / "command.key"), key);

  // A key someone made readable: refused, not replaced.
  fs::permissions(dir.path() / "command.key", fs::perms::others_read, fs::perm_options::add);
  const Outcome readable = run(create_keys(dir.path()));
  EXPECT_EQ(readable.exit_code, 2) << readable.output;
  EXPECT_TRUE(has(readable, "every user can read it")) << readable.output;
  EXPECT_EQ(text(dir.path() / "command.key"), key);

  // A directory every user may write into: nothing made, nothing kept.
  furuta::testing::TempDir open_dir;
  fs::permissions(open_dir.path(), fs::perms::all);
  const Outcome open = run(create_keys(open_dir.path()));
  EXPECT_EQ(open.exit_code, 2) << open.output;
  EXPECT_TRUE(has(open, open_dir.path().string())) << open.output;
  EXPECT_FALSE(fs::exists(open_dir.path() / "command.key"));
  EXPECT_FALSE(fs::exists(open_dir.path() / "daemon.key"));
  // A key planted there beforehand is not kept either.
  std::ofstream(open_dir.path() / "command.key") << std::string(64, 'a') << "\n";
  fs::permissions(open_dir.path() / "command.key",
                  fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  EXPECT_EQ(run(create_keys(open_dir.path())).exit_code, 2);
}

}  // namespace
