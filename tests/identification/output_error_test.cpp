// Output-error refinement (issue 19) on sessions of the simulated rig, whose truth is known: LSMI
// as the start, the refined estimate against the truth and its own standard deviations, the
// held-out free run against LSMI's.
#include "furuta/identification/output_error.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
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

struct Excitation {
  std::string profile = "bang_bang";
  double amplitude_duty = 0.3;
  auto operator<=>(const Excitation&) const = default;
};

// One 10 s session of the simulated rig with the project's rig.toml, in virtual time.
fs::path session_log_path(const fs::path& logs, const Excitation& x, std::int64_t seed) {
  return furuta::testing::simulated_session_log(logs, x.profile + std::to_string(seed), seed, {},
                                                x.profile, x.amplitude_duty);
}

// Logs made once for the whole suite.
class OutputErrorSim : public ::testing::Test {
 public:
  static const Session& session(std::int64_t seed, const Excitation& x = {}) {
    static testing::TempDir dir;
    static std::map<std::pair<Excitation, std::int64_t>, Session> cache;
    auto it = cache.find({x, seed});
    if (it == cache.end()) {
      const fs::path path = session_log_path(dir.path(), x, seed);
      Session s;
      s.log = session_log::load_session_log(path);
      s.rig = config::parse_rig_config(s.log.start->rig_config_toml, path.string());
      it = cache.emplace(std::make_pair(x, seed), std::move(s)).first;
    }
    return it->second;
  }

  struct Fit {
    Identification lsmi;
    OutputErrorResult oe;
    model::Parameters<double> truth;
    model::MotorData truth_motor;
    std::vector<OeExperiment> experiments;
    OeExperiment held_out;
  };

