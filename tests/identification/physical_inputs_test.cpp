// The physical inputs of the guaranteed identification: every input encloses what the
// simulated rig really does, the scaled parameters map both ways, and each input says where it
// came from.
#include "furuta/identification/physical_inputs.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <set>
#include <vector>

#include "furuta/config/rig_config.hpp"

namespace furuta::identification {
namespace {

config::RigConfig shipped_rig() {
  return config::load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
}

// The 1065's readings as the simulated rig makes them: the supply plus noise, in steps of
// 80/2048 V.
std::vector<double> supply_readings(const config::RigConfig& rig, std::size_t count) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, rig.simulation.supply_noise_v);
  const double step = 80.0 / 2048.0;
  std::vector<double> out;
  for (std::size_t i = 0; i < count; ++i) {
    out.push_back(std::round((rig.simulation.supply_voltage_v + noise(rng)) / step) * step);
  }
  return out;
}

TEST(PhysicalInputs, TheSimulatedRigsTruthIsInsideEveryInput) {
  const config::RigConfig rig = shipped_rig();
  const PhysicalInputs in = physical_inputs(rig, supply_readings(rig, 1250));
  const model::MotorData& m = rig.motor;
  const double g = m.arm_torque_nm(rig.simulation.supply_voltage_v / m.nominal_voltage_v, 0.0);
  const double k_w = -m.arm_torque_nm(0.0, 1.0);
  EXPECT_TRUE(in.drive.gain_nm().contains(g)) << in.drive.gain_nm().lo() << " " << g;
  EXPECT_TRUE(in.drive.back_emf_damping_nm_s().contains(k_w));
  EXPECT_TRUE(in.supply_v.contains(rig.simulation.supply_voltage_v));
  // 1 % on each data-sheet figure: k_w has three (Rv and the two efficiencies), g four (and
  // omega0) and the supply readings' range (+-3.4 sd of their 0.05 V noise over 1,250 readings).
  EXPECT_NEAR(in.drive.back_emf_damping_nm_s().width() / k_w, 0.06, 0.002);
  EXPECT_GT(in.drive.gain_nm().width() / g, 0.08 + 2 * 3 * 0.05 / 12);
  EXPECT_LT(in.drive.gain_nm().width() / g, 0.08 + 2 * 4 * 0.05 / 12);

  const model::Parameters<double> truth = rig.simulation.parameters;
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    EXPECT_TRUE(in.prior[k].contains(truth[k])) << k;
  }
  EXPECT_DOUBLE_EQ(in.prior.mu1.hi() / rig.nominal->mu1, 1.5);
  EXPECT_EQ(in.prior.fv2.lo(), 0.0);

  const double arm_count = 2 * std::numbers::pi / (1024 * m.total_ratio());
  const double pendulum_count = 2 * std::numbers::pi / 4096;
  EXPECT_NEAR(in.arm_angle_error_rad.width(), arm_count, 1e-15);
  EXPECT_NEAR(in.pendulum_angle_error_rad.hi(), pendulum_count / 2, 1e-15);
  EXPECT_NEAR(in.pendulum_zero_rad.hi(), 2.5 * pendulum_count, 1e-15);
  EXPECT_NEAR(in.duty_error.hi(), 0.5 / 255, 1e-15);
  EXPECT_EQ(in.lag_s.lo(), 0.0);
  EXPECT_NEAR(in.lag_s.hi(), 2e-3, 1e-15);
}

