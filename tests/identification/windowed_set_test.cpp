// The windowed set inversion on sessions of the simulated rig, whose truth is known: the truth and
// the data path's lag are kept from a search box around them; a search box the data exclude is
// proven empty; recordings the windows cannot start from are refused with their reason.
#include "furuta/identification/windowed_set.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "furuta/config/rig_config.hpp"
#include "furuta/identification/output_error.hpp"
#include "furuta/identification/physical_inputs.hpp"
#include "furuta/session_log/session_log.hpp"
#include "simulated_logs.hpp"
#include "temp_dir.hpp"

namespace furuta::identification {
namespace {

namespace fs = std::filesystem;
using interval::Interval;

struct Sessions {
  config::RigConfig rig;
  std::vector<OeExperiment> experiments;
  PhysicalInputs inputs;
  model::Parameters<double> truth_scaled;
};

// Two 10 s bang-bang sessions of the simulated rig (seeds 1 and 2), made once; their truth
// scaled with the nominal drive at the sessions' supply (the drive the simulated rig runs).
const Sessions& sessions() {
  static testing::TempDir dir;
  static const Sessions s = [] {
    Sessions out;
    std::vector<double> supply;
    for (const std::int64_t seed : {1, 2}) {
      const fs::path path =
          testing::simulated_session_log(dir.path(), "bang-bang" + std::to_string(seed), seed);
      const session_log::SessionLog log = session_log::load_session_log(path);
      out.rig = config::parse_rig_config(log.start->rig_config_toml, path.string());
      out.experiments.push_back(oe_experiment_from_log(log, out.rig));
      supply.insert(supply.end(), out.experiments.back().supply_readings_v.begin(),
                    out.experiments.back().supply_readings_v.end());
    }
    out.inputs = physical_inputs(out.rig, supply);
    double scale = 0;
    for (const OeExperiment& e : out.experiments) scale += e.supply_scale / 2;
    const double g = out.rig.motor.arm_torque_nm(1.0, 0.0) * scale;
    const double k_w = -out.rig.motor.arm_torque_nm(0.0, 1.0);
    const model::Parameters<double>& p = out.rig.simulation.parameters;
    out.truth_scaled = {p.mu1 / g, p.mu2 / g,         p.mu3 / g, p.mu4 / g,
                        p.mug / g, (p.fv1 + k_w) / g, p.fv2 / g};
    return out;
  }();
  return s;
}

model::Parameters<Interval> relative_box(const model::Parameters<double>& p, double relative) {
  return p.map([&](double v) { return Interval(v) * Interval(1 - relative, 1 + relative); });
}

bool inside_box(const model::Parameters<double>& p, const model::Parameters<Interval>& box) {
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    if (!box[k].contains(p[k])) return false;
  }
  return true;
}

WindowedSetOptions options(std::size_t windows) {
  WindowedSetOptions o;
  o.windows = windows;
  o.arm_rest_speed_rad_s = 0.01;
  o.inversion.max_passes = 1;
  return o;
}

// From rest through the first switch of both sessions on a box of +-0.3 %: the truth stays in
// the set, the damping b is narrowed, and the lag is pinned inside [guaranteed] lag_ms.
TEST(WindowedSet, OnSimulatedSessionsTheTruthAndTheLagAreKept) {
  const Sessions& s = sessions();
  const model::Parameters<Interval> search = relative_box(s.truth_scaled, 0.003);
  const WindowedSet out = invert_recordings(s.experiments, s.inputs, search, options(1));
  ASSERT_EQ(out.verdict, WindowedSetVerdict::contracted) << out.finding;
  EXPECT_TRUE(inside_box(s.truth_scaled, out.set));
  EXPECT_LT(out.set.fv1.width(), 0.8 * search.fv1.width());
  EXPECT_LT(out.lag_s.width(), 0.5 * s.inputs.lag_s.width());
  EXPECT_EQ(out.windows.size(), 2u);
  for (const WindowRecord& w : out.windows) {
    EXPECT_NE(w.verdict, WindowVerdict::inconsistent) << w.reason;
    EXPECT_GT(w.readings, 10u);
  }
  std::printf("[ measured ] %zu windows in %.1f s: b +-%.3f %%, lag [%.3f, %.3f] ms\n",
              out.windows.size(), out.seconds, 100 * out.set.fv1.rad() / s.truth_scaled.fv1,
              out.lag_s.lo() * 1e3, out.lag_s.hi() * 1e3);
}

// A search box whose damping is 2 % off the truth (+-0.3 % wide): the first windows prove that no
// parameter in it explains the angles.
TEST(WindowedSet, ASearchBoxTheDataExcludeIsProvenEmpty) {
  const Sessions& s = sessions();
  model::Parameters<double> wrong = s.truth_scaled;
  wrong.fv1 *= 1.02;
  const WindowedSet out =
      invert_recordings(s.experiments, s.inputs, relative_box(wrong, 0.003), options(1));
  EXPECT_EQ(out.verdict, WindowedSetVerdict::empty) << out.finding;
  EXPECT_NE(out.finding.find("no parameter of the search box"), std::string::npos) << out.finding;
}

TEST(WindowedSet, RecordingsTheWindowsCannotStartFromAreRefused) {
  const Sessions& s = sessions();
  const model::Parameters<Interval> search = relative_box(s.truth_scaled, 0.003);
  const auto refused = [&](OeExperiment e, const std::string& why) {
    try {
      (void)chain_start(e, s.inputs, search, options(1));
      ADD_FAILURE() << "accepted: " << why;
    } catch (const std::invalid_argument& error) {
      EXPECT_NE(std::string(error.what()).find(why), std::string::npos) << error.what();
    }
  };
  OeExperiment voltage = s.experiments.front();
  voltage.input_kind = InputKind::voltage;
  refused(voltage, "voltage or torque");
  OeExperiment cubic = s.experiments.front();
  cubic.input_slope.assign(cubic.input_t_s.size(), 0.0);
  refused(cubic, "cubic");
  OeExperiment moving = s.experiments.front();
  moving.input.front() = 0.1;
  refused(moving, "no rest before the first command");
  OeExperiment idle = s.experiments.front();
  std::fill(idle.input.begin(), idle.input.end(), 0.0);
  refused(idle, "never non-zero");
}

}  // namespace
}  // namespace furuta::identification
