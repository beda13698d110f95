// The paper's scenarios: the "measurement" against the physics, a short real integration whose
// tube must hold the true model's samples (soundness), coverage; their text, JSON and figures are
// tested in tests/report/scenario_outputs_test.cpp.
#include "furuta/validated/scenarios.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "furuta/validated/research/paper_parameters.hpp"
#include "short_scenario_run.hpp"

namespace furuta::validated {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(Scenarios, ThePapersFour) {
  const std::vector<Scenario> s = paper_scenarios();
  ASSERT_EQ(s.size(), 4u);
  const double q2_deg[] = {-100, 50, -90, -45};
  const double u_nm[] = {0, 0, 0.17, -0.1};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(s[i].number, static_cast<int>(i + 1));
    EXPECT_NEAR(s[i].q2_initial_rad, q2_deg[i] * kPi / 180, 1e-15);
    EXPECT_EQ(s[i].torque_nm, u_nm[i]);
    EXPECT_EQ(s[i].duration_s, 4.0);
  }
  EXPECT_EQ(paper_scenario(2).q2_initial_rad, s[1].q2_initial_rad);
  EXPECT_THROW(paper_scenario(0), std::invalid_argument);
  EXPECT_THROW(paper_scenario(5), std::invalid_argument);
}

TEST(ScenarioMeasurement, SampledAndQuantisedLikeTheRig) {
  const ScenarioMeasurement m = measure_scenario(paper_scenario(1), model::paper_run1());
  ASSERT_EQ(m.t_s.size(), 251u);  // 0 to 4 s every 16 ms
  const double pendulum = 2 * kPi / 4096, arm = 2 * kPi / (512 * 26.0);
  EXPECT_DOUBLE_EQ(m.pendulum_resolution_rad, pendulum);
  EXPECT_DOUBLE_EQ(m.arm_resolution_rad, arm);
  for (std::size_t k = 0; k < m.t_s.size(); ++k) {
    EXPECT_DOUBLE_EQ(m.t_s[k], 0.016 * static_cast<double>(k));
    // A whole number of counts, within half a count of the truth.
    EXPECT_NEAR(m.q2_rad[k] / pendulum, std::round(m.q2_rad[k] / pendulum), 1e-9);
    EXPECT_LE(std::abs(m.q2_rad[k] - m.q2_true_rad[k]), pendulum / 2 + 1e-15);
    EXPECT_NEAR(m.q1_rad[k] / arm, std::round(m.q1_rad[k] / arm), 1e-9);
    EXPECT_LE(std::abs(m.q1_rad[k] - m.q1_true_rad[k]), arm / 2 + 1e-15);
  }
  EXPECT_DOUBLE_EQ(m.q2_true_rad[0], -100 * kPi / 180);
  EXPECT_EQ(m.q1_true_rad[0], 0.0);
}

// Free decay (u = 0): friction only takes energy out, so the swing never exceeds its start and
// its peaks shrink; the half-period lies between the small-swing value with the arm free and,
// at this amplitude, the pendulum's with the arm clamped stretched by the large-swing factor.
TEST(ScenarioMeasurement, FreeDecayFollowsThePhysics) {
  const model::Parameters<double> p = model::paper_run1();
  for (const int n : {1, 2}) {
    const Scenario s = paper_scenario(n);
    const ScenarioMeasurement m = measure_scenario(s, p);
    const double start = std::abs(s.q2_initial_rad);
    std::vector<double> crossings, peaks;
    double peak = 0;
    for (std::size_t k = 1; k < m.t_s.size(); ++k) {
      const double a = m.q2_true_rad[k - 1], b = m.q2_true_rad[k];
      EXPECT_LE(std::abs(b), start + 1e-9) << "scenario " << n << " at " << m.t_s[k] << " s";
      peak = std::max(peak, std::abs(b));
      if ((a < 0) != (b < 0)) {
        crossings.push_back(m.t_s[k - 1] + 0.016 * a / (a - b));
        peaks.push_back(peak);
        peak = 0;
      }
    }
    ASSERT_GE(crossings.size(), 6u) << "scenario " << n;
    for (std::size_t i = 2; i < peaks.size(); ++i) EXPECT_LT(peaks[i], peaks[i - 1]);
    const double free_arm = kPi * std::sqrt((p.mu4 - p.mu3 * p.mu3 / p.mu1) / p.mug);
    const double clamped = kPi * std::sqrt(p.mu4 / p.mug);
    // Complete elliptic integral factor 2 K(sin(a/2)) / pi at the start's amplitude.
    const double k = std::sin(start / 2);
    const double stretch = 1 + k * k / 4 + 9 * std::pow(k, 4) / 64 + 25 * std::pow(k, 6) / 256 +
                           1225 * std::pow(k, 8) / 16384 + 0.05;
    for (std::size_t i = 1; i < crossings.size(); ++i) {
      const double half_period = crossings[i] - crossings[i - 1];
      EXPECT_GT(half_period, free_arm) << "scenario " << n;
      EXPECT_LT(half_period, clamped * stretch) << "scenario " << n;
    }
  }
}

