// The `furuta` session and log subcommands, as a user runs them (simulated rig, virtual time).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "furuta/session_log/lcm_log.hpp"
#include "furuta/session_log/session_log.hpp"
#include "temp_dir.hpp"

namespace furuta::app {
namespace {

namespace fs = std::filesystem;
using furuta::testing::TempDir;

fs::path only_log_in(const fs::path& dir) {
  fs::path found;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() == ".lcmlog") found = entry.path();
  }
  return found;
}

// A `furuta run --sim --virtual-time` of `duration_s` with the configuration at `config`.
RunOptions simulated_run(const fs::path& config, const fs::path& logs, double duration_s) {
  RunOptions options;
  options.config_path = config;
  options.simulated = true;
  options.virtual_time = true;
  options.logs_dir = logs;
  options.lcm_url = "memq://";
  options.session.duration_s = duration_s;
  options.session.label = "cli";
  return options;
}

fs::path run_simulated_session(const fs::path& logs, double duration_s) {
  const RunOptions options = simulated_run(FURUTA_SOURCE_DIR "/config/rig.toml", logs, duration_s);
  std::ostringstream out, err;
  EXPECT_EQ(run_session_command(options, out, err), 0) << out.str() << err.str();
  EXPECT_NE(out.str().find("session ended: duration_reached"), std::string::npos) << out.str();
  return only_log_in(logs);
}

TEST(RunCommand, OptionsLeftOutComeFromTheConfigurationFieldByField) {
  // Giving only --amplitude and --seed must not fall back to the configuration for them (nor for
  // the duration to a built-in default).
  TempDir dir;
  RunOptions options;
  options.config_path = FURUTA_SOURCE_DIR "/config/rig.toml";
  options.simulated = true;
  options.virtual_time = true;
  options.logs_dir = dir.path();
  options.lcm_url = "memq://";
  options.session.amplitude_duty = 0.125;
  options.session.seed = 7;
  options.session.duration_s = 1.0;
  std::ostringstream out, err;
  ASSERT_EQ(run_session_command(options, out, err), 0) << out.str() << err.str();
  const session_log::SessionLog log = session_log::load_session_log(only_log_in(dir.path()));
  ASSERT_TRUE(log.start.has_value());
  EXPECT_EQ(log.start->amplitude_duty, 0.125);
  EXPECT_EQ(log.start->seed, 7);
  EXPECT_EQ(log.start->duration_s, 1.0);
  EXPECT_EQ(log.start->profile, "bang_bang");  // the configuration's
}

TEST(RunCommand, ASimulatedSessionLeavesALogThatInfoExportAndReplayRead) {
  TempDir dir;
  const fs::path log = run_simulated_session(dir.path(), 4.0);
  ASSERT_FALSE(log.empty());

  std::ostringstream out, err;
  EXPECT_EQ(run_log_info_command(log, out, err), 0) << out.str();
  EXPECT_NE(out.str().find("samples   250"), std::string::npos) << out.str();  // 4 s / 16 ms
  EXPECT_NE(out.str().find("duration_reached"), std::string::npos);
  // The session ended with the zero, braking command written last.
  EXPECT_NE(out.str().find("motor     last command duty 0, braking 1\n"), std::string::npos)
      << out.str();

  const fs::path csv = dir.path() / "samples.csv";
  EXPECT_EQ(run_log_export_csv_command(log, csv, out, err), 0);
  std::ifstream in(csv);
  int lines = 0;
  for (std::string line; std::getline(in, line);) ++lines;
  EXPECT_EQ(lines, 251);  // header + samples

  std::ostringstream replay_out;
  EXPECT_EQ(run_replay_command(log, {}, replay_out, err), 0) << replay_out.str() << err.str();
  EXPECT_NE(replay_out.str().find("replayed 250 of 250 samples: identical"), std::string::npos)
      << replay_out.str();
}

TEST(RunCommand, InfoOnALogCutShortSaysSoAndFails) {
  TempDir dir;
  const fs::path log = run_simulated_session(dir.path(), 2.0);
  const fs::path cut = dir.path() / "cut.lcmlog";
  fs::copy_file(log, cut);
  // As if power failed mid-session: inside an event two thirds in (a cut at a plain byte count
  // could fall between two events, and there would be no torn tail to report).
  std::vector<std::uint64_t> offsets;
  {
    session_log::LcmLogReader reader(log);
    for (session_log::LogEvent e; reader.next(e);) offsets.push_back(e.file_offset);
  }
  ASSERT_GT(offsets.size(), 3u);
  fs::resize_file(cut, offsets[offsets.size() * 2 / 3] + 10);
  std::ostringstream out, err;
  EXPECT_EQ(run_log_info_command(cut, out, err), 1);
  EXPECT_NE(out.str().find("missing: the session was cut short"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("truncated tail"), std::string::npos) << out.str();
}

TEST(RemoteCommand, WithNoDaemonListeningItSaysSoAndReturns2) {
  RemoteOptions remote;
  remote.lcm_url = "memq://";  // nobody else is in this process's memq
  remote.reply_timeout_s = 0.2;
  std::ostringstream out, err;
  EXPECT_EQ(run_remote_command(RemoteKind::status, remote, {}, out, err), 2);
  EXPECT_NE(err.str().find("no answer from furutad"), std::string::npos) << err.str();
}

TEST(RunCommand, ABadConfigurationNamesFileLineAndField) {
  TempDir dir;
  const fs::path config = dir.path() / "rig.toml";
  std::ofstream(config) << "[safety]\nmax_duty = 2\n";
  RunOptions options;
  options.config_path = config;
  options.simulated = true;
  std::ostringstream out, err;
  try {
    run_session_command(options, out, err);
    FAIL() << "no error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("rig.toml:2: safety.max_duty: must be in (0, 1]"),
              std::string::npos)
        << e.what();
  }
}

