// What identification is worth to the balance controller: controllers designed from the main
// job's output-error estimate, its LSMI estimate and the CAD values, each run as
// `furuta run --sim --virtual-time --balance` from rest hanging down over several simulated-rig
// seeds; per controller and seed, whether it caught (and when), whether it held, the RMS angle
// from upright while balancing, the duty it used, how far the arm went, and the law's own time.
//
//   balance_outcomes [--results tests/data/golden/results.json] [--seeds 10] [--duration 70]
//                    [--jitter-ns 0] [--angle-noise-rad 0] [--tap-mnm-s X --tap-at-s T]
//                    [--period-ms 16]
//
// Figures, never pass/fail: docs/control.md keeps the table with this command.
#include <toml++/toml.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "commands.hpp"
#include "furuta/pipeline/balance.hpp"
#include "furuta/session_log/session_log.hpp"

namespace {

using namespace furuta;
namespace fs = std::filesystem;

struct RigChanges {
  std::int64_t jitter_ns = 0;
  double angle_noise_rad = 0;
  double tap_mnm_s = 0;
  double tap_at_s = 40;
  std::int64_t period_ms = 0;  // 0: the shipped [daemon] period_ms
};

// The shipped configuration with the loop's period, the simulated rig's seed, USB jitter, encoder
// noise and taps.
fs::path configuration(const fs::path& dir, std::int64_t seed, const RigChanges& c) {
  toml::table rig = toml::parse_file(FURUTA_SOURCE_DIR "/config/rig.toml");
  if (c.period_ms > 0) rig["daemon"].as_table()->insert_or_assign("period_ms", c.period_ms);
  toml::table& sim = *rig["simulation"].as_table();
  sim.insert_or_assign("seed", seed);
  sim.insert_or_assign("usb_latency_jitter_ns", c.jitter_ns);
  sim.insert_or_assign("arm_angle_noise_rad", c.angle_noise_rad);
  sim.insert_or_assign("pendulum_angle_noise_rad", c.angle_noise_rad);
  if (c.tap_mnm_s != 0) {
    sim.insert_or_assign("tap_times_s", toml::array{c.tap_at_s});
    sim.insert_or_assign("tap_impulse_mnm_s", c.tap_mnm_s);
  }
  const fs::path path = dir / ("rig-" + std::to_string(seed) + ".toml");
  std::ofstream(path) << rig << "\n";
  return path;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Balance controllers from identified and CAD parameters on the simulated rig"};
  fs::path results = FURUTA_SOURCE_DIR "/tests/data/golden/results.json";
  int seeds = 10;
  double duration_s = 70;
  RigChanges changes;
  app.add_option("--results", results, "results.json the controllers are designed from");
  app.add_option("--seeds", seeds, "Simulated-rig seeds per controller (1..N)");
  app.add_option("--duration", duration_s, "Seconds per session");
  app.add_option("--jitter-ns", changes.jitter_ns, "[simulation] usb_latency_jitter_ns");
  app.add_option("--angle-noise-rad", changes.angle_noise_rad,
                 "[simulation] arm_ and pendulum_angle_noise_rad (the seed draws it)");
  app.add_option("--tap-mnm-s", changes.tap_mnm_s, "A tap on the pendulum, mN m s (0: none)");
  app.add_option("--tap-at-s", changes.tap_at_s, "When the tap comes, s after the rig starts");
  app.add_option("--period-ms", changes.period_ms,
                 "[daemon] period_ms, for the design and the sessions (default: the shipped one)")
      ->check(CLI::Range(1, 1000));
  CLI11_PARSE(app, argc, argv);

  const fs::path dir = fs::temp_directory_path() / ("balance_outcomes." + std::to_string(getpid()));
  fs::create_directories(dir);
  std::printf("%-13s %4s %9s %10s %9s %9s %9s %8s %9s  %s\n", "parameters", "seed", "caught_s",
              "balanced_s", "rms_deg", "max_deg", "duty_rms", "arm_deg", "law_ns", "end");
  int all = 0;
  int held = 0;
  for (const auto source : {app::ControllerParameters::output_error,
                            app::ControllerParameters::lsmi, app::ControllerParameters::cad}) {
    app::ControllerDesignOptions design;
    design.results = results;
    design.parameters = source;
    design.config_path = configuration(dir, 1, changes);
    design.output = dir / (std::string(app::to_string(source)) + ".toml");
    std::ostringstream out, err;
    if (app::run_controller_design_command(design, out, err) != 0) {
      std::cerr << err.str();
      return 1;
    }
    for (int seed = 1; seed <= seeds; ++seed) {
      app::RunOptions run;
      run.config_path = configuration(dir, seed, changes);
      run.simulated = true;
      run.virtual_time = true;
      run.logs_dir = dir / "logs";
      run.lcm_url = "memq://";
      run.session.balance = design.output;
      run.session.duration_s = duration_s;
      run.session.label = "bench";
      std::ostringstream run_out, run_err;
      app::run_session_command(run, run_out, run_err);
      fs::path log;
      for (const auto& entry : fs::directory_iterator(run.logs_dir)) {
        if (entry.path().extension() == ".lcmlog") log = entry.path();
      }
      const auto b = pipeline::summarize_balance(session_log::load_session_log(log));
      fs::remove(log);
      ++all;
      if (!b) {
        std::printf("%-13s %4d  no balance session: %s\n", app::to_string(source), seed,
                    run_err.str().c_str());
        continue;
      }
      // Held: caught within 10 s and balanced until the session's end, nothing stopping it.
      const bool ended_well = b->end_reason == "duration_reached";
      if (b->caught_at_s && *b->caught_at_s < 10 && ended_well) ++held;
      const std::string end = !b->caught_at_s ? "not caught"
                              : ended_well    ? "held"
                                              : b->end_reason.substr(0, b->end_reason.find(':'));
      std::printf("%-13s %4d %9.2f %10.2f %9.3f %9.3f %9.4f %8.1f %9lld  %s\n",
                  app::to_string(source), seed, b->caught_at_s.value_or(-1), b->balanced_s,
                  b->upright_rms_deg, b->upright_max_deg, b->duty_rms, b->max_abs_arm_deg,
                  static_cast<long long>(b->law_time_p50_ns), end.c_str());
    }
  }
  std::printf("caught within 10 s and held: %d of %d sessions\n", held, all);
  fs::remove_all(dir);
  return 0;
}
