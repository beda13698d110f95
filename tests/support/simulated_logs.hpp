#pragma once
// Session logs as `furuta run --sim --virtual-time` makes them, for the tests that need real logs
// (identify, the trigger, the report). Needs the app library (commands.hpp).

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <sstream>
#include <string>

#include "commands.hpp"

namespace furuta::testing {

// One session of the simulated rig with the project's rig.toml (its bang-bang unless the
// configuration or `profile` says otherwise), in virtual time, logged into `logs`; the log's path,
// or an empty path (with a test failure) when the command failed.
inline std::filesystem::path simulated_session_log(const std::filesystem::path& logs,
                                                   const std::string& label, std::int64_t seed,
                                                   std::optional<double> duration_s = {},
                                                   std::optional<std::string> profile = {},
                                                   std::optional<double> amplitude_duty = {}) {
  app::RunOptions options;
  options.config_path = FURUTA_SOURCE_DIR "/config/rig.toml";
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

}  // namespace furuta::testing