// A constant torque drives the arm to the speed where viscous friction balances it (the pendulum's
// coupling averages out): q1 grows at about u / fv1.
TEST(ScenarioMeasurement, ConstantTorqueDrivesTheArmAtItsTerminalSpeed) {
  const model::Parameters<double> p = model::paper_run1();
  for (const int n : {3, 4}) {
    const Scenario s = paper_scenario(n);
    const ScenarioMeasurement m = measure_scenario(s, p);
    const double speed = (m.q1_true_rad.back() - m.q1_true_rad[125]) / (m.t_s.back() - m.t_s[125]);
    EXPECT_NEAR(speed, s.torque_nm / p.fv1, 0.15 * std::abs(s.torque_nm / p.fv1))
        << "scenario " << n;
  }
}

TEST(ScenarioMeasurement, BadOptionsAreRefused) {
  const model::Parameters<double> p = model::paper_run1();
  MeasurementOptions o;
  o.step_s = 0.003;  // 16 ms is not a whole number of 3 ms steps
  EXPECT_THROW(measure_scenario(paper_scenario(1), p, o), std::invalid_argument);
  o.step_s = 0;
  EXPECT_THROW(measure_scenario(paper_scenario(1), p, o), std::invalid_argument);
  Scenario s = paper_scenario(1);
  s.duration_s = -1;
  EXPECT_THROW(measure_scenario(s, p), std::invalid_argument);
  StateUncertainty u;
  u.q2_rad = -1e-3;
  EXPECT_THROW(initial_state_box(paper_scenario(1), u), std::invalid_argument);
}

TEST(ScenarioParameters, IntervalSetsWidenTheMusAndTakeTheFrictions) {
  const model::Parameters<double> p = model::paper_run1();
  const ParameterSet set = research::interval_parameters(
      "SIVIA", p, {12, 12, 10, 12, 15}, Interval(0.043012, 0.13002), Interval(0.000454, 0.001174));
  EXPECT_EQ(set.name, "SIVIA");
  EXPECT_LE(set.parameters.mu1.lo(), p.mu1 * 0.88);
  EXPECT_GE(set.parameters.mu1.hi(), p.mu1 * 1.12);
  EXPECT_NEAR(set.parameters.mu3.width(), 0.2 * p.mu3, 1e-12);
  EXPECT_NEAR(set.parameters.mug.width(), 0.3 * p.mug, 1e-12);
  EXPECT_EQ(set.parameters.fv1, Interval(0.043012, 0.13002));
  const ParameterSet point = point_parameters("LSMI", p);
  EXPECT_TRUE(point.parameters.fv2.is_point());
  EXPECT_EQ(point.parameters.fv2.lo(), p.fv2);
  EXPECT_THROW(
      research::interval_parameters("x", p, {-1, 0, 0, 0, 0}, Interval(0, 1), Interval(0, 1)),
      std::invalid_argument);
  EXPECT_THROW(
      research::interval_parameters("x", p, {0, 0, 0, 0, 0}, Interval::entire(), Interval(0, 1)),
      std::invalid_argument);
}

using ShortRun = furuta::testing::ShortScenarioRun;

