#include <gtest/gtest.h>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include "furuta/config/rig_config.hpp"
#include "furuta/control/upright_lqr.hpp"
#include "furuta/verification/balance_certificate.hpp"
namespace furuta::verification::zz_explore_test {
namespace {
constexpr double kDeg = std::numbers::pi / 180;
TEST(Explore, Split) {
  if (!std::getenv("EXPLORE")) GTEST_SKIP();
  const config::RigConfig rig = config::load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
  const auto truth = rig.simulation.parameters;
  const control::DesignPlant plant{truth, rig.simulation.motor, rig.simulation.supply_voltage_v};
  const control::SampledPlant sampled = control::sample(control::linearize_upright(plant), 0.016, 0.002 + control::ramp_lag_s(6250, 0.05));
  control::ObserverWeights f; f.arm_count_rad = 2 * std::numbers::pi / (1024.0 * rig.simulation.motor.total_ratio()); f.pendulum_count_rad = 2 * std::numbers::pi / 4096; f.reading_age_s = 0.004;
  const auto law = control::balance_spec(plant, sampled, control::design_lqr(sampled, control::LqrWeights{}), control::design_observer(sampled, f), control::DutyPath{0.002, 62.5}, 0.5, 1.0 / 255);
  const double k = std::atof(std::getenv("EXPLORE"));
  const model::Parameters<double> rel{2.4e-4, 7.4e-5, 8.2e-5, 7.6e-5, 7.8e-5, 1.8e-4, 2.6e-4};
  LoopModel loop;
  for (std::size_t i = 0; i < 7; ++i) loop.parameters[i] = Interval(truth[i]) * (Interval(1.0) + Interval(-k * rel[i], k * rel[i]));
  loop.duty_torque_nm = Interval(law.duty_torque_nm); loop.back_emf_nm_s = Interval(law.back_emf_nm_s);
  loop.lag_s = Interval(0.002); loop.ramp_duty_per_s = 62.5; loop.reading_age_s = 0.004;
  loop.arm_count_rad = f.arm_count_rad; loop.pendulum_count_rad = f.pendulum_count_rad;
  const double sc = std::getenv("SCALE") ? std::atof(std::getenv("SCALE")) : 1.0;
  LoopStart start; start.state = {Interval(0.0), Interval(-2 * kDeg * sc, 2 * kDeg * sc), Interval(0.0), Interval(-10 * kDeg * sc, 10 * kDeg * sc)};
  start.estimate_error = {Interval(-f.arm_count_rad, f.arm_count_rad), Interval(-f.pendulum_count_rad, f.pendulum_count_rad), Interval(-kDeg, kDeg), Interval(-kDeg, kDeg)};
  VerifyOptions o; o.horizon_s = std::getenv("HORIZON") ? std::atof(std::getenv("HORIZON")) : 10;
  SplitOptions sp{std::getenv("PIECES") ? static_cast<std::size_t>(std::atoi(std::getenv("PIECES"))) : 32};
  const BalanceCertificate c = verify_balance_split(law, loop, start, {law.region.fall_rad, 150 * kDeg}, o, sp);
  std::printf("k %g scale %g certified %d pieces %zu seconds %g", k, sc, int(c.certified()), c.pieces, c.seconds);
  if (c.failure) std::printf(" fail kind %d t %g", int(c.failure->kind), c.failure->t_s);
  std::printf("\n");
}
}  // namespace
}  // namespace furuta::verification::zz_explore_test
