#include "furuta/firmware_bridge/encoder_geometry.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>

namespace furuta::bridge {
namespace {

constexpr double kPi = std::numbers::pi;

// The rig's arm: a 1024 count/rev encoder on the motor shaft, behind 5.2 * 5 = 26 of gearing.
EncoderGeometry arm() {
  return {1024.0, 26.0, 1, 0.0};
}
// The pendulum: 4096 count/rev directly on the joint, mounted counting the other way, with an
// offset.
EncoderGeometry pendulum() {
  return {4096.0, 1.0, -1, 0.1};
}

TEST(EncoderGeometry, ArmScaling) {
  const EncoderGeometry g = arm();
  EXPECT_DOUBLE_EQ(g.counts_per_joint_rev(), 26624.0);  // 1024 * 26
  EXPECT_DOUBLE_EQ(counts_to_rad(g, 0), 0.0);
  EXPECT_DOUBLE_EQ(counts_to_rad(g, 26624), 2 * kPi);
  EXPECT_DOUBLE_EQ(counts_to_rad(g, 6656), kPi / 2);  // a quarter turn: 26624 / 4
  EXPECT_DOUBLE_EQ(counts_to_rad(g, -13312), -kPi);
  EXPECT_DOUBLE_EQ(resolution_rad(g), 2 * kPi / 26624);  // 2.36e-4 rad per count
  EXPECT_NEAR(resolution_rad(g), 2.3599704e-4, 1e-11);
}

TEST(EncoderGeometry, PendulumScalingWithSignAndOffset) {
  const EncoderGeometry g = pendulum();
  EXPECT_DOUBLE_EQ(counts_to_rad(g, 0), -0.1);
  EXPECT_DOUBLE_EQ(counts_to_rad(g, 1024), -kPi / 2 - 0.1);  // -2 pi * 1024 / 4096 - 0.1
  EXPECT_DOUBLE_EQ(counts_to_rad(g, -2048), kPi - 0.1);
  EXPECT_DOUBLE_EQ(resolution_rad(g), 2 * kPi / 4096);  // positive whatever the sign
}

TEST(EncoderGeometry, RadToCountsFloorsAndInvertsExactCounts) {
  const EncoderGeometry g = arm();
  EXPECT_EQ(rad_to_counts(g, kPi / 2), 6656);
  // 1e-6 rad is 0.0042 counts: just below a count shows the one below.
  EXPECT_EQ(rad_to_counts(g, kPi / 2 - 1e-6), 6655);
  EXPECT_EQ(rad_to_counts(g, kPi / 2 + 1e-6), 6656);
  // Floor, not truncation towards zero.
  EXPECT_EQ(rad_to_counts(g, -1e-9), -1);
  EXPECT_EQ(rad_to_counts(g, -resolution_rad(g) * 1.5), -2);

  for (const EncoderGeometry& geo : {arm(), pendulum()}) {
    for (std::int64_t n = -100'000; n <= 100'000; n += 7) {
      ASSERT_EQ(rad_to_counts(geo, counts_to_rad(geo, n)), n) << geo.counts_per_rev;
    }
  }
}

TEST(EncoderGeometry, QuantisationIsOneSidedForPositiveSign) {
  const EncoderGeometry g = arm();
  const double res = resolution_rad(g);
  // Angles that do not sit on count boundaries, over several turns either way.
  for (double a = -20.0; a < 20.0; a += 0.001237) {
    const double shown = counts_to_rad(g, rad_to_counts(g, a));
    ASSERT_LE(shown, a) << a;
    ASSERT_LT(a, shown + res) << a;
  }
}

TEST(EncoderGeometry, QuantisationFollowsTheEncoderForNegativeSign) {
  // The encoder floors in its own counting direction, which runs against the joint angle here:
  // the angle it reports is at or above the true one, by less than a count.
  const EncoderGeometry g = pendulum();
  const double res = resolution_rad(g);
  for (double a = -20.0; a < 20.0; a += 0.001237) {
    const double shown = counts_to_rad(g, rad_to_counts(g, a));
    ASSERT_GE(shown, a) << a;
    ASSERT_LT(shown - res, a) << a;
  }
  // Half a count past the zero, in the joint's positive direction, is count -1 on this encoder:
  // position = -(a + offset) * 4096 / (2 pi) = -0.5 -> floor -1 -> angle +res - 0.1.
  const double a = -0.1 + 0.5 * res;
  EXPECT_EQ(rad_to_counts(g, a), -1);
  EXPECT_DOUBLE_EQ(counts_to_rad(g, -1), res - 0.1);
}

TEST(EncoderGeometry, BrokenGeometryDoesNotCrash) {
  const EncoderGeometry g{0.0, 1.0, 1, 0.0};  // uncalibrated
  EXPECT_EQ(rad_to_counts(g, 0.0), 0);        // 0 * 0 / 2pi, no NaN here
  EXPECT_EQ(rad_to_counts(arm(), std::nan("")), 0);
  EXPECT_EQ(rad_to_counts(arm(), 1e300), INT64_MAX);
  EXPECT_EQ(rad_to_counts(arm(), -1e300), INT64_MIN);
}

}  // namespace
}  // namespace furuta::bridge