  static Fit fit(std::int64_t a, std::int64_t b, std::int64_t held_out,
                 const OutputErrorOptions& options = {}, const Excitation& x = {}) {
    const Session& sa = session(a, x);
    const Session& sb = session(b, x);
    const Session& sv = session(held_out, x);
    const pipeline::Settings settings = pipeline::settings_for(sa.rig);
    Fit f;
    f.lsmi = identify({experiment_from_log(sa.log), experiment_from_log(sb.log)},
                      experiment_from_log(sv.log), settings.identify, sa.rig.motor);
    f.truth = sa.rig.simulation.parameters;
    f.truth_motor = sa.rig.motor;
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

// Figures for the report and the README (not a check): run with
// --gtest_also_run_disabled_tests --gtest_filter='*Explore*'.
TEST_F(OutputErrorSim, DISABLED_Explore) {
  const std::vector<std::array<std::int64_t, 3>> seeds = {
      {1, 2, 3}, {4, 5, 6}, {7, 8, 9}, {10, 11, 12}, {13, 14, 15}};
  std::vector<Excitation> excitations = {
      {}, {"bang_bang", 0.1}, {"bang_bang", 0.5}, {"chirp", 0.1}, {"multisine", 0.1}};
  if (const char* only = std::getenv("OE_EXPLORE_PROFILE")) {
    excitations = {{only, std::atof(std::getenv("OE_EXPLORE_AMPLITUDE"))}};
  }
  for (const Excitation& x : excitations) {
    for (const auto& s : seeds) {
      const auto t0 = std::chrono::steady_clock::now();
      OutputErrorOptions o;
      if (const char* seg = std::getenv("OE_SEGMENT")) o.segment_s = std::atof(seg);
      const Fit f = fit(s[0], s[1], s[2], o, x);
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      print(f, x.profile + " " + std::to_string(x.amplitude_duty) + " seeds " +
                   std::to_string(s[0]) + " " + std::to_string(s[1]));
      const FreeRun lsmi = simulate_free_run(f.held_out, f.lsmi.combined.estimate, f.truth_motor,
                                             f.oe.input_lag_s, f.oe.q2_offset_rad);
      const FreeRun oe = simulate_free_run(f.held_out, f.oe.estimate, f.truth_motor,
                                           f.oe.input_lag_s, f.oe.q2_offset_rad);
      const FreeRun truth = simulate_free_run(f.held_out, f.truth, f.truth_motor, f.oe.input_lag_s,
                                              f.oe.q2_offset_rad);
      std::printf(
          "  held out free run q1/q2 RMSE [rad]: LSMI %.4f %.4f  OE %.4f %.4f  truth %.4f "
          "%.4f   (%.2f s incl. logs)\n",
          lsmi.rmse_rad[0], lsmi.rmse_rad[1], oe.rmse_rad[0], oe.rmse_rad[1], truth.rmse_rad[0],
          truth.rmse_rad[1], seconds);
    }
  }
}

TEST_F(OutputErrorSim, DISABLED_ExploreSteps) {
  for (double substep : {1e-3, 2e-3, 4e-3}) {
    for (double segment : {0.25, 0.5, 1.0}) {
      OutputErrorOptions o;
      o.substep_s = substep;
      o.segment_s = segment;
      const auto t0 = std::chrono::steady_clock::now();
      const Fit f = fit(1, 2, 3, o);
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      print(f, "substep " + std::to_string(substep) + " segment " + std::to_string(segment) + " (" +
                   std::to_string(seconds) + " s)");
    }
  }
}

// The targets for one fit (two sessions fitted, one held out): every mu and fv1 within 1 %
// of the truth, fv2 within 5 %; the lag and the pendulum's zero as the simulated rig made them;
// residuals at the encoders' quantisation; the result in the physical region; the held-out free
// run closer to the measured angles than LSMI's. The truth's distance in reported standard
// deviations is returned for the caller to judge over many fits.
std::vector<double> expect_targets(const OutputErrorSim::Fit& f, const std::string& what) {
  SCOPED_TRACE(what);
  EXPECT_TRUE(f.oe.converged) << f.oe.message;
  std::vector<double> sds;
  for (std::size_t i = 0; i < model::kParameterCount; ++i) {
    const double truth = f.truth[i];
    const double tolerance = i == 6 ? 0.05 : 0.01;
    EXPECT_NEAR(f.oe.estimate[i], truth, tolerance * std::abs(truth)) << model::kParameterNames[i];
    sds.push_back(std::abs(f.oe.estimate[i] - truth) / f.oe.std_dev[i]);
  }
  // The physical region (docs/model.md).
  const model::Parameters<double>& p = f.oe.estimate;
  EXPECT_GT(p.mu1, 0);
  EXPECT_GT(p.mu2, 0);
  EXPECT_GT(p.mu4, 0);
  EXPECT_GT(p.mug, 0);
  EXPECT_GT(p.mu1 * p.mu4, p.mu3 * p.mu3);
  EXPECT_GE(p.fv1, 0);
  EXPECT_GE(p.fv2, 0);
  // The simulated rig's USB latency is 1 ms; its encoders read half a count low on average.
  EXPECT_NEAR(f.oe.input_lag_s, 1e-3, 0.05e-3);
  EXPECT_NEAR(f.oe.q2_offset_rad, 0.5 * 2 * std::numbers::pi / 4096,
              0.2 * 2 * std::numbers::pi / 4096);
  // The angle residuals are the encoders' quantisation (one count / sqrt(12)) and no more.
  EXPECT_NEAR(f.oe.residual_sigma, 1.0, 0.1);
  EXPECT_LT(f.oe.continuity_rms, 1.0);
  const model::MotorData& motor = f.truth_motor;
  const FreeRun lsmi = simulate_free_run(f.held_out, f.lsmi.combined.estimate, motor,
                                         f.oe.input_lag_s, f.oe.q2_offset_rad);
  const FreeRun oe =
      simulate_free_run(f.held_out, f.oe.estimate, motor, f.oe.input_lag_s, f.oe.q2_offset_rad);
  EXPECT_LT(oe.rmse_rad[1], lsmi.rmse_rad[1]);
  EXPECT_LT(oe.rmse_rad[0], lsmi.rmse_rad[0]);
  return sds;
}

// The truth within 3 reported standard deviations, judged as a calibrated estimate is: of normal
// errors 0.27 % lie beyond 3 sd, so over the 7 parameters of five fits a strict test would fail
// about one run in twelve with perfect standard deviations. The parameters of one fit move
// together (the arm's inertia and the lag), so fits are counted: at most one of them with a
// parameter beyond 3 sd, none beyond 4.
void expect_calibrated(const std::vector<std::vector<double>>& fits, const std::string& what) {
  std::size_t beyond3 = 0;
  double worst = 0;
  for (const std::vector<double>& sds : fits) {
    const double fit_worst = *std::max_element(sds.begin(), sds.end());
    beyond3 += fit_worst > 3.0;
    worst = std::max(worst, fit_worst);
  }
  EXPECT_LE(beyond3, 1u) << what;
  EXPECT_LT(worst, 4.0) << what;
}

TEST_F(OutputErrorSim, DefaultSessionsMeetTheTargets) {
  const std::vector<double> sds = expect_targets(fit(1, 2, 3), "seeds 1 2, held out 3");
  EXPECT_LT(*std::max_element(sds.begin(), sds.end()), 3.0);
}

// Five seed triples of each excitation the issue names: bang-bang at amplitude 0.1, 0.3 and 0.5,
// the chirp and the multisine (at 0.1: at 0.3 both drive the arm past its limit within 2 s).
class RefinementTargets : public OutputErrorSim {
 public:
  static void five_seed_triples(const Excitation& x) {
    std::vector<std::vector<double>> fits;
    for (std::int64_t first : {1, 4, 7, 10, 13}) {
      fits.push_back(expect_targets(fit(first, first + 1, first + 2, {}, x),
                                    x.profile + " " + std::to_string(x.amplitude_duty) + " seeds " +
                                        std::to_string(first) + " " + std::to_string(first + 1)));
    }
    expect_calibrated(fits, x.profile);
  }
};

TEST_F(RefinementTargets, BangBangAtTheDefaultAmplitude) {
  five_seed_triples({"bang_bang", 0.3});
}

TEST_F(RefinementTargets, GentleBangBang) {
  five_seed_triples({"bang_bang", 0.1});
}

// At 0.5 the arm reaches its +-86 degree thresholds before any switch period ends, so the sign
// follows the thresholds alone and every seed gives the same session: one fit says it all. Its
// LSMI start is 28 % off (the pendulum spins over at 16 ms samples).
TEST_F(RefinementTargets, StrongBangBang) {
  const Fit f = fit(1, 2, 3, {}, {"bang_bang", 0.5});
  const std::vector<double> sds = expect_targets(f, "amplitude 0.5");
  EXPECT_LT(*std::max_element(sds.begin(), sds.end()), 3.0);
  EXPECT_GT(std::abs(f.lsmi.combined.estimate.mu1 - f.truth.mu1), 0.1 * f.truth.mu1);
}

TEST_F(RefinementTargets, Chirp) {
  five_seed_triples({"chirp", 0.1});
}

TEST_F(RefinementTargets, Multisine) {
  five_seed_triples({"multisine", 0.1});
}

// A start outside the physical region (what a reversed pendulum gives LSMI: mu3 < 0 and a mass
// matrix that is not positive definite) is moved into it, said so, and the fit still finds the
// truth: the region is the parametrisation's, not a penalty's.
TEST_F(OutputErrorSim, AStartOutsideThePhysicalRegionIsMovedIntoItAndSaid) {
  const Session& a = session(1);
  const Session& b = session(2);
  model::Parameters<double> start = a.rig.simulation.parameters;
  start.mu2 *= 1.05;
  start.mu3 = -2.0 * start.mu3;
  start.fv2 = -start.fv2;
  const OutputErrorResult r = refine_output_error(
      {oe_experiment_from_log(a.log, a.rig), oe_experiment_from_log(b.log, b.rig)}, start,
      a.rig.motor);
  EXPECT_GE(r.warnings.size(), 2u);
  const model::Parameters<double>& truth = a.rig.simulation.parameters;
  for (std::size_t i = 0; i < model::kParameterCount; ++i) {
    EXPECT_NEAR(r.estimate[i], truth[i], (i == 6 ? 0.05 : 0.01) * std::abs(truth[i]))
        << model::kParameterNames[i];
  }
}

// Angle errors correlated over a segment (a one-count wobble of the pendulum's reading at 1.2 Hz,
// its own swing, as an eccentric encoder disc would give) are not independent noise: the reported
// standard deviations take the cluster-robust estimate where it is the larger, and the truth stays
// within 3 of them. On clean sessions the two agree.
TEST_F(OutputErrorSim, CorrelatedAngleErrorsWidenTheStandardDeviations) {
  const Fit clean = fit(1, 2, 3);
  std::vector<OeExperiment> wobbly = clean.experiments;
  const double count = 2 * std::numbers::pi / 4096;
  for (OeExperiment& e : wobbly) {
    for (OeObservation& o : e.observations) {
      if (o.joint == 1) o.angle_rad += count * std::sin(2 * std::numbers::pi * 1.2 * o.t_s);
    }
  }
  const OutputErrorResult r =
      refine_output_error(wobbly, clean.lsmi.combined.estimate, clean.truth_motor);
  ASSERT_TRUE(r.converged) << r.message;
  std::size_t widened = 0;
  for (std::size_t i = 0; i < model::kParameterCount; ++i) {
    const char* name = model::kParameterNames[i];
    std::printf("[ measured ] %s: robust / local sd %.2f clean, %.2f with the wobble\n", name,
                clean.oe.std_dev[i] / clean.oe.local_std_dev[i], r.std_dev[i] / r.local_std_dev[i]);
    EXPECT_LT(clean.oe.std_dev[i], 1.1 * clean.oe.local_std_dev[i]) << name;
    widened += r.std_dev[i] > 1.2 * r.local_std_dev[i];
    EXPECT_LT(std::abs(r.estimate[i] - clean.truth[i]), 3 * r.std_dev[i]) << name;
  }
  EXPECT_GE(widened, 4u);
}

// With the lag held at a wrong value, the fit is worse: the lag is what the data say, not free.
TEST_F(OutputErrorSim, AHeldWrongLagShowsInTheResiduals) {
  OutputErrorOptions held;
  held.estimate_lag = false;
  held.input_lag_s = 3e-3;
  held.max_iterations = 15;  // far enough to show it; a wrong lag takes the full 50 to stop
  const Fit wrong = fit(1, 2, 3, held);
  EXPECT_EQ(wrong.oe.input_lag_s, 3e-3);
  // The right lag leaves the encoders' quantisation, sigma 1 (DefaultSessionsMeetTheTargets).
  EXPECT_GT(wrong.oe.residual_sigma, 1.3) << wrong.oe.message;
}

TEST(OutputError, RefusesAnExperimentWithoutAngles) {
  OeExperiment e;
  e.name = "empty";
  EXPECT_THROW(refine_output_error({e}, model::paper_run1(), {}), std::invalid_argument);
}

// The noise of readings that state no resolution, from the readings: white noise on a swing with
// input switches (a bang-bang arm's kinks), a quantised swing (its count / sqrt(12)), and readings
// that never change (nothing to estimate).
TEST(AngleNoiseFromReadings, FindsWhiteNoiseAndQuantisationUnderTheMotion) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 2e-4);
  std::vector<double> noisy, counted, still(100, 0.25);
  const double count = 2 * std::numbers::pi / 4096;
  for (int k = 0; k < 1000; ++k) {
    const double t = 0.01 * k;
    // A swing of 0.8 rad at 1.2 Hz and a triangle wave (a kink every 0.6 s).
    const double phase = std::fmod(t, 1.2);
    const double motion =
        0.8 * std::sin(2 * std::numbers::pi * 1.2 * t) + (phase < 0.6 ? phase : 1.2 - phase);
    noisy.push_back(motion + noise(rng));
    counted.push_back(std::floor(motion / count) * count);
  }
  EXPECT_NEAR(angle_noise_from_readings(noisy), 2e-4, 3e-5);
  const double quantised = angle_noise_from_readings(counted);
  std::printf("[ measured ] quantised: %.3g rad against a count / sqrt(12) of %.3g\n", quantised,
              count / std::sqrt(12.0));
  EXPECT_GE(quantised, count / std::sqrt(12.0));
  EXPECT_LT(quantised, 1.5 * count / std::sqrt(12.0));
  EXPECT_EQ(angle_noise_from_readings(still), 0.0);
  // Too few readings for a fourth difference: the floor, one step / sqrt(12).
  EXPECT_DOUBLE_EQ(angle_noise_from_readings(std::vector<double>{0.0, 0.1, 0.3}),
                   0.1 / std::sqrt(12.0));
}

}  // namespace
}  // namespace furuta::identification