// Every solution from x0 +- the uncertainty is in the tube: the true model's own samples, from
// the centre and from starts inside the box, are all covered, in both modes.
TEST_F(ShortRun, TubeHoldsTheTrueModelsSamples) {
  ASSERT_EQ(tubes().status, IntegrationResult::Status::ok) << tubes().reason;
  ASSERT_EQ(tubes().pieces.size(), 1u);
  EXPECT_DOUBLE_EQ(tubes().t_reached_s, 0.2);
  const model::Parameters<double> truth = model::paper_run1();
  for (const double offset : {0.0, 1.5e-3, -1.5e-3}) {
    Scenario start = scenario();
    start.q2_initial_rad += offset;
    MeasurementOptions fine;
    fine.sample_period_s = 0.004;  // more samples than the rig takes, to test more instants
    const ScenarioMeasurement m = measure_scenario(start, truth, fine);
    ASSERT_EQ(m.t_s.size(), 51u);
    for (const CoverageMode mode : {CoverageMode::step, CoverageMode::interpolated}) {
      for (const std::size_t component :
           {std::size_t{FurutaDynamics::q1}, std::size_t{FurutaDynamics::q2}}) {
        const std::vector<double>& y =
            component == FurutaDynamics::q1 ? m.q1_true_rad : m.q2_true_rad;
        const Coverage c = coverage(tubes().views(), component, m.t_s, y, mode);
        EXPECT_EQ(c.in_time, m.t_s.size());
        EXPECT_EQ(c.covered, m.t_s.size())
            << "offset " << offset << ", component " << component << ", " << to_string(mode);
      }
    }
  }
}

// The same tube against a model it does not hold (the pendulum started 0.01 rad outside the
// box): the coverage falls, so the check above can fail.
TEST_F(ShortRun, TubeMissesAStartOutsideItsBox) {
  Scenario outside = scenario();
  outside.q2_initial_rad += 0.01;
  const ScenarioMeasurement m = measure_scenario(outside, model::paper_run1());
  const Coverage c = coverage(tubes().views(), FurutaDynamics::q2, m.t_s, m.q2_true_rad,
                              CoverageMode::interpolated);
  EXPECT_LT(c.covered, c.measurements / 2);
}

// Table III, its JSON and Fig. 6 of this result: tests/report/scenario_outputs_test.cpp.
TEST_F(ShortRun, ResultCoverageAndWidths) {
  const ScenarioMeasurement m = measure_scenario(scenario(), model::paper_run1());
  const ParameterSet set = point_parameters("LSMI", model::paper_run1());
  const ScenarioResult r = evaluate_tubes(scenario(), set, {}, m, tubes());
  EXPECT_EQ(r.q2_step.measurements, m.t_s.size());
  EXPECT_EQ(r.q2_step.in_time, m.t_s.size());
  EXPECT_EQ(r.q2_tube.size(), tubes().steps);
  EXPECT_GT(r.q2_mean_width_rad, 0.0);
  EXPECT_LE(r.q2_mean_width_rad, r.q2_max_width_rad);
  // The x0 box is 3.2e-3 wide in q2: the tube can never be narrower than that at t = 0.
  EXPECT_GE(r.q2_max_width_rad, 3.2e-3);
  // Quantised samples: covered by the step test at least as often as by the interpolated one.
  EXPECT_GE(r.q2_step.covered, r.q2_interpolated.covered);
  ASSERT_EQ(r.q2_covered_step.size(), m.t_s.size());
  EXPECT_EQ(static_cast<std::size_t>(
                std::count(r.q2_covered_step.begin(), r.q2_covered_step.end(), true)),
            r.q2_step.covered);
}

// A tube that ends early: the samples past its end are counted apart (the figure's mark is
// report's test, tests/report/scenario_outputs_test.cpp).
TEST_F(ShortRun, EarlyEndIsReported) {
  Scenario longer = scenario();
  longer.duration_s = 0.8;
  const ScenarioMeasurement m = measure_scenario(longer, model::paper_run1());
  const ScenarioResult r =
      evaluate_tubes(longer, point_parameters("LSMI", model::paper_run1()), {}, m, tubes());
  EXPECT_DOUBLE_EQ(r.t_reached_s, 0.2);
  EXPECT_EQ(r.q2_step.outside_time, m.t_s.size() - r.q2_step.in_time);
  EXPECT_GT(r.q2_step.outside_time, 20u);
  EXPECT_LT(r.q2_step.rate(), r.q2_step.rate_in_time());
}