// theta = p / g (b = (fv1 + k_w) / g) and back: sound both ways, and no rig parameter's interval
// is narrower than the drive gain's relative width.
TEST(PhysicalInputs, ScaledParametersMapBothWaysAndTheGainSetsTheFloor) {
  const config::RigConfig rig = shipped_rig();
  const PhysicalInputs in = physical_inputs(rig, supply_readings(rig, 200));
  const model::Parameters<double> truth = rig.simulation.parameters;
  const model::MotorData& m = rig.motor;
  const double g = m.arm_torque_nm(1.0, 0.0);
  const double k_w = -m.arm_torque_nm(0.0, 1.0);

  const model::Parameters<Interval> point = truth.map([](double v) { return Interval(v); });
  const model::Parameters<Interval> theta = scaled_parameters(point, in.drive);
  EXPECT_TRUE(theta.mu1.contains(truth.mu1 / g));
  EXPECT_TRUE(theta.fv1.contains((truth.fv1 + k_w) / g));
  // The scaled truth, known exactly, maps back onto intervals that hold the truth and are at
  // least as wide as the gain.
  const model::Parameters<double> exact{truth.mu1 / g, truth.mu2 / g, truth.mu3 / g,
                                        truth.mu4 / g, truth.mug / g, (truth.fv1 + k_w) / g,
                                        truth.fv2 / g};
  const model::Parameters<Interval> back =
      rig_parameters(exact.map([](double v) { return Interval(v); }), in.drive);
  const double gain_relative = in.drive.gain_nm().width() / in.drive.gain_nm().mid();
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    EXPECT_TRUE(back[k].contains(truth[k])) << k;
    if (k != 5) {
      EXPECT_GE(back[k].width() / truth[k], 0.99 * gain_relative) << k;
    }
  }
  // fv1 = b g - k_w = F N (b omega0_s - N 60 / 2 pi): a difference of two large terms, so wider
  // relatively than the gain; F's tolerance (3 %) counts once, not in both terms (which would
  // give about 27 % here instead of about 16 %).
  EXPECT_GT(back.fv1.width() / truth.fv1, gain_relative);
  EXPECT_LT(back.fv1.width() / truth.fv1, 0.2);
  const Interval independent =
      Interval(exact.fv1) * in.drive.gain_nm() - in.drive.back_emf_damping_nm_s();
  EXPECT_LT(back.fv1.width(), 0.8 * independent.width());
  std::printf(
      "[ measured ] from the exact scaled truth: mu's %.1f %% wide, fv1 %.1f %% (%.1f %% with "
      "g and k_w independent)\n",
      100 * back.mu1.width() / truth.mu1, 100 * back.fv1.width() / truth.fv1,
      100 * independent.width() / truth.fv1);
  // The prior maps into the scaled prior.
  const model::Parameters<Interval> scaled_prior = scaled_parameters(in.prior, in.drive);
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    EXPECT_TRUE(scaled_prior[k].contains(exact[k])) << k;
  }
}

// Per unit of the gain: the rig's parameters over its gain, p / g, are inside what the scaled
// truth gives for every drive (the simulated rig's own drive among them), far narrower than the
// rig parameters themselves; a b with the back-EMF's part left in would not hold fv1 / g.
TEST(PhysicalInputs, PerUnitOfGainTheScaledSetHoldsTheRigOverItsGain) {
  const config::RigConfig rig = shipped_rig();
  const PhysicalInputs in = physical_inputs(rig, supply_readings(rig, 200));
  const model::Parameters<double> truth = rig.simulation.parameters;
  const model::MotorData& m = rig.motor;
  const double g = m.arm_torque_nm(rig.simulation.supply_voltage_v / m.nominal_voltage_v, 0.0);
  const double k_w = -m.arm_torque_nm(0.0, 1.0);
  const model::Parameters<double> exact{truth.mu1 / g, truth.mu2 / g, truth.mu3 / g,
                                        truth.mu4 / g, truth.mug / g, (truth.fv1 + k_w) / g,
                                        truth.fv2 / g};
  const model::Parameters<Interval> per_gain =
      rig_parameters_per_gain(exact.map([](double v) { return Interval(v); }), in.drive);
  const model::Parameters<Interval> rig_set =
      rig_parameters(exact.map([](double v) { return Interval(v); }), in.drive);
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    EXPECT_TRUE(per_gain[k].contains(truth[k] / g)) << k;
    if (k != 5) {
      EXPECT_EQ(per_gain[k], Interval(exact[k])) << k;
    }
  }
  EXPECT_FALSE(Interval(exact.fv1).contains(truth.fv1 / g));
  EXPECT_LT(per_gain.fv1.width() / per_gain.fv1.mid(), 0.5 * rig_set.fv1.width() / truth.fv1);
  EXPECT_TRUE((Interval(1.0) / in.drive.gain_nm()).contains(1.0 / g));
}

