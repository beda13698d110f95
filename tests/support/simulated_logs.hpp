#pragma once
// Session logs as `furuta run --sim --virtual-time` makes them, for the tests that need real logs
// (identify, the trigger, the report). Needs the app library (commands.hpp).

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include "commands.hpp"

namespace furuta::testing {

// One session of the simulated rig with the project's rig.toml or `config` (its bang-bang unless
// the configuration or `profile` says otherwise), in virtual time, logged into `logs`; the log's
// path, or an empty path (with a test failure) when the command failed.
inline std::filesystem::path simulated_session_log(const std::filesystem::path& logs,
                                                   const std::string& label, std::int64_t seed,
                                                   std::optional<double> duration_s = {},
                                                   std::optional<std::string> profile = {},
                                                   std::optional<double> amplitude_duty = {},
                                                   const std::filesystem::path& config = {}) {
  app::RunOptions options;
  options.config_path = config.empty() ? FURUTA_SOURCE_DIR "/config/rig.toml" : config;
  options.simulated = true;
  options.virtual_time = true;
  options.logs_dir = logs;
  options.lcm_url = "memq://";
  options.session.label = label;
  options.session.seed = seed;
  options.session.duration_s = duration_s;
  options.session.profile = profile;
  options.session.amplitude_duty = amplitude_duty;
  std::ostringstream out, err;
  EXPECT_EQ(app::run_session_command(options, out, err), 0) << out.str() << err.str();
  const std::string text = out.str();
  const auto at = text.find("; log ");
  if (at == std::string::npos) return {};
  return std::filesystem::path(text.substr(at + 6, text.find('\n', at) - at - 6));
}

// The project's rig.toml with [output_error] disabled, written into `dir`: sessions that carry it
// are identified without the refinement, for tests of what runs around it (the trigger); the
// path, or an empty path (with a test failure) when the file no longer has that line.
inline std::filesystem::path rig_config_without_output_error(const std::filesystem::path& dir) {
  std::ifstream in(FURUTA_SOURCE_DIR "/config/rig.toml");
  std::stringstream text;
  text << in.rdbuf();
  std::string toml = text.str();
  const std::string enabled = "enabled = true";
  const auto section = toml.find("\n[output_error]");
  const auto next = section == std::string::npos ? section : toml.find("\n[", section + 1);
  auto at = section == std::string::npos ? section : toml.find("\n" + enabled, section);
  if (at > next) at = std::string::npos;  // another section's
  EXPECT_NE(at, std::string::npos) << "config/rig.toml: no `" << enabled << "` in [output_error]";
  if (at == std::string::npos) return {};
  toml.replace(at + 1, enabled.size(), "enabled = false");
  const std::filesystem::path path = dir / "rig-without-output-error.toml";
  std::ofstream(path) << toml;
  return path;
}

}  // namespace furuta::testing