// A set known up to the drive's gain, through the Taylor-model flow: theta = p / g in a box, the
// torque times 1 / g's interval. Every rig (g theta, any g in the gain's interval, theta at a
// corner of the box) under the scenario's torque is inside the tube at every sample, in both
// modes; a rig whose gain is outside the interval is not, so the check can fail.
TEST(ScenarioTaylorModels, ARigKnownUpToItsGainIsInsideTheTube) {
  Scenario scenario = paper_scenario(3);  // -90 deg, 0.17 N m
  scenario.duration_s = 0.3;
  const model::Parameters<double> rig = model::paper_run1();
  const Interval gain(7.0, 7.4);
  model::Parameters<double> theta = rig;
  for (double* x :
       {&theta.mu1, &theta.mu2, &theta.mu3, &theta.mu4, &theta.mug, &theta.fv1, &theta.fv2}) {
    *x /= gain.mid();
  }
  ParameterSet set;
  set.name = "per gain";
  set.parameters = parameters_around(theta, 1e-3);
  set.torque_scale = Interval(1.0) / gain;
  const ScenarioTubes tubes =
      run_scenario_taylor_models(scenario, set, {}, scenario_taylor_model_options());
  ASSERT_EQ(tubes.status, IntegrationResult::Status::ok) << tubes.reason;
  ASSERT_EQ(tubes.pieces.size(), 1U);
  ASSERT_EQ(tubes.initial.size(), FurutaRampedDynamics::dimension);
  EXPECT_GT(tubes.steps, 20U);

  MeasurementOptions fine;
  fine.sample_period_s = 0.004;
  const auto rig_at = [&](unsigned corner, double g) {
    const std::array<Interval, 7> box{set.parameters.mu1, set.parameters.mu2, set.parameters.mu3,
                                      set.parameters.mu4, set.parameters.mug, set.parameters.fv1,
                                      set.parameters.fv2};
    std::array<double, 7> v{};
    for (std::size_t i = 0; i < 7; ++i) v[i] = g * ((corner >> i) & 1U ? box[i].hi() : box[i].lo());
    return model::Parameters<double>{v[0], v[1], v[2], v[3], v[4], v[5], v[6]};
  };
  const auto covered = [&](const model::Parameters<double>& p, double q2_offset) {
    Scenario start = scenario;
    start.q2_initial_rad += q2_offset;
    const ScenarioMeasurement m = measure_scenario(start, p, fine);
    std::size_t n = 0;
    for (const CoverageMode mode : {CoverageMode::step, CoverageMode::interpolated}) {
      n += coverage(tubes.views(), FurutaDynamics::q1, m.t_s, m.q1_true_rad, mode).covered;
      n += coverage(tubes.views(), FurutaDynamics::q2, m.t_s, m.q2_true_rad, mode).covered;
    }
    return std::pair{n, 4 * m.t_s.size()};
  };
  std::size_t checks = 0;
  for (unsigned corner = 0; corner < 128; ++corner) {
    for (const double g : {gain.lo(), gain.hi()}) {
      for (const double offset : {-1.5e-3, 1.5e-3}) {
        const auto [n, all] = covered(rig_at(corner, g), offset);
        EXPECT_EQ(n, all) << "corner " << corner << ", gain " << g << ", q2 offset " << offset;
        checks += all;
      }
    }
  }
  EXPECT_GT(checks, 50000U);
  std::printf(
      "[ measured ] scenario (c) per unit of gain, 0.3 s: %zu checks of q1 and q2, %.1f s\n",
      checks, tubes.seconds);
  const auto [n, all] = covered(rig_at(0, 1.1 * gain.hi()), 0.0);
  EXPECT_LT(n, all * 3 / 4) << "a gain 10 % outside the interval";
}

}  // namespace
}  // namespace furuta::validated
