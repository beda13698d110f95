#pragma once
// The controller file `furuta controller design` writes (docs/control.md, "The controller file"),
// read into the spec of the balance law the loop runs. The file holds everything the loop needs,
// so nothing is recomputed from a configuration that may have changed since the design; the
// reader checks all of it and accepts only what control::BalanceLaw accepts. Every problem is a
// ConfigError naming file, line and key ("C.toml:23: gain.k: must be an array of 4 to 8
// numbers"): missing tables and keys, wrong types, non-finite numbers, unknown keys, a kind other
// than upright_lqr, a gain whose length is not the one its lag gives, and each value the balance
// law refuses, reported at the key it came from.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "furuta/config/config_error.hpp"
#include "furuta/control/balance_law.hpp"

namespace furuta::config {

// The kind of controller this reader knows, [controller] kind.
inline constexpr std::string_view kUprightLqrKind = "upright_lqr";

struct ControllerFile {
  std::filesystem::path path;  // as named to the loader; empty from parse_controller_file
  std::string text;            // the file verbatim, so a session can carry it
  std::string sha256;          // hex of the file's bytes
  // [controller]: the rig it was designed for ([rig] name of its configuration), the software.
  std::string kind, rig, designed_by;
  // [parameters]: which estimate (output-error, lsmi, cad), of which results.json.
  std::string parameters_source, results, results_sha256;
  std::int64_t period_ns = 0;
  // The data path's lag and the board's duty ramp as a delay on a step of ramp_step_duty: the
  // design sampled the plant with their sum.
  double lag_s = 0, ramp_lag_s = 0, ramp_step_duty = 0;
  double supply_v = 0;
  // [observer] reading_age_s: how old the angles are that the filter's gain was designed for.
  double reading_age_s = 0;
  control::BalanceControllerSpec spec;  // ready for control::BalanceLaw
};

// `file_name` names the text in errors.
ControllerFile parse_controller_file(std::string_view text, const std::string& file_name);
// A SHA-256 as the file's digest and the commands carry it: 64 lowercase hex digits.
bool is_sha256_hex(std::string_view text);
// A file that cannot be opened or read is a ConfigError naming its path.
ControllerFile load_controller_file(const std::filesystem::path& path);

}  // namespace furuta::config
