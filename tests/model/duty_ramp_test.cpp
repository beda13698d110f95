#include "furuta/model/duty_ramp.hpp"

#include <gtest/gtest.h>

namespace furuta::model {
namespace {

TEST(DutyRamp, SlewsTowardsTheCommandAtItsRateThenHoldsIt) {
  DutyRamp ramp(0.2);
  EXPECT_EQ(ramp.applied(), 0.2);
  EXPECT_EQ(ramp.seconds_to_target(), 0.0);
  ramp.command(-0.4, 50.0);  // 0.6 of duty at 50 per s: 12 ms
  EXPECT_DOUBLE_EQ(ramp.seconds_to_target(), 0.012);
  EXPECT_DOUBLE_EQ(ramp.advance(0.004), 0.0);
  EXPECT_DOUBLE_EQ(ramp.seconds_to_target(), 0.008);
  EXPECT_EQ(ramp.advance(0.1), -0.4) << "reaches the command exactly, never past it";
  EXPECT_EQ(ramp.advance(1.0), -0.4);
  ramp.command(0.5, 1000.0);
  EXPECT_EQ(ramp.advance(0.0009), 0.5);
  ramp.hold(0.0);
  EXPECT_EQ(ramp.applied(), 0.0);
  EXPECT_EQ(ramp.target(), 0.0);
}

TEST(DutyRamp, AStepInPiecesEndsWhereOneStepDoes) {
  DutyRamp whole(0.0), pieces(0.0);
  whole.command(1.0, 62.5);
  pieces.command(1.0, 62.5);
  whole.advance(0.01);
  for (int i = 0; i < 10; ++i) pieces.advance(0.001);
  EXPECT_NEAR(whole.applied(), pieces.applied(), 1e-12);
  EXPECT_NEAR(whole.applied(), 0.625, 1e-12);
}

}  // namespace
}  // namespace furuta::model
