// The balance law on the nonlinear model, without the boards: from rest hanging down it swings the
// pendulum up, catches and holds it; a push it cannot take ends in a fall with the duty at zero;
// its modes follow the catch region's hysteresis; a spec out of range is refused by a
// BalanceSpecError naming its path in the spec, so a file's reader can point at the key. The
// daemon's sessions (tests/daemon, tests/app) run the same law against the simulated rig.
#include "furuta/control/balance_law.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "furuta/control/upright_lqr.hpp"
#include "furuta/model/duty_ramp.hpp"
#include "furuta/model/model.hpp"
#include "simulated_rig.hpp"

namespace furuta::control::balance_law_test {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180;

using Rig = testing::SimulatedRig;
using testing::simulated_rig;

// The law for `design` parameters with a 2 ms lag, as `furuta controller design` makes it: at
// 16 ms unless told, the filter's gain for angles read half a board report (4 ms) before a sample.
BalanceControllerSpec spec_for(const Rig& rig, const model::Parameters<double>& design,
                               double period_s = 0.016) {
  constexpr double kLag = 0.002;
  const DesignPlant plant{design, rig.motor, rig.supply_v};
  const SampledPlant sampled = sample(linearize_upright(plant), period_s, kLag);
  ObserverWeights filter;
  filter.arm_count_rad = 2 * kPi / (1024.0 * rig.motor.total_ratio());
  filter.pendulum_count_rad = 2 * kPi / 4096.0;
  filter.reading_age_s = 0.004;
  return balance_spec(plant, sampled, design_lqr(sampled, LqrWeights{}),
                      design_observer(sampled, filter), DutyPath{kLag, 62.5}, 0.5, 1.0 / 255);
}

struct Outcome {
  std::optional<double> balanced_at_s;
  std::optional<double> fell_at_s;
  double upright_rms_deg = 0;          // over the balance mode's cycles after a second of it
  double duty_rms = 0;                 // over the same cycles
  double pendulum_rate_error_rms = 0;  // the law's dq2 against the truth, same cycles
  double max_arm_deg = 0;
  double final_duty = 0;
};

// When the law's angles were read: this long before each sample (whole 0.1 ms steps), and a
// board that reports every `every` samples only (the others leave its angle as it was).
struct Readings {
  double arm_age_s = 0;
  double pendulum_age_s = 0;
  int pendulum_every = 1;
};

// The closed loop: the pendulum integrated at 0.1 ms, the encoders' counts (4096 per pendulum
// turn, 1024 per motor-shaft turn before 26:1 gears), each duty reaching the board 2 ms after its
// sample and ramped there at 62.5 duty/s. `tap_at_s`: an impulse on the pendulum (N m s).
Outcome run(const Rig& rig, const BalanceControllerSpec& spec, double seconds, double tap_at_s = -1,
            double tap_nm_s = 0, const Readings& readings = {}) {
  BalanceLaw law(spec);
  model::PendulumState x{};
  model::DutyRamp ramp;
  constexpr double h = 1e-4;
  const int substeps = static_cast<int>(std::lround(spec.period_s / h));
  const double arm_count = 2 * kPi / (1024.0 * rig.motor.total_ratio());
  const double pendulum_count = 2 * kPi / 4096.0;
  const double scale = rig.supply_v / rig.motor.nominal_voltage_v;
  Outcome out;
  double sum2 = 0;
  double duty2 = 0;
  double rate2 = 0;
  int n = 0;
  double t = 0;
  bool tapped = false;
  const int arm_read_at = substeps - static_cast<int>(std::lround(readings.arm_age_s / h));
  const int pendulum_read_at =
      substeps - static_cast<int>(std::lround(readings.pendulum_age_s / h));
  double arm_read = 0;
  double pendulum_read = 0;
  for (int k = 0; t < seconds; ++k) {
    if (readings.arm_age_s == 0) arm_read = std::floor(x.q1 / arm_count) * arm_count;
    const bool pendulum_fresh = k % readings.pendulum_every == 0;
    if (readings.pendulum_age_s == 0 && pendulum_fresh) {
      pendulum_read = std::floor(x.q2 / pendulum_count) * pendulum_count;
    }
    ReadingTimes times;
    times.arm_age_s = readings.arm_age_s;
    times.pendulum_age_s = readings.pendulum_age_s;
    times.pendulum_fresh = pendulum_fresh;
    const BalanceStep step = law.step(arm_read, pendulum_read, times);
    out.final_duty = step.duty;
    if (step.mode == BalanceMode::fallen && !out.fell_at_s) out.fell_at_s = t;
    if (step.mode == BalanceMode::balance) {
      if (!out.balanced_at_s) out.balanced_at_s = t;
      if (t > *out.balanced_at_s + 1) {
        sum2 += step.upright_error_rad * step.upright_error_rad;
        duty2 += step.duty * step.duty;
        rate2 += (step.pendulum_rate_rad_s - x.dq2) * (step.pendulum_rate_rad_s - x.dq2);
        ++n;
      }
    }
    for (int j = 0; j < substeps; ++j, t += h) {
      if (j == arm_read_at) arm_read = std::floor(x.q1 / arm_count) * arm_count;
      if (j == pendulum_read_at && (k + 1) % readings.pendulum_every == 0) {
        pendulum_read = std::floor(x.q2 / pendulum_count) * pendulum_count;
      }
      if (j == 20) ramp.command(step.duty, 62.5);  // 2 ms after the sample
      if (tap_at_s >= 0 && !tapped && t >= tap_at_s) {
        tapped = true;
        const auto m = model::mass_matrix(rig.truth, x.q2);
        const double det = m.m11 * m.m22 - m.m12 * m.m12;
        x.dq1 += -m.m12 / det * tap_nm_s;
        x.dq2 += m.m11 / det * tap_nm_s;
      }
      const double u = ramp.advance(h) * scale;
      x = model::rk4_step(rig.truth, x, h, [&](const model::PendulumState& s) {
        return rig.motor.arm_torque(u, s.dq1);
      });
    }
    out.max_arm_deg = std::max(out.max_arm_deg, std::fabs(x.q1) / kDeg);
  }
  out.upright_rms_deg = n > 0 ? std::sqrt(sum2 / n) / kDeg : 0;
  out.duty_rms = n > 0 ? std::sqrt(duty2 / n) : 0;
  out.pendulum_rate_error_rms = n > 0 ? std::sqrt(rate2 / n) : 0;
  return out;
}

TEST(BalanceLaw, SwingsUpFromRestCatchesAndHoldsTheTruePendulum) {
  const Rig rig = simulated_rig();
  const Outcome o = run(rig, spec_for(rig, rig.truth), 30);
  ASSERT_TRUE(o.balanced_at_s.has_value());
  EXPECT_LT(*o.balanced_at_s, 10.0);
  EXPECT_FALSE(o.fell_at_s.has_value());
  EXPECT_LT(o.upright_rms_deg, 1.0);
  EXPECT_GT(o.upright_rms_deg, 0.0);  // the encoders' counts leave a residue: it is measured
  EXPECT_LT(o.max_arm_deg, 150.0);    // the configuration's arm limit
  // Held with the filter's velocities: no ringing at the sampling's Nyquist rate, which a
  // difference's half-period lag excites against an arm that follows its duty within a period.
  EXPECT_LT(o.duty_rms, 0.01);
  // A count of the pendulum's encoder over a period is 0.1 rad/s: the filter does far better.
  EXPECT_LT(o.pendulum_rate_error_rms, 0.04);
}

// The boards' reports reach the loop up to one of their periods (8 ms) before a sample: the filter
// compares each angle with the model's at the instant it was read. At 8 ms, the boards' own
// report period, a gain for angles read at the sample rang and fell within a second.
TEST(BalanceLaw, HoldsTheTruePendulumWithAnglesReadBeforeTheSample) {
  const Rig rig = simulated_rig();
  for (const double period_s : {0.016, 0.008}) {
    const BalanceControllerSpec spec = spec_for(rig, rig.truth, period_s);
    for (const double age_s : {0.0, 0.004, 0.008}) {
      SCOPED_TRACE(::testing::Message() << "period " << period_s << " s, angles read " << age_s
                                        << " s (arm) and " << age_s / 2 << " s (pendulum) before");
      const Outcome o = run(rig, spec, 20, -1, 0, {age_s, age_s / 2});
      ASSERT_TRUE(o.balanced_at_s.has_value());
      EXPECT_FALSE(o.fell_at_s.has_value());
      EXPECT_LT(o.upright_rms_deg, 1.0);
      EXPECT_LT(o.duty_rms, 0.01);
      EXPECT_LT(o.pendulum_rate_error_rms, 0.06);
    }
  }
}

// A board that reports every other sample: the cycles without its report predict its angle from
// the model rather than take the old one as new.
TEST(BalanceLaw, HoldsWhenTheEncoderBoardReportsEveryOtherSample) {
  const Rig rig = simulated_rig();
  const BalanceControllerSpec spec = spec_for(rig, rig.truth, 0.008);
  const Outcome o = run(rig, spec, 20, -1, 0, {0.007, 0.004, 2});
  ASSERT_TRUE(o.balanced_at_s.has_value());
  EXPECT_FALSE(o.fell_at_s.has_value());
  EXPECT_LT(o.upright_rms_deg, 1.0);
  EXPECT_LT(o.duty_rms, 0.01);
}

// Inside the catch angle, the catch comes only where the gain asks for at most entry_duty_ratio of
// max_duty: a pendulum coming up at the pace the gain expects is caught; the same angle at rest,
// or passed at speed, would drive the duty to its limit and the arm to its own, and the swing goes
// on.
// start_catch: the law takes over as if it had just caught, its filter at the estimate given: the
// gain on it (rounded to a duty step) is the first duty, then each cycle filters the angles read.
TEST(BalanceLaw, StartCatchSendsTheGainOnTheEstimateThenFilters) {
  const Rig rig = simulated_rig();
  const BalanceControllerSpec spec = spec_for(rig, rig.truth);
  BalanceLaw law(spec);
  const std::array<double, 4> estimate{0.01, 2 * kDeg, -0.1, 0.2};
  const BalanceStep first = law.start_catch(estimate);
  double gain_duty = 0;
  for (std::size_t i = 0; i < 4; ++i) gain_duty -= spec.gain[i] * estimate[i];
  EXPECT_EQ(first.mode, BalanceMode::catching);
  EXPECT_NEAR(first.duty, std::round(gain_duty / spec.duty_step) * spec.duty_step, 1e-15);
  EXPECT_DOUBLE_EQ(first.pendulum_rate_rad_s, 0.2);
  // The next cycle corrects the estimate with the angles (here the estimate's own, carried): it
  // stays in the catch, its rates the filter's, not a difference of the angles over the period.
  const BalanceStep next = law.step(estimate[0], kPi + estimate[1]);
  EXPECT_EQ(next.mode, BalanceMode::catching);
  EXPECT_NE(next.pendulum_rate_rad_s, 0.0);
  EXPECT_LT(std::fabs(next.duty), spec.max_duty);
  // Reset and started again, the same first duty: start_catch starts from nothing of before.
  EXPECT_EQ(law.start_catch(estimate).duty, first.duty);
}

TEST(BalanceLaw, CatchesOnlyWhereTheGainAsksForPartOfTheDuty) {
  const Rig rig = simulated_rig();
  BalanceControllerSpec spec = spec_for(rig, rig.truth);
  spec.gain.fill(0.0);
  spec.gain[1] = 1.0;  // duty = -(error + 0.1 dq2): 0 coming up at 10 error/s
  spec.gain[3] = 0.1;
  const double t = spec.period_s;
  const double error = 0.3;  // inside the catch angle
  const auto mode_after = [&](double previous_error) {
    BalanceLaw law(spec);
    law.step(0, kPi + previous_error);
    return law.step(0, kPi + error).mode;
  };
  EXPECT_EQ(mode_after(error + 10 * error * t), BalanceMode::catching);  // at the gain's pace
  EXPECT_EQ(mode_after(error), BalanceMode::swing_up);                   // at rest: duty -0.3
  EXPECT_EQ(mode_after(error + 20 * t), BalanceMode::swing_up);          // at 20 rad/s: 1.7
  spec.region.entry_duty_ratio = 1.0;                                    // up to the limit
  EXPECT_EQ(mode_after(error), BalanceMode::catching);
}

TEST(BalanceLaw, RecoversFromASmallTapAndFallsCleanlyFromALargeOne) {
  const Rig rig = simulated_rig();
  const BalanceControllerSpec spec = spec_for(rig, rig.truth);
  const Outcome small = run(rig, spec, 20, 12.0, 2e-3);
  ASSERT_TRUE(small.balanced_at_s.has_value());
  ASSERT_LT(*small.balanced_at_s, 12.0);
  EXPECT_FALSE(small.fell_at_s.has_value());
  const Outcome large = run(rig, spec, 20, 12.0, 30e-3);
  ASSERT_TRUE(large.fell_at_s.has_value());
  EXPECT_GT(*large.fell_at_s, 12.0);
  EXPECT_EQ(large.final_duty, 0.0);  // fallen is final: nothing more is driven
}

TEST(BalanceLaw, ModesFollowTheCatchRegionWithHysteresis) {
  const Rig rig = simulated_rig();
  BalanceControllerSpec spec = spec_for(rig, rig.truth);
  spec.region.settle_s = 0.032;  // two periods
  spec.gain.fill(0.0);           // the gain's duty never keeps the catch out (the next test)
  BalanceLaw law(spec);
  const double catch_in = kPi - 0.9 * spec.region.catch_rad;
  const double between = kPi - 0.5 * (spec.region.catch_rad + spec.region.release_rad);
  const double beyond = kPi - 1.1 * spec.region.release_rad;
  EXPECT_EQ(law.step(0, 0.1).mode, BalanceMode::swing_up);
  EXPECT_EQ(law.step(0, catch_in).mode, BalanceMode::catching);
  EXPECT_EQ(law.step(0, between).mode, BalanceMode::catching);  // inside the release angle
  EXPECT_EQ(law.step(0, beyond).mode, BalanceMode::swing_up);
  EXPECT_EQ(law.step(0, catch_in).mode, BalanceMode::catching);
  EXPECT_EQ(law.step(0, catch_in).mode, BalanceMode::catching);
  EXPECT_EQ(law.step(0, catch_in).mode, BalanceMode::balance);  // settle_s inside
  EXPECT_EQ(law.step(0, kPi - 1.1 * spec.region.fall_rad).mode, BalanceMode::fallen);
  const BalanceStep after = law.step(0, kPi);
  EXPECT_EQ(after.mode, BalanceMode::fallen);
  EXPECT_EQ(after.duty, 0.0);
  law.reset();
  EXPECT_EQ(law.step(0, kPi).mode, BalanceMode::catching);
}

TEST(BalanceLaw, DutiesAreWholeStepsWithinTheLimit) {
  const Rig rig = simulated_rig();
  BalanceControllerSpec spec = spec_for(rig, rig.truth);
  spec.max_duty = 0.3;
  spec.swing_up.max_duty = 0.3;
  BalanceLaw law(spec);
  law.step(0, kPi);
  for (const double q2 : {kPi - 0.3, kPi + 0.3, kPi - 0.01, kPi + 0.2}) {
    const double duty = law.step(0.5, q2).duty;
    EXPECT_LE(std::fabs(duty), 0.3);
    EXPECT_NEAR(duty * 255, std::round(duty * 255), 1e-9);
  }
}

// A spec the law accepts: the defaults with a model and a drive.
BalanceControllerSpec valid_spec() {
  BalanceControllerSpec s;
  s.parameters = {
      .mu1 = 4e-3, .mu2 = 1e-3, .mu3 = 2e-3, .mu4 = 1.5e-3, .mug = 0.1, .fv1 = 1e-3, .fv2 = 1e-5};
  s.gain = {-1, 30, -1.5, 3, 0.2};
  s.delayed = 1;
  s.duty_torque_nm = 0.5;
  s.back_emf_nm_s = 0.05;
  return s;
}

TEST(BalanceLaw, EachFieldOutOfRangeIsNamedByItsPathInTheSpec) {
  EXPECT_NO_THROW(BalanceLaw{valid_spec()});
  const std::vector<std::pair<std::string, std::function<void(BalanceControllerSpec&)>>> cases = {
      {"period_s", [](auto& s) { s.period_s = 0; }},
      {"delayed", [](auto& s) { s.delayed = kMaxDelayedDuties + 1; }},
      {"gain", [](auto& s) { s.gain[6] = 1; }},
      {"max_duty", [](auto& s) { s.max_duty = 1.5; }},
      {"duty_step", [](auto& s) { s.duty_step = 0; }},
      {"parameters.mu4", [](auto& s) { s.parameters.mu4 = -1; }},
      {"parameters.fv2", [](auto& s) { s.parameters.fv2 = -1; }},
      {"duty_torque_nm", [](auto& s) { s.duty_torque_nm = 0; }},
      {"back_emf_nm_s", [](auto& s) { s.back_emf_nm_s = -1; }},
      {"swing_up.energy_gain", [](auto& s) { s.swing_up.energy_gain = -1; }},
      {"swing_up.start_acceleration",
       [](auto& s) { s.swing_up.start_acceleration = 2 * s.swing_up.max_acceleration; }},
      {"swing_up.max_duty", [](auto& s) { s.swing_up.max_duty = s.max_duty + 0.1; }},
      {"region.catch_rad", [](auto& s) { s.region.catch_rad = std::numbers::pi; }},
      {"region.release_rad", [](auto& s) { s.region.release_rad = s.region.catch_rad; }},
      {"region.settle_s", [](auto& s) { s.region.settle_s = -1; }},
      {"region.fall_rad", [](auto& s) { s.region.fall_rad = 0.5 * s.region.catch_rad; }},
      {"region.entry_duty_ratio", [](auto& s) { s.region.entry_duty_ratio = 0; }},
      {"swing_up.pump_arm_rad", [](auto& s) { s.swing_up.pump_arm_rad = 4.0; }},
      {"duty_path.lag_s", [](auto& s) { s.duty_path.lag_s = (s.delayed + 1) * s.period_s; }},
      {"duty_path.ramp_duty_per_s", [](auto& s) { s.duty_path.ramp_duty_per_s = -1; }},
      {"a_continuous", [](auto& s) { s.a_continuous[3] = std::nan(""); }},
  };
  for (const auto& [field, spoil] : cases) {
    BalanceControllerSpec s = valid_spec();
    spoil(s);
    try {
      BalanceLaw law(s);
      ADD_FAILURE() << field << " accepted";
    } catch (const BalanceSpecError& e) {
      EXPECT_EQ(e.field(), field);
      EXPECT_EQ(std::string(e.what()), "balance controller: " + field + " " + e.rule());
      EXPECT_FALSE(e.rule().empty());
    }
  }
}

}  // namespace
}  // namespace furuta::control::balance_law_test
