#pragma once
// The motor board's response to a duty command, the one model of it that the simulated rig and the
// output-error fit share: from the moment a command arrives, the applied duty moves towards the
// commanded one at the command's rate (a slew limit) and then holds it. The rate is the board's
// ramp as its adapter reads it from the written command (bridge::MotorWrite), in duty per second.

#include <cmath>

namespace furuta::model {

class DutyRamp {
 public:
  explicit DutyRamp(double applied = 0.0) : applied_(applied), target_(applied) {}

  // From now on, towards `target` at `rate_per_s` (> 0) duty per second.
  void command(double target, double rate_per_s) {
    target_ = target;
    rate_per_s_ = rate_per_s;
  }
  // Seconds until the applied duty reaches the target; 0 when it is there.
  double seconds_to_target() const { return std::abs(target_ - applied_) / rate_per_s_; }
  // Moves `dt_s` seconds on and returns the applied duty then.
  double advance(double dt_s) {
    const double gap = target_ - applied_;
    const double max_change = rate_per_s_ * dt_s;
    applied_ = std::abs(gap) <= max_change ? target_ : applied_ + std::copysign(max_change, gap);
    return applied_;
  }
  // Applied and commanded at once, as a board after a reset.
  void hold(double duty) { applied_ = target_ = duty; }

  double applied() const { return applied_; }
  double target() const { return target_; }
  double rate_per_s() const { return rate_per_s_; }

 private:
  double applied_ = 0.0;
  double target_ = 0.0;
  double rate_per_s_ = 1.0;
};

}  // namespace furuta::model
