#include "furuta/daemon/safety.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace furuta::daemon {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

static_assert(noexcept(check_safety(SafetyLimits{}, SafetyInput{})));

// A healthy cycle under the default limits.
SafetyInput healthy() {
  SafetyInput input;
  input.arm_angle_rad = 0.1;
  input.commanded_duty = 0.3;
  input.cycles_without_motor_report = 0;
  input.cycles_without_encoder_report = 1;
  input.supply_voltage_v = 12.0;
  input.have_supply_reading = true;
  return input;
}

StopReason check(const SafetyInput& input) {
  return check_safety(SafetyLimits{}, input);
}

TEST(Safety, AHealthyCyclePasses) {
  EXPECT_EQ(check(healthy()), StopReason::none);
  EXPECT_EQ(check(SafetyInput{}), StopReason::none);  // before the first report
}

TEST(Safety, BoardProtectionsStopTheSession) {
  SafetyInput input = healthy();
  input.motor_over_temperature = true;
  EXPECT_EQ(check(input), StopReason::over_temperature);
  input.motor_over_temperature = false;
  input.motor_under_voltage = true;
  EXPECT_EQ(check(input), StopReason::under_voltage);
}

TEST(Safety, SupplyIsCheckedOnlyOnceThereIsAReadingAndItsLimitsAreAllowed) {
  SafetyInput input = healthy();
  for (double volts : {7.0, 12.0, 34.0}) {
    input.supply_voltage_v = volts;
    EXPECT_EQ(check(input), StopReason::none) << volts;
  }
  for (double volts : {std::nextafter(7.0, 0.0), std::nextafter(34.0, 100.0), 0.0, -12.0, 48.0,
                       kNan, kInf, -kInf}) {
    input.supply_voltage_v = volts;
    EXPECT_EQ(check(input), StopReason::supply_out_of_range) << volts;
  }
  input.have_supply_reading = false;
  for (double volts : {0.0, kNan, 100.0}) {
    input.supply_voltage_v = volts;
    EXPECT_EQ(check(input), StopReason::none) << volts;
  }
}

TEST(Safety, StaleReportsStopAtTheConfiguredCountMotorFirst) {
  SafetyInput input = healthy();
  input.cycles_without_motor_report = 3;
  input.cycles_without_encoder_report = 3;
  EXPECT_EQ(check(input), StopReason::none);
  input.cycles_without_motor_report = 4;
  EXPECT_EQ(check(input), StopReason::stale_motor_reports);
  input.cycles_without_encoder_report = 400;
  EXPECT_EQ(check(input), StopReason::stale_motor_reports);
  input.cycles_without_motor_report = 0;
  EXPECT_EQ(check(input), StopReason::stale_encoder_reports);
  input.cycles_without_encoder_report = 4;
  EXPECT_EQ(check(input), StopReason::stale_encoder_reports);

  SafetyLimits strict;
  strict.stale_report_cycles = 1;
  input = healthy();
  input.cycles_without_encoder_report = 0;
  EXPECT_EQ(check_safety(strict, input), StopReason::none);
  input.cycles_without_encoder_report = 1;
  EXPECT_EQ(check_safety(strict, input), StopReason::stale_encoder_reports);
}

TEST(Safety, ArmAngleAtTheLimitIsAllowedBeyondItOrUnknownIsNot) {
  SafetyInput input = healthy();
  for (double q : {2.6, -2.6, 0.0, -0.0}) {
    input.arm_angle_rad = q;
    EXPECT_EQ(check(input), StopReason::none) << q;
  }
  for (double q : {std::nextafter(2.6, 10.0), std::nextafter(-2.6, -10.0), 3.2, -100.0, kNan, -kNan,
                   kInf, -kInf}) {
    input.arm_angle_rad = q;
    EXPECT_EQ(check(input), StopReason::arm_angle_limit) << q;
  }
}

TEST(Safety, DutyAtTheLimitIsAllowedBeyondItOrUnknownIsNot) {
  SafetyInput input = healthy();
  for (double d : {0.6, -0.6, 0.0}) {
    input.commanded_duty = d;
    EXPECT_EQ(check(input), StopReason::none) << d;
  }
  for (double d :
       {std::nextafter(0.6, 1.0), std::nextafter(-0.6, -1.0), 1.0, -1.0, kNan, kInf, -kInf}) {
    input.commanded_duty = d;
    EXPECT_EQ(check(input), StopReason::duty_limit) << d;
  }
}

