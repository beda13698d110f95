// The windowed set inversion on a pair of 10 s bang-bang sessions of the simulated rig, as
// `furuta identify --guaranteed` runs it: the output-error fit, its estimate +- k sd as the search
// box, the recordings' chains of windows. Prints the time per step and per window, the set's
// half-widths against the truth, and whether the truth is inside.
//
//   windowed_set [SEED_A SEED_B [WINDOWS [SEARCH_SD [PASSES]]]]   (defaults 1 2 8 50 3)
#include "furuta/identification/windowed_set.hpp"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/identification/identify.hpp"
#include "furuta/identification/output_error.hpp"
#include "furuta/identification/physical_inputs.hpp"
#include "furuta/pipeline/pipeline.hpp"
#include "furuta/session_log/session_log.hpp"

namespace {

using namespace furuta;
namespace fs = std::filesystem;

session_log::SessionLog session(const fs::path& logs, std::int64_t seed) {
  app::RunOptions options;
  options.config_path = FURUTA_SOURCE_DIR "/config/rig.toml";
  options.simulated = true;
  options.virtual_time = true;
  options.logs_dir = logs;
  options.lcm_url = "memq://";
  options.session.label = "bench" + std::to_string(seed);
  options.session.seed = seed;
  std::ostringstream text, err;
  if (app::run_session_command(options, text, err) != 0) {
    std::fprintf(stderr, "%s", err.str().c_str());
    std::exit(1);
  }
  const std::string t = text.str();
  const auto at = t.find("; log ");
  return session_log::load_session_log(t.substr(at + 6, t.find('\n', at) - at - 6));
}

}  // namespace

int main(int argc, char** argv) {
  const std::int64_t seed_a = argc > 1 ? std::atoll(argv[1]) : 1;
  const std::int64_t seed_b = argc > 2 ? std::atoll(argv[2]) : 2;
  const auto windows = static_cast<std::size_t>(argc > 3 ? std::atoi(argv[3]) : 8);
  const double search_sd = argc > 4 ? std::atof(argv[4]) : 50.0;
  const int passes = argc > 5 ? std::atoi(argv[5]) : 3;

  const fs::path logs =
      fs::temp_directory_path() /
      ("furuta-windowed-set-bench-" + std::to_string(seed_a) + "-" + std::to_string(seed_b));
  fs::remove_all(logs);
  config::RigConfig rig;
  std::vector<identification::OeExperiment> experiments;
  std::vector<identification::RawExperiment> raw;
  std::vector<double> supply;
  for (const std::int64_t seed : {seed_a, seed_b}) {
    const session_log::SessionLog log = session(logs, seed);
    rig = config::parse_rig_config(log.start->rig_config_toml, "log");
    experiments.push_back(identification::oe_experiment_from_log(log, rig));
    raw.push_back(identification::experiment_from_log(log));
    supply.insert(supply.end(), experiments.back().supply_readings_v.begin(),
                  experiments.back().supply_readings_v.end());
  }
  fs::remove_all(logs);
  const pipeline::Settings settings = pipeline::settings_for(rig);
  const model::Parameters<double> lsmi =
      identification::identify(raw, std::nullopt, settings.identify, rig.motor).combined.estimate;
  const identification::OutputErrorResult oe = identification::refine_output_error(
      experiments, lsmi, rig.motor, settings.output_error.options);

  const identification::PhysicalInputs inputs = identification::physical_inputs(rig, supply);
  double scale = 0;
  for (std::size_t i = 0; i < experiments.size(); ++i) {
    scale += experiments[i].supply_scale * oe.input_gain[i] / 2;
  }
  const double g = rig.motor.arm_torque_nm(1.0, 0.0) * scale;
  const double k_w = -rig.motor.arm_torque_nm(0.0, 1.0);
  const model::Parameters<interval::Interval> search =
      identification::search_box(oe.estimate, oe.std_dev, search_sd, g, k_w, inputs);
  identification::WindowedSetOptions o = settings.windowed.options;
  o.windows = windows;
  o.inversion.max_passes = passes;

  auto last = std::chrono::steady_clock::now();
  const identification::WindowedSet r = identification::invert_recordings(
      experiments, inputs, search, o, [&](std::size_t done, std::size_t total) {
        const auto now = std::chrono::steady_clock::now();
        std::printf("  step %zu of at most %zu: %.1f s\n", done, total,
                    std::chrono::duration<double>(now - last).count());
        std::fflush(stdout);
        last = now;
      });

  const model::Parameters<double>& p = rig.simulation.parameters;
  const model::Parameters<double> truth{p.mu1 / g, p.mu2 / g,         p.mu3 / g, p.mu4 / g,
                                        p.mug / g, (p.fv1 + k_w) / g, p.fv2 / g};
  const char* verdicts[] = {"contracted", "empty", "unresolved"};
  std::size_t carried = 0;
  for (const auto& w : r.windows) carried += w.verdict == identification::WindowVerdict::contracted;
  std::printf(
      "seeds %lld-%lld, %zu windows per recording, +-%g sd, %d passes: %s; %zu windows (%zu "
      "carried whole) in %.1f s wall, %.1f s per window (flows %.1f s summed); lag [%.4f, %.4f] "
      "ms, "
      "pendulum zero [%.3g, %.3g] rad\n",
      static_cast<long long>(seed_a), static_cast<long long>(seed_b), windows, search_sd, passes,
      verdicts[static_cast<int>(r.verdict)], r.windows.size(), carried, r.seconds,
      r.windows.empty() ? 0.0 : r.seconds / static_cast<double>(r.windows.size()), r.flow_seconds,
      r.lag_s.lo() * 1e3, r.lag_s.hi() * 1e3, r.pendulum_zero_rad.lo(), r.pendulum_zero_rad.hi());
  const char* names[] = {"mu1/g", "mu2/g", "mu3/g", "mu4/g", "mug/g", "b", "fv2/g"};
  bool all_inside = true;
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const bool inside = r.set[k].contains(truth[k]);
    all_inside = all_inside && inside;
    std::printf("  %-6s +-%7.4f %% of the truth (searched +-%7.4f %%), truth inside: %s\n",
                names[k], 100 * r.set[k].rad() / truth[k], 100 * r.search[k].rad() / truth[k],
                inside ? "yes" : "NO");
  }
  std::printf("truth inside the set: %s\n", all_inside ? "yes" : "NO");
  return 0;
}
