// The README's exit-status table ("Exit status", and app/README.md's per command), enforced: each
// command in each outcome the tables list, called in-process, with the status asserted. The
// outcomes that need a daemon's verdict (start 0 and 1, stop and estop 0 and 2 after --wait) run
// against a daemon in virtual time in RemoteCommand.* (session_commands_test.cpp); replay's in
// LogCommands.Replay*.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>

#include "commands.hpp"
#include "devices_report.hpp"
#include "furuta/firmware_bridge/usb_backends.hpp"
#include "simulated_logs.hpp"
#include "temp_dir.hpp"

namespace furuta::app::exit_status_test {
namespace {

namespace fs = std::filesystem;
using furuta::testing::TempDir;

constexpr const char* kRigConfig = FURUTA_SOURCE_DIR "/config/rig.toml";

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_file(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// The status and what was said, of one in-process call.
struct Said {
  int code = -1;
  std::string text;  // out and err together
};

template <typename Command>
Said call(Command command) {
  std::ostringstream out, err;
  Said said;
  said.code = command(out, err);
  said.text = out.str() + err.str();
  return said;
}

class ExitStatus : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    made_ = std::make_unique<TempDir>("furuta-exit-status");
    fs::create_directories(made_->path() / "made");
    fs::create_directories(made_->path() / "other");
    log_ = furuta::testing::simulated_session_log(made_->path() / "made", "fit", 1);
    other_label_ = furuta::testing::simulated_session_log(made_->path() / "other", "run1", 2, 3.0);
  }
  static void TearDownTestSuite() { made_.reset(); }

  // A copy with seeded random bytes over the middle: damaged, its two halves intact.
  fs::path damaged_copy() const {
    std::string bytes = read_file(log_);
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> byte(0, 255);
    for (std::size_t k = bytes.size() / 2; k < bytes.size() / 2 + 2000; ++k) {
      bytes[k] = static_cast<char>(byte(rng));
    }
    const fs::path copy = dir_.path() / "damaged.lcmlog";
    write_file(copy, bytes);
    return copy;
  }
  fs::path empty_file() const {
    const fs::path empty = dir_.path() / "empty.lcmlog";
    write_file(empty, "");
    return empty;
  }

