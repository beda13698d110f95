// The output-error refinement (issue 19) of two 10 s sessions of the simulated rig (bang-bang,
// amplitude 0.3, 16 ms; `furuta run --sim --virtual-time` logs them once, untimed), started from
// their LSMI estimate. Run: build/release/bench/output_error_bench
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/identification/identify.hpp"
#include "furuta/identification/output_error.hpp"
#include "furuta/pipeline/pipeline.hpp"
#include "furuta/session_log/session_log.hpp"

namespace {

using namespace furuta;
namespace fs = std::filesystem;

struct Sessions {
  config::RigConfig rig;
  std::vector<identification::OeExperiment> experiments;
  model::Parameters<double> lsmi;
};

const Sessions& sessions() {
  static const Sessions s = [] {
    const fs::path logs = fs::temp_directory_path() / "furuta-output-error-bench";
    fs::remove_all(logs);
    Sessions out;
    std::vector<identification::RawExperiment> raw;
    for (std::int64_t seed : {1, 2}) {
      app::RunOptions options;
      options.config_path = FURUTA_SOURCE_DIR "/config/rig.toml";
      options.simulated = true;
      options.virtual_time = true;
      options.logs_dir = logs;
      options.lcm_url = "memq://";
      options.session.label = "bench" + std::to_string(seed);
      options.session.seed = seed;
      std::ostringstream text, err;
      if (app::run_session_command(options, text, err) != 0) std::abort();
      const std::string t = text.str();
      const auto at = t.find("; log ");
      const session_log::SessionLog log =
          session_log::load_session_log(t.substr(at + 6, t.find('\n', at) - at - 6));
      out.rig = config::parse_rig_config(log.start->rig_config_toml, "log");
      out.experiments.push_back(identification::oe_experiment_from_log(log, out.rig));
      raw.push_back(identification::experiment_from_log(log));
    }
    out.lsmi = identification::identify(raw, std::nullopt, pipeline::settings_for(out.rig).identify,
                                        out.rig.motor)
                   .combined.estimate;
    fs::remove_all(logs);
    return out;
  }();
  return s;
}

// One iteration = refine_output_error on both sessions: the multiple-shooting fit from the LSMI
// estimate and the covariance. state.range(0): RK4 substep in microseconds; range(1): threads.
void BM_RefineTwoSessions(benchmark::State& state) {
  const Sessions& s = sessions();
  identification::OutputErrorOptions o;
  o.substep_s = static_cast<double>(state.range(0)) * 1e-6;
  o.num_threads = static_cast<int>(state.range(1));
  int iterations = 0;
  for (auto _ : state) {
    const identification::OutputErrorResult r =
        identification::refine_output_error(s.experiments, s.lsmi, s.rig.motor, o);
    iterations = r.iterations;
    benchmark::DoNotOptimize(r.estimate);
  }
  state.counters["solver_iterations"] = iterations;
}
BENCHMARK(BM_RefineTwoSessions)
    ->Args({1000, 1})
    ->Args({1000, 2})
    ->Args({2000, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