TEST(Safety, ConfiguredLimitsAreUsed) {
  SafetyLimits limits;
  limits.arm_limit_rad = 1.0;
  limits.max_duty = 0.2;
  limits.min_supply_v = 11.0;
  limits.max_supply_v = 13.0;
  SafetyInput input = healthy();
  input.commanded_duty = 0.2;
  EXPECT_EQ(check_safety(limits, input), StopReason::none);
  input.arm_angle_rad = 1.01;
  EXPECT_EQ(check_safety(limits, input), StopReason::arm_angle_limit);
  input.arm_angle_rad = 0.0;
  input.commanded_duty = 0.21;
  EXPECT_EQ(check_safety(limits, input), StopReason::duty_limit);
  input.commanded_duty = 0.0;
  input.supply_voltage_v = 10.9;
  EXPECT_EQ(check_safety(limits, input), StopReason::supply_out_of_range);
}

TEST(Safety, AMissingLimitFailsSafe) {
  // A NaN limit (a configuration bug) stops the session instead of passing everything.
  SafetyInput input = healthy();
  SafetyLimits limits;
  limits.arm_limit_rad = kNan;
  EXPECT_EQ(check_safety(limits, input), StopReason::arm_angle_limit);
  limits = SafetyLimits{};
  limits.max_duty = kNan;
  EXPECT_EQ(check_safety(limits, input), StopReason::duty_limit);
  limits = SafetyLimits{};
  limits.min_supply_v = kNan;
  EXPECT_EQ(check_safety(limits, input), StopReason::supply_out_of_range);
}

TEST(Safety, StuckEncodersAtTheirThresholds) {
  const SafetyLimits limits;
  SafetyInput input = healthy();
  input.arm_still_driven_cycles = limits.stuck_arm_cycles - 1;
  EXPECT_EQ(check_safety(limits, input), StopReason::none);
  input.arm_still_driven_cycles = limits.stuck_arm_cycles;
  EXPECT_EQ(check_safety(limits, input), StopReason::arm_encoder_stuck);
  input = healthy();
  input.arm_travel_pendulum_still_rad = std::nextafter(limits.stuck_pendulum_arm_travel_rad, 0.0);
  EXPECT_EQ(check_safety(limits, input), StopReason::none);
  input.arm_travel_pendulum_still_rad = limits.stuck_pendulum_arm_travel_rad;
  EXPECT_EQ(check_safety(limits, input), StopReason::pendulum_encoder_stuck);
  input.arm_travel_pendulum_still_rad = kNan;  // an unknown travel is not taken as safe
  EXPECT_EQ(check_safety(limits, input), StopReason::pendulum_encoder_stuck);
}

TEST(Safety, WhenSeveralRulesAreBrokenTheFirstInOrderIsReported) {
  // In the documented order; breaking rules i.. must report rule i.
  const std::vector<std::pair<StopReason, std::function<void(SafetyInput&)>>> rules = {
      {StopReason::over_temperature, [](SafetyInput& s) { s.motor_over_temperature = true; }},
      {StopReason::under_voltage, [](SafetyInput& s) { s.motor_under_voltage = true; }},
      {StopReason::supply_out_of_range, [](SafetyInput& s) { s.supply_voltage_v = 5.0; }},
      {StopReason::stale_motor_reports, [](SafetyInput& s) { s.cycles_without_motor_report = 9; }},
      {StopReason::stale_encoder_reports,
       [](SafetyInput& s) { s.cycles_without_encoder_report = 9; }},
      {StopReason::arm_angle_limit, [](SafetyInput& s) { s.arm_angle_rad = kNan; }},
      {StopReason::duty_limit, [](SafetyInput& s) { s.commanded_duty = 0.9; }},
      {StopReason::arm_encoder_stuck, [](SafetyInput& s) { s.arm_still_driven_cycles = 9; }},
      {StopReason::pendulum_encoder_stuck,
       [](SafetyInput& s) { s.arm_travel_pendulum_still_rad = 7.0; }},
  };
  for (std::size_t first = 0; first < rules.size(); ++first) {
    SafetyInput input = healthy();
    for (std::size_t i = first; i < rules.size(); ++i) rules[i].second(input);
    EXPECT_EQ(check(input), rules[first].first) << to_string(rules[first].first);
    // And each rule on its own.
    SafetyInput alone = healthy();
    rules[first].second(alone);
    EXPECT_EQ(check(alone), rules[first].first) << to_string(rules[first].first);
  }
}

}  // namespace
}  // namespace furuta::daemon