  static std::unique_ptr<TempDir> made_;
  static fs::path log_, other_label_;
  TempDir dir_{"furuta-exit-status-case"};
};

std::unique_ptr<TempDir> ExitStatus::made_;
fs::path ExitStatus::log_;
fs::path ExitStatus::other_label_;

bridge::DeviceInfo a_board() {
  bridge::DeviceInfo info;
  info.vendor_id = bridge::kPhidgetsVendorId;
  info.product_id = bridge::kProductMotorControl1065;
  info.product_name = std::string(bridge::phidget_product_name(info.product_id));
  info.serial = "312345";
  info.firmware_version = 105;
  info.path = "bus 1 port 3";
  return info;
}

// devices: 0 every board listed; 1 some listed, some denied; 2 none answered.
TEST_F(ExitStatus, Devices) {
  const auto discovered = [](const bridge::DiscoveryResult& found) {
    return call(
        [&](std::ostream& out, std::ostream& err) { return report_discovery(found, out, err); });
  };
  bridge::DiscoveryResult listed;
  listed.devices = {a_board()};
  EXPECT_EQ(discovered(listed).code, kExitDone);
  bridge::DiscoveryResult part = listed;
  part.access_denied = {"1047 Encoder HighSpeed 4-input at bus 1 port 4"};
  EXPECT_EQ(discovered(part).code, kExitPartOrRefused);
  EXPECT_EQ(discovered(bridge::DiscoveryResult{}).code, kExitNotDone);  // none plugged in
  bridge::DiscoveryResult denied;
  denied.access_denied = part.access_denied;
  EXPECT_EQ(discovered(denied).code, kExitNotDone);
  bridge::DiscoveryResult unreadable;
  unreadable.error = "libusb_init failed";
  EXPECT_EQ(discovered(unreadable).code, kExitNotDone);
  DevicesOptions simulated;
  simulated.simulated = true;
  EXPECT_EQ(call([&](std::ostream& out, std::ostream& err) {
              return run_devices_command(simulated, out, err);
            }).code,
            kExitDone);
}

RunOptions run_options(const fs::path& logs) {
  RunOptions o;
  o.config_path = kRigConfig;
  o.simulated = true;
  o.virtual_time = true;
  o.logs_dir = logs;
  o.lcm_url = "memq://";
  o.session.duration_s = 0.2;
  o.session.label = "exit";
  return o;
}

// run: 0 ended as asked; 2 a value the configuration never accepts (nothing run, no log).
TEST_F(ExitStatus, Run) {
  const fs::path logs = dir_.path() / "logs";
  const auto ran = [](const RunOptions& o) {
    return call(
        [&](std::ostream& out, std::ostream& err) { return run_session_command(o, out, err); });
  };
  EXPECT_EQ(ran(run_options(logs)).code, kExitDone);
  RunOptions too_much = run_options(dir_.path() / "refused");
  too_much.session.amplitude_duty = 0.9;
  const Said refused = ran(too_much);
  EXPECT_EQ(refused.code, kExitNotDone) << refused.text;
  EXPECT_FALSE(fs::exists(dir_.path() / "refused") && !fs::is_empty(dir_.path() / "refused"));
}

// log info: 0 intact, 1 not intact, 2 not a session log.
TEST_F(ExitStatus, LogInfo) {
  const auto info = [](const fs::path& log) {
    return call(
        [&](std::ostream& out, std::ostream& err) { return run_log_info_command(log, out, err); });
  };
  EXPECT_EQ(info(log_).code, kExitDone);
  EXPECT_EQ(info(damaged_copy()).code, kExitPartOrRefused);
  EXPECT_EQ(info(empty_file()).code, kExitNotDone);
}

// log export-csv: 0; 1 not intact (what was written is said); 2 not a session log.
TEST_F(ExitStatus, LogExportCsv) {
  const auto exported = [&](const fs::path& log) {
    return call([&](std::ostream& out, std::ostream& err) {
      return run_log_export_csv_command(log, dir_.path() / "samples.csv", out, err);
    });
  };
  EXPECT_EQ(exported(log_).code, kExitDone);
  EXPECT_EQ(exported(damaged_copy()).code, kExitPartOrRefused);
  EXPECT_EQ(exported(empty_file()).code, kExitNotDone);
}

// identify: 0; 1 done in part (a log fitted by its intact parts); 2 unusable input.
TEST_F(ExitStatus, Identify) {
  IdentifyCommandOptions options;
  options.no_output_error = true;  // LSMI alone: the statuses, not the fit, are tested here
  const auto identified = [&](const IdentifyCommandOptions& o) {
    return call(
        [&](std::ostream& out, std::ostream& err) { return run_identify_command(o, out, err); });
  };
  options.logs = {log_};
  options.output_dir = dir_.path() / "whole";
  const Said whole = identified(options);
  EXPECT_EQ(whole.code, kExitDone) << whole.text;
  options.logs = {damaged_copy()};
  options.use_intact_part = true;
  options.output_dir = dir_.path() / "part";
  const Said part = identified(options);
  EXPECT_EQ(part.code, kExitPartOrRefused) << part.text;
  EXPECT_NE(part.text.find("done in part: "), std::string::npos) << part.text;
  options.use_intact_part = false;
  const Said refused = identified(options);
  EXPECT_EQ(refused.code, kExitNotDone) << refused.text;
  options.logs = {empty_file()};
  EXPECT_EQ(identified(options).code, kExitNotDone);
}

// simulate: 0 whatever the tubes reached; 2 bad arguments.
TEST_F(ExitStatus, Simulate) {
  SimulateCommandOptions options;
  options.truth = true;
  options.scenarios = {1};
  options.seconds = 0.05;
  options.output_dir = dir_.path() / "simulation";
  const auto simulated = [&](const SimulateCommandOptions& o) {
    return call(
        [&](std::ostream& out, std::ostream& err) { return run_simulate_command(o, out, err); });
  };
  const Said done = simulated(options);
  EXPECT_EQ(done.code, kExitDone) << done.text;
  options.pieces = 3;
  EXPECT_EQ(simulated(options).code, kExitNotDone);
}

// process-logs: 0 nothing set aside; 1 a log to failed/ or to done/ unidentified; 2 DIR missing.
TEST_F(ExitStatus, ProcessLogs) {
  ProcessLogsOptions options;
  options.config_path = kRigConfig;
  options.identifications_dir = dir_.path() / "identifications";
  options.logs_dir = dir_.path() / "logs";
  const auto processed = [&]() {
    return call([&](std::ostream& out, std::ostream& err) {
      return run_process_logs_command(options, out, err);
    });
  };
  EXPECT_EQ(processed().code, kExitNotDone);  // no such directory
  fs::create_directories(options.logs_dir);
  EXPECT_EQ(processed().code, kExitDone);  // nothing to do
  fs::copy_file(other_label_, options.logs_dir / other_label_.filename());
  const Said unidentified = processed();
  EXPECT_EQ(unidentified.code, kExitPartOrRefused) << unidentified.text;
  EXPECT_NE(unidentified.text.find("not identified"), std::string::npos) << unidentified.text;
  write_file(options.logs_dir / "2020-01-01T00-00-00Z_garbage.lcmlog", "not a log");
  EXPECT_EQ(processed().code, kExitPartOrRefused);  // to failed/
}

// start, status: 2 nothing answered or a value the configuration never accepts; 77 no key.
TEST_F(ExitStatus, RemoteCommandsWithoutADaemon) {
  RemoteOptions remote;
  remote.config_path = kRigConfig;
  remote.lcm_url = "memq://";
  remote.reply_timeout_s = 0.2;
  remote.wait_s = 0.2;
  remote.command_key = dir_.path() / "no-such.key";
  remote.daemon_public_key = dir_.path() / "no-such.pub";
  const auto sent = [&](RemoteKind kind, const StartOptions& start) {
    return call([&](std::ostream& out, std::ostream& err) {
      return run_remote_command(kind, remote, start, out, err);
    });
  };
  EXPECT_EQ(sent(RemoteKind::status, {}).code, kExitNotDone);  // no daemon answered
  StartOptions start;
  EXPECT_EQ(sent(RemoteKind::start, start).code, kExitNotPermitted);  // the key unreadable
  start.amplitude_duty = 0.9;
  const Said bad = sent(RemoteKind::start, start);
  EXPECT_EQ(bad.code, kExitNotDone) << bad.text;
  EXPECT_NE(bad.text.find("[limits] max_amplitude_duty"), std::string::npos) << bad.text;
}

}  // namespace
}  // namespace furuta::app::exit_status_test
