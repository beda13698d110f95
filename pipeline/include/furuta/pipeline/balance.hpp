#pragma once
// What a balance session did, from its log (RIG_CONTROL beside RIG_SAMPLE): when the pendulum was
// caught, how well it was held, how far the arm went and what duty it took. Numbers only; the
// report and `furuta log info` say them.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "furuta/session_log/session_log.hpp"

namespace furuta::pipeline {

// The controller file a balance session ran, as its log's controller record names it.
struct BalanceController {
  std::string path;    // as the daemon read it
  std::string sha256;  // hex, of the file's bytes
  // From the record's TOML when config::parse_controller_file reads it: which estimate
  // ([parameters] source: output-error, lsmi, cad) of which results.json, for which rig.
  std::string parameters_source, results, rig;
  std::string unreadable;  // why the TOML did not read; "" when it did
};

struct BalanceSummary {
  std::int64_t cycles = 0;  // samples with a controller cycle beside them
  // The start of the catch that held: the first cycle in catch mode after which the controller
  // never swung up again (none: never caught).
  std::optional<double> caught_at_s;
  double balanced_s = 0;  // time in balance mode
  // Over the cycles in balance mode (0 when none).
  double upright_rms_deg = 0;
  double upright_max_deg = 0;
  double duty_rms = 0;
  double max_abs_duty = 0;     // over the whole session, as commanded
  double max_abs_arm_deg = 0;  // over the whole session
  bool fell = false;           // the session ended with pendulum_fell
  std::string end_reason;      // the end record's, in full; "" when the log has none (cut short)
  std::int64_t law_time_p50_ns = 0;
  std::int64_t law_time_max_ns = 0;
  // Each cycle's time from the session start and mode (rig_control_t::MODE_*), for plots.
  std::vector<double> time_s;
  std::vector<std::int8_t> mode;
  std::vector<double> upright_error_deg;
  std::vector<double> arm_deg;
  std::vector<double> duty;
  std::optional<BalanceController> controller;  // none: the log has no controller record
};

// nullopt when the log has no controller cycles (not a balance session).
std::optional<BalanceSummary> summarize_balance(const session_log::SessionLog& log);

}  // namespace furuta::pipeline
