// Output-error refinement (issue 19) on sessions of the simulated rig, whose truth is known: LSMI
// as the start, the refined estimate against the truth and its own standard deviations, the
// held-out free run against LSMI's.
#include "furuta/identification/output_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "furuta/config/rig_config.hpp"
#include "furuta/identification/identify.hpp"
#include "furuta/pipeline/pipeline.hpp"
#include "furuta/session_log/session_log.hpp"
#include "simulated_logs.hpp"
#include "temp_dir.hpp"

namespace furuta::identification {
namespace {

namespace fs = std::filesystem;

struct Session {
  session_log::SessionLog log;
  config::RigConfig rig;
};

// Logs made once for the whole suite (each is a 10 s session in virtual time).
class OutputErrorSim : public ::testing::Test {
 protected:
  static const Session& session(std::int64_t seed) {
    static testing::TempDir dir;
    static std::map<std::int64_t, Session> cache;
    auto it = cache.find(seed);
    if (it == cache.end()) {
      const fs::path path =
          furuta::testing::simulated_session_log(dir.path(), "oe" + std::to_string(seed), seed);
      Session s;
      s.log = session_log::load_session_log(path);
      s.rig = config::parse_rig_config(s.log.start->rig_config_toml, path.string());
      it = cache.emplace(seed, std::move(s)).first;
    }
    return it->second;
  }

  struct Fit {
    Identification lsmi;
    OutputErrorResult oe;
    model::Parameters<double> truth;
    std::vector<OeExperiment> experiments;
    OeExperiment held_out;
  };

  static Fit fit(std::int64_t a, std::int64_t b, std::int64_t held_out,
                 const OutputErrorOptions& options = {}) {
    const Session& sa = session(a);
    const Session& sb = session(b);
    const Session& sv = session(held_out);
    const pipeline::Settings settings = pipeline::settings_for(sa.rig);
    Fit f;
    f.lsmi = identify({experiment_from_log(sa.log), experiment_from_log(sb.log)},
                      experiment_from_log(sv.log), settings.identify, sa.rig.motor);
    f.truth = sa.rig.simulation.parameters;
    f.experiments = {oe_experiment_from_log(sa.log, sa.rig),
                     oe_experiment_from_log(sb.log, sb.rig)};
    f.held_out = oe_experiment_from_log(sv.log, sv.rig);
    f.oe = refine_output_error(f.experiments, f.lsmi.combined.estimate, sa.rig.motor, options);
    return f;
  }

  static void print(const Fit& f, const std::string& what) {
    std::printf("%s: %s\n", what.c_str(), f.oe.message.c_str());
    std::printf(
        "  lag %.3f ms (sd %.3f), q2 offset %.2e rad, rms q1 %.2e q2 %.2e, continuity %.3f, "
        "sigma %.3f, %zu segments, %d iterations\n",
        f.oe.input_lag_s * 1e3, f.oe.input_lag_std_s * 1e3, f.oe.q2_offset_rad,
        f.oe.angle_rms_rad[0], f.oe.angle_rms_rad[1], f.oe.continuity_rms, f.oe.residual_sigma,
        f.oe.segments, f.oe.iterations);
    for (double g : f.oe.input_gain) std::printf("  gain %.5f\n", g);
    for (std::size_t i = 0; i < model::kParameterCount; ++i) {
      const double t = f.truth[i];
      std::printf("  %-4s LSMI %+6.2f %%  OE %+7.3f %%  (%.2f sd, sd %.3f %%)\n",
                  model::kParameterNames[i], (f.lsmi.combined.estimate[i] - t) / t * 100,
                  (f.oe.estimate[i] - t) / t * 100, (f.oe.estimate[i] - t) / f.oe.std_dev[i],
                  f.oe.std_dev[i] / std::abs(t) * 100);
    }
  }
};

TEST_F(OutputErrorSim, Explore) {
  const Fit f = fit(1, 2, 3);
  print(f, "seeds 1 2");
}

}  // namespace
}  // namespace furuta::identification
