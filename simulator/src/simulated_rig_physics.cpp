// The simulated rig's physics and the boards' reports: the model integrated to the clock's time
// with the duty the 1065 applies, and each board's report built on its own 8 ms clock.

#include "furuta/firmware_bridge/phidget_ids.hpp"
#include "simulated_rig_impl.hpp"

namespace furuta::sim {

using namespace bridge;  // NOLINT(google-build-using-namespace): the boards' types and codecs
using namespace detail;  // NOLINT(google-build-using-namespace): this file is the rig's own

SimulatedRig::Impl::Impl(SimulatedRigConfig config, Clock& clock)
    : config_(std::move(config)), clock_(clock) {
  if (!(config_.integration_step_s > 0.0) || config_.report_period_ns <= 0 ||
      config_.encoder_report_phase_ns < 0 || config_.usb_latency_ns < 0 ||
      config_.usb_latency_jitter_ns < 0) {
    throw std::invalid_argument(
        "SimulatedRigConfig: step, period, phase and latencies must be >= 0");
  }
  if (config_.input_report_bytes_1065 < k1065InputReportMinBytes ||
      config_.input_report_bytes_1065 > kMaxReportBytes ||
      config_.input_report_bytes_1047 < k1047InputReportMinBytes ||
      config_.input_report_bytes_1047 > kMaxReportBytes ||
      config_.output_report_bytes_1065 < k1065OutputReportMinBytes ||
      config_.output_report_bytes_1065 > kMaxReportBytes) {
    throw std::invalid_argument("SimulatedRigConfig: report lengths outside the boards' layouts");
  }
  // A firmware version is three digits (bcdDevice carries it, docs/phidget-protocol.md); any of
  // them may be presented, so that a test can show one the codecs do not know.
  if (config_.firmware_1065 < 100 || config_.firmware_1065 > 999 || config_.firmware_1047 < 100 ||
      config_.firmware_1047 > 999) {
    throw std::invalid_argument("SimulatedRigConfig: firmware versions must be in [100, 999]");
  }
  if (config_.usb_packet_bytes_1047 < config_.input_report_bytes_1047 ||
      config_.usb_packet_bytes_1047 > kMaxReportBytes) {
    throw std::invalid_argument(
        "SimulatedRigConfig: usb_packet_bytes_1047 must hold a report and be at most 64");
  }
  if (config_.pendulum_channel < 0 ||
      config_.pendulum_channel >= static_cast<int>(k1047ChannelCount)) {
    throw std::invalid_argument("SimulatedRigConfig: pendulum_channel must be 0..3");
  }
  step_ns_ = std::max<std::int64_t>(1, std::llround(config_.integration_step_s * kNsPerS));
  tick_ns_1047_ = tick_seconds_1047(config_.firmware_1047) * kNsPerS;
  const double packet_ticks = std::round(config_.report_period_ns / tick_ns_1047_);
  if (packet_ticks > kMax1047PacketTimeTicks) {
    throw std::invalid_argument("SimulatedRigConfig: report period too long for the 1047's u24");
  }
  packet_time_ticks_ = static_cast<std::uint32_t>(packet_ticks);
  for (std::size_t i = 0; i < config_.taps.size(); ++i) {
    const Tap& tap = config_.taps[i];
    if (!(tap.time_s >= 0.0 && tap.time_s <= kMaxTapTimeS) || !std::isfinite(tap.impulse_nm_s) ||
        (i > 0 && !(tap.time_s > config_.taps[i - 1].time_s))) {
      throw std::invalid_argument(
          "SimulatedRigConfig: tap times must be strictly increasing in [0, 1e9] s, impulses "
          "finite");
    }
  }

  std::mt19937_64 master(config_.seed);
  noise_rng_.seed(master());
  for (auto& rng : jitter_rng_) rng.seed(master());
  corrupt_rng_.seed(master());

  t0_ns_ = clock_.now_ns();
  physics_ns_ = t0_ns_;
  state_ = config_.initial_state;
  supply_v_ = config_.supply_voltage_v;

  // Two taps that round to the same nanosecond are applied one after the other at that instant.
  tap_ns_.reserve(config_.taps.size());
  for (const Tap& tap : config_.taps) {
    tap_ns_.push_back(t0_ns_ + std::llround(tap.time_s * static_cast<double>(kNsPerS)));
  }
  tap_records_.reserve(config_.taps.size());

  board_of(RigBoard::motor_1065).encoder.counts_per_rad =
      config_.motor_encoder_counts_per_rev * config_.motor.total_ratio() / kTwoPi;
  board_of(RigBoard::encoder_1047).encoder.counts_per_rad =
      config_.pendulum_encoder_counts_per_rev / kTwoPi;
  board_of(RigBoard::motor_1065).next_generation_ns = t0_ns_ + config_.report_period_ns;
  board_of(RigBoard::encoder_1047).next_generation_ns =
      t0_ns_ + config_.encoder_report_phase_ns + config_.report_period_ns;
  for (int i = 0; i < kBoardCount; ++i) {
    std::uniform_int_distribution<std::int64_t> jitter(0, config_.usb_latency_jitter_ns);
    boards_[i].next_jitter_ns = jitter(jitter_rng_[i]);
    power_up(static_cast<RigBoard>(i));
  }
  apply_due_taps();  // a tap at 0 s acts on the initial state
}

double SimulatedRig::Impl::drive_torque(double duty, double dq1, bool idle) const {
  if (idle) {
    // Inferred board behaviour: with no PWM the H-bridge either lets the motor coast (braking 0) or
    // shorts its windings, which brakes like eq. 4 at zero duty; the braking setting blends the
    // two.
    return motor_output_.braking_fraction() * config_.motor.arm_torque_nm(0.0, dq1);
  }
  // PWM chops the supply, so the no-load speed scales with it; at the nominal supply this is eq. 4.
  const double effective_duty = duty * supply_v_ / config_.motor.nominal_voltage_v;
  return config_.motor.arm_torque_nm(effective_duty, dq1);
}

void SimulatedRig::Impl::reset_motor() {
  motor_output_ = MotorOutput1065{};
  duty_.hold(0.0);
  duty_.command(0.0, duty_rate_per_s(motor_output_));
}

void SimulatedRig::Impl::power_up(RigBoard board) {
  Board& b = board_of(board);
  b.power_up_ns = physics_ns_;
  b.reports_since_power_up = 0;
  b.previous_reported_count = 0;
  b.queue.clear();
  if (board == RigBoard::motor_1065) {
    b.encoder.power_up(state_.q1, physics_ns_);
    reset_motor();
  } else {
    b.encoder.power_up(state_.q2, physics_ns_);
    enable_mask_ = 0;
  }
}

void SimulatedRig::Impl::advance_locked(std::int64_t t_ns) {
  for (;;) {
    Board& motor = board_of(RigBoard::motor_1065);
    Board& encoder = board_of(RigBoard::encoder_1047);
    const std::int64_t next_event = std::min(motor.next_generation_ns, encoder.next_generation_ns);
    if (next_event > t_ns) break;
    integrate_to(next_event);
    for (int i = 0; i < kBoardCount; ++i) {
      Board& b = boards_[i];
      if (b.next_generation_ns != next_event) continue;
      // An unplugged board sends nothing; its schedule stays on the grid for when it comes back.
      if (b.connected) generate(static_cast<RigBoard>(i), next_event);
      b.next_generation_ns += config_.report_period_ns;
    }
  }
  integrate_to(t_ns);
}

double duty_rate_per_s(const MotorOutput1065& output) {
  double pct = output.acceleration_pct_per_s();
  // Inferred: raw acceleration 0 is taken as the slowest ramp the wire can express rather than a
  // motor that never responds.
  if (pct <= 0.0) pct = k1065FullScaleAccelerationPctPerS / 255.0;
  return pct / 100.0;
}

void SimulatedRig::Impl::apply_due_taps() {
  while (next_tap_ < tap_ns_.size() && tap_ns_[next_tap_] <= physics_ns_) {
    const double impulse = config_.taps[next_tap_].impulse_nm_s;
    TapRecord& record = tap_records_.emplace_back();  // room reserved at construction
    record.time_ns = physics_ns_;  // the instant it acted on, which is its own time
    record.impulse_nm_s = impulse;
    record.before = state_;
    if (arm_clamped_) {
      // The clamp takes the arm's reaction: the arm stays still and the pendulum alone turns.
      state_.dq2 += impulse / config_.parameters.mu4;
    } else {
      // dq += M(q)^-1 [0, impulse], the 2x2 inverse written out.
      const model::MassMatrix<double> m = model::mass_matrix(config_.parameters, state_.q2);
      const double det = m.m11 * m.m22 - m.m12 * m.m12;
      state_.dq1 += -m.m12 * impulse / det;
      state_.dq2 += m.m11 * impulse / det;
    }
    record.after = state_;
    for (double& since : tap_since_report_) since += impulse;
    ++next_tap_;
  }
}

void SimulatedRig::Impl::integrate_to(std::int64_t t_ns) {
  Encoder& arm = board_of(RigBoard::motor_1065).encoder;
  Encoder& pendulum = board_of(RigBoard::encoder_1047).encoder;
  apply_due_taps();
  while (physics_ns_ < t_ns) {
    // Steps stay on a grid anchored at t0, split only where a report, a command or a tap needs the
    // state, so the trajectory does not depend on how often the host happens to poll.
    const std::int64_t grid_next = t0_ns_ + ((physics_ns_ - t0_ns_) / step_ns_ + 1) * step_ns_;
    std::int64_t end_ns = std::min(grid_next, t_ns);
    if (next_tap_ < tap_ns_.size()) end_ns = std::min(end_ns, tap_ns_[next_tap_]);
    // A ramp that reaches its target within the step ends the step there: the step sees a duty
    // constant at the ramp's mean, and a short ramp (a small command change) spread over a whole
    // step would act half a step late: an effective delay on every small change, which an
    // output-error fit reads as a bias in the arm's inertia (docs/measurements/identification.md,
    // "Output-error refinement: five seed triples per excitation").
    if (duty_.target() != duty_.applied()) {
      const auto ramp_ns = static_cast<std::int64_t>(
          std::ceil(duty_.seconds_to_target() * static_cast<double>(kNsPerS)));
      end_ns = std::min(end_ns, physics_ns_ + std::max<std::int64_t>(1, ramp_ns));
    }
    const double h = static_cast<double>(end_ns - physics_ns_) / kNsPerS;

    const double duty_start = duty_.applied();
    // The ramp is linear within the step (the step ends where it reaches the target), and RK4
    // sees it so at each stage. The board is idle (braking) where the whole step has duty 0; a
    // ramp through 0 is not.
    const double duty_end = duty_.advance(h);
    const bool idle = duty_start == 0.0 && duty_end == 0.0;

    state_ = model::rk4_step(
        config_.parameters, state_, h,
        [&](const model::PendulumState& s, double fraction) {
          return drive_torque(duty_start + fraction * (duty_end - duty_start), s.dq1, idle);
        },
        arm_clamped_);
    physics_ns_ = end_ns;
    arm.track_edges(state_.q1, physics_ns_);
    pendulum.track_edges(state_.q2, physics_ns_);
    apply_due_taps();
  }
}

std::size_t SimulatedRig::Impl::build_1065(double torque, std::span<std::uint8_t> out) {
  Board& b = board_of(RigBoard::motor_1065);
  const double measured_q1 = state_.q1 + config_.arm_angle_noise_rad * standard_normal_(noise_rng_);
  const std::int64_t count = b.encoder.reported(measured_q1);

  MotorReport1065 r;
  r.status_flags = static_cast<std::uint8_t>(
      (over_temperature_ ? k1065FlagOverTemperature : 0) |
      (under_voltage_ ? k1065FlagUnderVoltage : 0) |
      (duty_.applied() > 0.0 ? k1065FlagActualDirection : 0) |
      ((motor_output_.flags & k1065OutDirectionPositive) ? k1065FlagCommandedDirection : 0) |
      ((motor_output_.flags & k1065OutRatiometric) ? k1065FlagRatiometricEcho : 0) |
      ((motor_output_.flags & k1065OutBackEmfSensing) ? k1065FlagBackEmfSensingEcho : 0));
  r.current_raw = current_raw_from_a(std::abs(config_.motor.motor_current_a(torque)));
  r.supply_raw = supply_raw_from_v(
      std::max(0.0, supply_v_ + config_.supply_noise_v * standard_normal_(noise_rng_)));
  // The board keeps an i32 that wraps.
  r.encoder_position = static_cast<std::int32_t>(static_cast<std::uint32_t>(count));
  r.encoder_time_raw =
      static_cast<std::uint16_t>((b.encoder.last_edge_ns - b.power_up_ns) * 3 / 1'000'000);
  r.applied_duty_raw = duty_raw_from_fraction(std::min(1.0, std::abs(duty_.applied())));
  r.commanded_duty_raw = motor_output_.duty_raw;
  r.acceleration_raw = motor_output_.acceleration_raw;
  r.braking_raw = motor_output_.braking_raw;
  r.packet_counter = static_cast<std::uint8_t>(b.reports_since_power_up);
  // Every field is in range by construction, so encoding cannot fail.
  (void)encode_input_1065(r, out.first(config_.input_report_bytes_1065));
  return config_.input_report_bytes_1065;
}

std::size_t SimulatedRig::Impl::build_1047(std::int64_t generated_ns, std::span<std::uint8_t> out) {
  Board& b = board_of(RigBoard::encoder_1047);
  const double measured_q2 =
      state_.q2 + config_.pendulum_angle_noise_rad * standard_normal_(noise_rng_);
  const std::int64_t count = b.encoder.reported(measured_q2);
  // The delta is taken against the previous generated report even when that one was lost, so a
  // dropped report loses its counts for good, as on the real board.
  const std::int64_t delta = count - b.previous_reported_count;
  b.previous_reported_count = count;

  EncoderReport1047 r;
  for (std::size_t i = 0; i < k1047ChannelCount; ++i) {
    EncoderChannel1047& ch = r.channels[i];
    const bool enabled = enable_mask_ & (1u << i);
    ch.packet_time_ticks = packet_time_ticks_;
    ch.cur_time_ticks = kMax1047CurTimeTicks;
    ch.flags = static_cast<std::uint8_t>(k1047FlagDigitalInputFalse |
                                         (enabled ? k1047FlagEnabledEcho : 0));
    if (static_cast<int>(i) != config_.pendulum_channel) continue;
    const double since_edge_ticks =
        static_cast<double>(generated_ns - b.encoder.last_edge_ns) / tick_ns_1047_;
    ch.cur_time_ticks = static_cast<std::uint16_t>(
        std::clamp(since_edge_ticks, 0.0, static_cast<double>(kMax1047CurTimeTicks)));
    if (enabled) {
      ch.position_delta =
          static_cast<std::int32_t>(std::clamp<std::int64_t>(delta, k1047MinDelta, k1047MaxDelta));
    }
  }
  // Deltas are saturated and the packet time was checked at construction: encoding cannot fail.
  (void)encode_input_1047(r, out.first(config_.input_report_bytes_1047));
  return config_.input_report_bytes_1047;
}

void SimulatedRig::Impl::corrupt(PendingReport& report) {
  if (report.length == 0) return;
  std::uniform_int_distribution<int> how_many(1, 3);
  std::uniform_int_distribution<std::size_t> which(0, report.length * 8 - 1);
  std::array<std::size_t, 3> flipped{};
  const int n = how_many(corrupt_rng_);
  for (int k = 0; k < n; ++k) {
    std::size_t bit = 0;
    // Distinct bits, so that two flips never cancel and the report is always damaged.
    do {
      bit = which(corrupt_rng_);
    } while (std::find(flipped.begin(), flipped.begin() + k, bit) != flipped.begin() + k);
    flipped[k] = bit;
    report.bytes[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
  }
}

void SimulatedRig::Impl::generate(RigBoard board, std::int64_t generated_ns) {
  Board& b = board_of(board);
  const double torque = drive_torque(duty_.applied(), state_.dq1, duty_.applied() == 0.0);

  // Built on the stack and copied into the ring only if it is kept.
  PendingReport report;
  report.length = board == RigBoard::motor_1065 ? build_1065(torque, report.bytes)
                                                : build_1047(generated_ns, report.bytes);
  ++b.reports_since_power_up;
  const std::int64_t index = b.report_index++;

  const std::int64_t jitter = b.next_jitter_ns;
  std::uniform_int_distribution<std::int64_t> jitter_dist(0, config_.usb_latency_jitter_ns);
  b.next_jitter_ns = jitter_dist(jitter_rng_[board_index(board)]);

  FaultPlan& f = b.faults;
  const bool dropped = consume(f.drop);
  std::int64_t delivery = generated_ns + config_.usb_latency_ns + jitter;
  if (consume(f.delay)) delivery += f.delay_ns;
  if (consume(f.truncate)) report.length = std::min(report.length, f.truncate_bytes);
  if (consume(f.corrupt)) corrupt(report);
  if (generated_ns < f.stall_until_ns) delivery = std::max(delivery, f.stall_until_ns);
  delivery = std::max(delivery, b.last_delivery_ns);
  report.delivery_ns = delivery;

  // Nobody listening (not opened) or a full buffer loses the report like a dropped one.
  const bool delivered = !dropped && b.owner != 0 && !b.queue.full();
  if (delivered) {
    b.queue.push_slot() = report;
    b.last_delivery_ns = delivery;
  }

  if (config_.record_truth) {
    TruthRecord t;
    t.board = board;
    t.generated_ns = generated_ns;
    t.report_index = index;
    t.state = state_;
    t.applied_duty = duty_.applied();
    t.arm_torque_nm = torque;
    t.delivered = delivered;
    t.tap_impulse_nm_s = tap_since_report_[board_index(board)];
    truth_.push_back(t);
  }
  tap_since_report_[board_index(board)] = 0.0;
}

std::int64_t SimulatedRig::Impl::next_delivery_estimate(const Board& b) const {
  if (!b.queue.empty()) return b.queue.front().delivery_ns;
  const std::int64_t g = b.next_generation_ns;
  // A report that will be lost or cannot be queued lands never; wake at its generation and look
  // again.
  if (b.faults.drop > 0 || b.queue.full()) return g;
  std::int64_t delivery = g + config_.usb_latency_ns + b.next_jitter_ns;
  if (b.faults.delay > 0) delivery += b.faults.delay_ns;
  if (g < b.faults.stall_until_ns) delivery = std::max(delivery, b.faults.stall_until_ns);
  return std::max(delivery, b.last_delivery_ns);
}

}  // namespace furuta::sim