TEST(PhysicalInputs, EveryInputSaysWhereItCameFrom) {
  const config::RigConfig rig = shipped_rig();
  const PhysicalInputs in = physical_inputs(rig, supply_readings(rig, 10));
  std::set<std::string> quantities;
  for (const PhysicalInput& p : in.provenance) {
    EXPECT_FALSE(p.setting.empty()) << p.quantity;
    EXPECT_FALSE(p.unit.empty()) << p.quantity;
    EXPECT_TRUE(p.value.is_bounded()) << p.quantity;
    EXPECT_TRUE(quantities.insert(p.quantity).second) << p.quantity << " twice";
  }
  const auto source_of = [&](const std::string& quantity) {
    for (const PhysicalInput& p : in.provenance) {
      if (p.quantity == quantity) return p.source;
    }
    ADD_FAILURE() << quantity << " missing";
    return InputSource::configured;
  };
  EXPECT_EQ(source_of("arm_angle_error"), InputSource::encoder_counts);
  EXPECT_EQ(source_of("pendulum_zero"), InputSource::rest_check);
  EXPECT_EQ(source_of("duty_error"), InputSource::duty_steps);
  EXPECT_EQ(source_of("supply"), InputSource::supply_readings);
  EXPECT_EQ(source_of("drive_gain"), InputSource::data_sheet);
  EXPECT_EQ(source_of("lag"), InputSource::configured);
  EXPECT_EQ(source_of("prior_mu3"), InputSource::cad);
  EXPECT_EQ(source_of("prior_fv1"), InputSource::configured);
  EXPECT_EQ(quantities.size(), 8U + model::kParameterCount);
}

TEST(PhysicalInputs, WhatCannotBeBoundedIsRefusedWithTheReason) {
  config::RigConfig rig = shipped_rig();
  const std::vector<double> readings = {12.0};
  EXPECT_THROW((void)physical_inputs(rig, {}), std::invalid_argument);
  const std::vector<double> broken = {12.0, std::numeric_limits<double>::quiet_NaN()};
  EXPECT_THROW((void)physical_inputs(rig, broken), std::invalid_argument);
  rig.nominal.reset();
  try {
    (void)physical_inputs(rig, readings);
    ADD_FAILURE() << "no error without [nominal]";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("[nominal]"), std::string::npos) << e.what();
  }
}

// A recording's own bounds (a CSV's import spec) replace the daemon's: each is taken as stated,
// with its provenance; without supply readings the stated supply is the supply, and the drive's
// gain follows it.
TEST(PhysicalInputs, ARecordingsStatedBoundsReplaceTheDaemons) {
  const config::RigConfig rig = shipped_rig();
  RecordingBounds b = session_log_bounds(rig);
  const auto stated = [](const char* quantity, double lo, double hi, const char* unit) {
    return PhysicalInput{quantity, Interval(lo, hi), unit, InputSource::import_spec,
                         "spec.toml:9 guaranteed.x"};
  };
  b.arm_angle_error = stated("arm_angle_error", -1e-3, 1e-3, "rad");
  b.lag = stated("lag", 0.5e-3, 4e-3, "s");
  b.supply = stated("supply", 11.0, 13.0, "V");
  const PhysicalInputs in = physical_inputs(rig, {}, b);
  EXPECT_EQ(in.arm_angle_error_rad.hi(), 1e-3);
  EXPECT_EQ(in.lag_s.lo(), 0.5e-3);
  EXPECT_EQ(in.supply_v.lo(), 11.0);
  EXPECT_EQ(in.pendulum_zero_rad.hi(), session_log_bounds(rig).pendulum_zero.value.hi());
  const PhysicalInputs from_readings = physical_inputs(rig, supply_readings(rig, 100));
  EXPECT_GT(in.drive.gain_nm().width(), 2 * from_readings.drive.gain_nm().width());
  std::size_t from_spec = 0;
  for (const PhysicalInput& p : in.provenance) {
    if (p.source == InputSource::import_spec) ++from_spec;
  }
  EXPECT_EQ(from_spec, 3U);
  // With readings the stated supply is not used: the readings' range, widened by their error.
  const std::vector<double> readings = {12.0, 12.1};
  const PhysicalInputs read = physical_inputs(rig, readings, b);
  EXPECT_NEAR(read.supply_v.lo(), 12.0 - 40.0 / 2048.0, 1e-12);
  b.supply.reset();
  EXPECT_THROW((void)physical_inputs(rig, {}, b), std::invalid_argument);
}

}  // namespace
}  // namespace furuta::identification
