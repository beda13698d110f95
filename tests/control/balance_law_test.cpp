// The balance law on the nonlinear model, without the boards: from rest hanging down it swings the
// pendulum up, catches and holds it; a push it cannot take ends in a fall with the duty at zero;
// its modes follow the catch region's hysteresis; a spec out of range is refused by a
// BalanceSpecError naming its path in the spec, so a file's reader can point at the key. The
// daemon's sessions (tests/daemon, tests/app) run the same law against the simulated rig.
#include "furuta/control/balance_law.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "furuta/config/rig_config.hpp"
#include "furuta/control/upright_lqr.hpp"
#include "furuta/model/duty_ramp.hpp"
#include "furuta/model/model.hpp"

namespace furuta::control::balance_law_test {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180;

struct Rig {
  model::Parameters<double> truth;
  model::MotorData motor;
  double supply_v = 12;
};

Rig simulated_rig() {
  const config::RigConfig rig = config::load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
  return {rig.simulation.parameters, rig.simulation.motor, rig.simulation.supply_voltage_v};
}

// The law for `design` parameters at 16 ms with a 2 ms lag, as `furuta controller design` makes it.
BalanceControllerSpec spec_for(const Rig& rig, const model::Parameters<double>& design) {
  constexpr double kPeriod = 0.016;
  constexpr double kLag = 0.002;
  const DesignPlant plant{design, rig.motor, rig.supply_v};
  const SampledPlant sampled = sample(linearize_upright(plant), kPeriod, kLag);
  ObserverWeights filter;
  filter.arm_count_rad = 2 * kPi / (1024.0 * rig.motor.total_ratio());
  filter.pendulum_count_rad = 2 * kPi / 4096.0;
  return balance_spec(plant, sampled, design_lqr(sampled, LqrWeights{}),
                      design_observer(sampled, filter), 0.5, 1.0 / 255);
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

// The closed loop: the pendulum integrated at 0.1 ms, the encoders' counts (4096 per pendulum
// turn, 1024 per motor-shaft turn before 26:1 gears), each duty reaching the board 2 ms after its
// sample and ramped there at 62.5 duty/s. `tap_at_s`: an impulse on the pendulum (N m s).
Outcome run(const Rig& rig, const BalanceControllerSpec& spec, double seconds, double tap_at_s = -1,
            double tap_nm_s = 0) {
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
  for (int k = 0; t < seconds; ++k) {
    const BalanceStep step = law.step(std::floor(x.q1 / arm_count) * arm_count,
                                      std::floor(x.q2 / pendulum_count) * pendulum_count);
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

TEST(BalanceLaw, ControllersFromTheCadValuesBalanceTheTruePendulumToo) {
  const Rig rig = simulated_rig();
  const config::RigConfig config = config::load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
  ASSERT_TRUE(config.nominal.has_value());
  model::Parameters<double> cad = *config.nominal;
  cad.fv1 = rig.truth.fv1;  // CAD has no friction: the design takes the identified values'
  cad.fv2 = rig.truth.fv2;
  const Outcome o = run(rig, spec_for(rig, cad), 30);
  ASSERT_TRUE(o.balanced_at_s.has_value());
  EXPECT_LT(o.upright_rms_deg, 1.0);
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