// The shipped rig.toml with `from` replaced by `to` (each must occur), written into `dir`.
fs::path edited_config(const fs::path& dir,
                       const std::vector<std::pair<std::string, std::string>>& edits) {
  std::ifstream in(FURUTA_SOURCE_DIR "/config/rig.toml");
  std::stringstream text;
  text << in.rdbuf();
  std::string toml = text.str();
  for (const auto& [from, to] : edits) {
    const auto at = toml.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) toml.replace(at, from.size(), to);
  }
  const fs::path path = dir / "rig.toml";
  std::ofstream(path) << toml;
  return path;
}

// A 1047_2 (vendor class, firmware 2xx, 6 MHz ticks) runs a whole session like the HID board: its
// report timing is read with its own tick, so no report counts as lost, and the log replays.
TEST(RunCommand, ASessionOnAVendorClass1047WithFirmware210) {
  TempDir dir;
  const fs::path config =
      edited_config(dir.path(), {{"firmware_1047 = 101", "firmware_1047 = 210"}});
  std::ostringstream out, err;
  ASSERT_EQ(run_session_command(simulated_run(config, dir.path() / "logs", 2.0), out, err), 0)
      << out.str() << err.str();
  EXPECT_NE(out.str().find("session ended: duration_reached"), std::string::npos) << out.str();
  const fs::path log = only_log_in(dir.path() / "logs");
  const session_log::SessionLog loaded = session_log::load_session_log(log);
  ASSERT_TRUE(loaded.start.has_value());
  ASSERT_EQ(loaded.samples.size(), 125u);  // 2 s / 16 ms
  EXPECT_EQ(loaded.samples.back().encoder_lost_reports, 0);
  EXPECT_EQ(loaded.samples.back().motor_lost_reports, 0);
  EXPECT_NE(loaded.start->encoder_device.find("firmware=210"), std::string::npos)
      << loaded.start->encoder_device;
  std::ostringstream replay_out;
  EXPECT_EQ(run_replay_command(log, {}, replay_out, err), 0) << replay_out.str() << err.str();
  EXPECT_NE(replay_out.str().find("identical"), std::string::npos) << replay_out.str();
}

// A 1047 with firmware 3xx (the 1047_2's later firmware adds a field whose layout is not known) is
// refused before the motor moves, naming the board, its serial, its firmware and the way out.
TEST(RunCommand, AnUntestedFirmwareIsRefusedUnlessTheConfigurationAllowsIt) {
  TempDir dir;
  const fs::path refused =
      edited_config(dir.path(), {{"firmware_1047 = 101", "firmware_1047 = 310"}});
  std::ostringstream out, err;
  try {
    run_session_command(simulated_run(refused, dir.path() / "logs", 1.0), out, err);
    FAIL() << "a board with firmware 310 was opened: " << out.str();
  } catch (const std::exception& e) {
    const std::string message = e.what();
    for (const char* part : {"encoder board", "1047", "serial 300002", "firmware 310", "200-299",
                             "[boards.encoder] allow_untested_firmware = true"}) {
      EXPECT_NE(message.find(part), std::string::npos) << part << " in: " << message;
    }
  }
  EXPECT_FALSE(fs::exists(dir.path() / "logs") && !fs::is_empty(dir.path() / "logs"));

  TempDir allowed_dir;
  const fs::path allowed = edited_config(
      allowed_dir.path(),
      {{"firmware_1047 = 101", "firmware_1047 = 310"},
       {"allow_untested_firmware = false  # known", "allow_untested_firmware = true  # known"}});
  std::ostringstream out2, err2;
  EXPECT_EQ(
      run_session_command(simulated_run(allowed, allowed_dir.path() / "logs", 1.0), out2, err2), 0)
      << out2.str() << err2.str();
  EXPECT_NE(err2.str().find("firmware 310"), std::string::npos) << err2.str();
  EXPECT_NE(err2.str().find("opened anyway"), std::string::npos) << err2.str();
}

}  // namespace
}  // namespace furuta::app
