#pragma once
// The balancing loop simulated without intervals, one start and one parameter at a time: the
// verifier's independent check (every sample inside its boxes) and the trajectories the report
// draws inside the tube. It shares nothing with the verifier's enclosures: the nonlinear model by
// Runge-Kutta 4, the board's lag and ramp as a duty that is piecewise linear in time, the angles
// rounded to whole counts, and the real control::BalanceLaw.

#include <array>
#include <cstddef>
#include <limits>
#include <vector>

#include "furuta/control/balance_law.hpp"
#include "furuta/model/parameters.hpp"
#include "furuta/verification/balance_certificate.hpp"

namespace furuta::verification {

// One point of the verifier's boxes.
struct LoopPoint {
  model::Parameters<double> parameters;
  double duty_torque_nm = 0;
  double back_emf_nm_s = 0;
  double lag_s = 0;
  // Where each encoder's count boundaries lie, as a fraction of a count in [-0.5, 0.5]: a reading
  // is the angle rounded to the nearest count from that offset (within half a count of it).
  double arm_count_offset = 0;
  double pendulum_count_offset = 0;
  std::array<double, 4> state{};     // [q1, q2 - pi, dq1, dq2] at t = 0
  std::array<double, 4> estimate{};  // the law's estimate at t = 0
};

struct LoopSample {
  double t_s = 0;
  std::array<double, 4> state{};  // the plant's, [q1, q2 - pi, dq1, dq2]
  double duty = 0;                // what the law sent at t_s
  double arm_rate_rad_s = 0;      // the filter's estimated rates at t_s
  double pendulum_rate_rad_s = 0;
  control::BalanceMode mode = control::BalanceMode::catching;
};

struct LoopTrajectory {
  std::vector<LoopSample> samples;  // t = 0 and every sample after it
  // The plant's state at the end of every Runge-Kutta step: the motion between samples.
  std::vector<double> inner_t_s;
  std::vector<std::array<double, 4>> inner_state;
};

// `loop` gives the ramp, the reading age and the counts (its boxes are ignored); steps_per_period
// Runge-Kutta steps at least per period (more where the duty's slope changes).
LoopTrajectory simulate_loop(const control::BalanceControllerSpec& law, const LoopModel& loop,
                             const LoopPoint& point, double horizon_s, int steps_per_period);

// Every sample's state, duty and filter rates, and every inner state, against the certificate's
// boxes of the period they fall in (up to the certificate's last step).
struct TubeCheck {
  std::size_t checks = 0;   // values compared
  std::size_t outside = 0;  // of them, outside their box
  double first_outside_s = std::numeric_limits<double>::quiet_NaN();
};
TubeCheck check_inside(const BalanceCertificate& certificate, const LoopTrajectory& trajectory);

// The check over many trajectories: `count` of them, the first from the corners of the parameters
// that move the plant most (mu1, mu3, mu4) and of the start's pendulum angle and rate (32
// corners), the filter's error, the lag and the counts' boundaries at random corners or inside;
// then points inside every box at random (`seed`). The first `draw` trajectories are kept.
struct SampledCheck {
  std::size_t trajectories = 0;
  TubeCheck check;  // summed over the trajectories
  std::vector<LoopTrajectory> drawn;
};
SampledCheck sampled_check(const control::BalanceControllerSpec& law, const LoopModel& loop,
                           const LoopStart& start, const BalanceCertificate& certificate,
                           std::size_t count, std::size_t draw, unsigned seed,
                           int steps_per_period = 64);

}  // namespace furuta::verification
