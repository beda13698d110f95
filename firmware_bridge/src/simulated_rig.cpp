#include "furuta/firmware_bridge/simulated_rig.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <utility>

#include "furuta/firmware_bridge/phidget_ids.hpp"
#include "simulated_usb.hpp"

namespace furuta::bridge {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr std::int64_t kNsPerS = 1'000'000'000;
constexpr std::int64_t kFarPast = std::numeric_limits<std::int64_t>::min() / 4;
constexpr int kBoardCount = 2;

// Reports waiting for the host, per board. The kernel's hidraw buffer holds 64 reports and drops
// new ones when full; this is larger so that a test can stall a board for seconds and still see
// every held report, but it keeps the same drop-the-newest behaviour when it does overflow.
constexpr std::size_t kReportQueueCapacity = 1024;

constexpr std::uint16_t kMax1047CurTimeTicks = 0xFFFF;
constexpr std::uint32_t kMax1047PacketTimeTicks = 0xFFFFFF;

int board_index(RigBoard board) {
  return static_cast<int>(board);
}

struct PendingReport {
  std::array<std::uint8_t, kMaxReportBytes> bytes{};
  std::size_t length = 0;
  std::int64_t delivery_ns = 0;
};

// Fixed-capacity FIFO so that the steady-state report path never touches the heap.
class ReportRing {
 public:
  ReportRing() : slots_(kReportQueueCapacity) {}
  bool empty() const { return size_ == 0; }
  bool full() const { return size_ == slots_.size(); }
  const PendingReport& front() const { return slots_[head_]; }
  PendingReport& push_slot() {
    PendingReport& slot = slots_[(head_ + size_) % slots_.size()];
    ++size_;
    return slot;
  }
  void pop() {
    head_ = (head_ + 1) % slots_.size();
    --size_;
  }
  void clear() {
    head_ = 0;
    size_ = 0;
  }

 private:
  std::vector<PendingReport> slots_;
  std::size_t head_ = 0;
  std::size_t size_ = 0;
};

struct FaultPlan {
  int drop = 0;
  int delay = 0;
  std::int64_t delay_ns = 0;
  int truncate = 0;
  std::size_t truncate_bytes = 0;
  int corrupt = 0;
  std::int64_t stall_until_ns = kFarPast;
};

bool consume(int& remaining) {
  if (remaining <= 0) return false;
  --remaining;
  return true;
}

// An incremental encoder as the board sees it: the raw count follows the shaft, `offset` holds the
// board's zero (power-up) plus any counts missed while the encoder was stuck.
struct Encoder {
  double counts_per_rad = 0.0;
  std::int64_t offset = 0;
  bool stuck = false;
  std::int64_t frozen = 0;
  std::int64_t last_true_raw = 0;  // noise-free, for edge times
  std::int64_t last_edge_ns = 0;

  std::int64_t raw(double angle_rad) const {
    return static_cast<std::int64_t>(std::floor(angle_rad * counts_per_rad));
  }
  std::int64_t reported(double measured_angle_rad) const {
    return stuck ? frozen : raw(measured_angle_rad) - offset;
  }
  void power_up(double true_angle_rad, std::int64_t now_ns) {
    offset = raw(true_angle_rad);
    frozen = 0;
    last_true_raw = raw(true_angle_rad);
    last_edge_ns = now_ns;
  }
  void track_edges(double true_angle_rad, std::int64_t now_ns) {
    const std::int64_t count = raw(true_angle_rad);
    if (count == last_true_raw) return;
    last_true_raw = count;
    if (!stuck) last_edge_ns = now_ns;
  }
  void set_stuck(bool on, double true_angle_rad) {
    if (on == stuck) return;
    if (on) {
      frozen = raw(true_angle_rad) - offset;
    } else {
      // Counts that passed while stuck are lost, as with a broken encoder line: counting resumes
      // from the frozen value.
      offset = raw(true_angle_rad) - frozen;
    }
    stuck = on;
  }
};

struct Board {
  bool connected = true;
  std::uint64_t owner = 0;  // handle id that has it open; 0 = nobody
  std::int64_t power_up_ns = 0;
  std::int64_t next_generation_ns = 0;
  std::int64_t next_jitter_ns = 0;  // drawn ahead so a blocking read knows when the next one lands
  std::int64_t last_delivery_ns = kFarPast;
  std::int64_t report_index = 0;  // since the rig was built
  std::uint64_t reports_since_power_up = 0;
  std::int64_t previous_reported_count = 0;  // 1047: the count at the previous generated report
  FaultPlan faults;
  ReportRing queue;
  Encoder encoder;
};

}  // namespace

class SimulatedRig::Impl {
 public:
  Impl(SimulatedRigConfig config, Clock& clock);

  // --- called by the transports ---
  std::uint64_t new_handle_id() {
    std::lock_guard lock(mutex_);
    return next_handle_id_++;
  }
  TransportStatus open(std::uint64_t handle, const DeviceMatch& match, RigBoard& board,
                       DeviceInfo& info);
  void release(std::uint64_t handle, RigBoard board);
  TransportStatus read(std::uint64_t handle, RigBoard board, UsbReport& report,
                       std::chrono::nanoseconds timeout);
  TransportStatus write(std::uint64_t handle, RigBoard board, std::span<const std::uint8_t> bytes);

  // --- the rig's own API ---
  std::vector<DeviceInfo> devices() const;
  void drop_reports(RigBoard board, int count);
  void delay_reports(RigBoard board, int count, std::int64_t extra_latency_ns);
  void truncate_reports(RigBoard board, int count, std::size_t length_bytes);
  void corrupt_reports(RigBoard board, int count);
  void stall(RigBoard board, std::int64_t duration_ns);
  void disconnect(RigBoard board);
  void reconnect(RigBoard board);
  void stick_encoder(RigBoard board, bool stuck);
  void set_supply_voltage(double volts);
  void set_over_temperature(bool on);
  void set_under_voltage(bool on);
  void clamp_arm(bool clamped);

  const SimulatedRigConfig& config() const { return config_; }
  std::int64_t now_ns() const { return clock_.now_ns(); }
  model::PendulumState true_state() const {
    std::lock_guard lock(mutex_);
    return state_;
  }
  std::int64_t physics_time_ns() const {
    std::lock_guard lock(mutex_);
    return physics_ns_;
  }
  const std::vector<TruthRecord>& truth() const { return truth_; }
  const std::vector<MotorCommandRecord>& motor_commands() const { return motor_commands_; }
  void advance_to_now() {
    std::lock_guard lock(mutex_);
    advance_locked(clock_.now_ns());
  }

 private:
  DeviceInfo info_of(RigBoard board) const;
  Board& board_of(RigBoard board) { return boards_[board_index(board)]; }
  double drive_torque(double duty, double dq1) const;
  void reset_motor();
  void power_up(RigBoard board);
  void advance_locked(std::int64_t t_ns);
  void integrate_to(std::int64_t t_ns);
  void generate(RigBoard board, std::int64_t generated_ns);
  std::size_t build_1065(double torque, std::span<std::uint8_t> out);
  std::size_t build_1047(std::int64_t generated_ns, std::span<std::uint8_t> out);
  void corrupt(PendingReport& report);
  std::int64_t next_delivery_estimate(const Board& b) const;
  bool handle_valid(std::uint64_t handle, RigBoard board) const {
    const Board& b = boards_[board_index(board)];
    return b.connected && b.owner == handle;
  }
  std::size_t input_report_bytes(RigBoard board) const {
    return board == RigBoard::motor_1065 ? config_.input_report_bytes_1065
                                         : config_.input_report_bytes_1047;
  }

  const SimulatedRigConfig config_;
  Clock& clock_;
  mutable std::mutex mutex_;

  std::int64_t t0_ns_ = 0;
  std::int64_t step_ns_ = 0;
  std::int64_t physics_ns_ = 0;
  model::PendulumState state_{};
  bool arm_clamped_ = false;

  // 1065 motor drive.
  MotorOutput1065 motor_output_{};
  double target_duty_ = 0.0;
  double applied_duty_ = 0.0;
  double supply_v_ = 0.0;
  bool over_temperature_ = false;
  bool under_voltage_ = false;

  // 1047.
  std::uint8_t enable_mask_ = 0;
  double tick_ns_1047_ = 0.0;
  std::uint32_t packet_time_ticks_ = 0;

  std::array<Board, kBoardCount> boards_{};

  std::mt19937_64 noise_rng_;
  std::array<std::mt19937_64, kBoardCount> jitter_rng_;
  std::mt19937_64 corrupt_rng_;
  std::normal_distribution<double> standard_normal_{0.0, 1.0};

  std::vector<TruthRecord> truth_;
  std::vector<MotorCommandRecord> motor_commands_;
  std::uint64_t next_handle_id_ = 1;
};

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

  std::mt19937_64 master(config_.seed);
  noise_rng_.seed(master());
  for (auto& rng : jitter_rng_) rng.seed(master());
  corrupt_rng_.seed(master());

  t0_ns_ = clock_.now_ns();
  physics_ns_ = t0_ns_;
  state_ = config_.initial_state;
  supply_v_ = config_.supply_voltage_v;

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
}

double SimulatedRig::Impl::drive_torque(double duty, double dq1) const {
  if (duty == 0.0) {
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
  target_duty_ = 0.0;
  applied_duty_ = 0.0;
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

void SimulatedRig::Impl::integrate_to(std::int64_t t_ns) {
  const double max_duty_step_per_s = [&] {
    double pct = motor_output_.acceleration_pct_per_s();
    // Inferred: raw acceleration 0 is taken as the slowest ramp the wire can express rather than a
    // motor that never responds.
    if (pct <= 0.0) pct = k1065FullScaleAccelerationPctPerS / 255.0;
    return pct / 100.0;
  }();
  Encoder& arm = board_of(RigBoard::motor_1065).encoder;
  Encoder& pendulum = board_of(RigBoard::encoder_1047).encoder;
  while (physics_ns_ < t_ns) {
    // Steps stay on a grid anchored at t0, split only where a report or a command needs the state,
    // so the trajectory does not depend on how often the host happens to poll.
    const std::int64_t grid_next = t0_ns_ + ((physics_ns_ - t0_ns_) / step_ns_ + 1) * step_ns_;
    const std::int64_t end_ns = std::min(grid_next, t_ns);
    const double h = static_cast<double>(end_ns - physics_ns_) / kNsPerS;

    const double duty_start = applied_duty_;
    const double max_change = max_duty_step_per_s * h;
    const double gap = target_duty_ - applied_duty_;
    applied_duty_ =
        std::abs(gap) <= max_change ? target_duty_ : applied_duty_ + std::copysign(max_change, gap);
    // The ramp is linear within the step, so its mean is the duty the step sees on average.
    const double step_duty = 0.5 * (duty_start + applied_duty_);

    state_ = model::rk4_step(
        config_.parameters, state_, h,
        [&](const model::PendulumState& s) { return drive_torque(step_duty, s.dq1); },
        arm_clamped_);
    physics_ns_ = end_ns;
    arm.track_edges(state_.q1, physics_ns_);
    pendulum.track_edges(state_.q2, physics_ns_);
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
      (applied_duty_ > 0.0 ? k1065FlagActualDirection : 0) |
      ((motor_output_.flags & k1065OutDirectionPositive) ? k1065FlagCommandedDirection : 0) |
      ((motor_output_.flags & k1065OutRatiometric) ? k1065FlagRatiometricEcho : 0) |
      ((motor_output_.flags & k1065OutBackEmfSensing) ? k1065FlagBackEmfSensingEcho : 0));
  r.current_raw = current_raw_from_a(std::abs(config_.motor.motor_current_a(torque)));
  r.supply_raw = supply_raw_from_v(supply_v_);
  // The board keeps an i32 that wraps.
  r.encoder_position = static_cast<std::int32_t>(static_cast<std::uint32_t>(count));
  r.encoder_time_raw =
      static_cast<std::uint16_t>((b.encoder.last_edge_ns - b.power_up_ns) * 3 / 1'000'000);
  r.applied_duty_raw = duty_raw_from_fraction(std::min(1.0, std::abs(applied_duty_)));
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
  const double torque = drive_torque(applied_duty_, state_.dq1);

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
    t.applied_duty = applied_duty_;
    t.arm_torque_nm = torque;
    t.delivered = delivered;
    truth_.push_back(t);
  }
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

DeviceInfo SimulatedRig::Impl::info_of(RigBoard board) const {
  DeviceInfo info;
  info.vendor_id = kPhidgetsVendorId;
  if (board == RigBoard::motor_1065) {
    info.product_id = kProductMotorControl1065;
    info.serial = config_.serial_1065;
    info.firmware_version = config_.firmware_1065;
    info.path = "sim:1065";
    info.input_report_bytes = config_.input_report_bytes_1065;
    info.output_report_bytes = config_.output_report_bytes_1065;
  } else {
    info.product_id = kProductEncoder1047;
    info.serial = config_.serial_1047;
    info.firmware_version = config_.firmware_1047;
    info.path = "sim:1047";
    info.input_report_bytes = config_.input_report_bytes_1047;
    info.output_report_bytes = k1047OutputReportBytes;
    info.vendor_class_interface = config_.firmware_1047 >= 200;
  }
  info.product_name = std::string(phidget_product_name(info.product_id));
  return info;
}

std::vector<DeviceInfo> SimulatedRig::Impl::devices() const {
  std::lock_guard lock(mutex_);
  std::vector<DeviceInfo> out;
  for (int i = 0; i < kBoardCount; ++i) {
    if (boards_[i].connected) out.push_back(info_of(static_cast<RigBoard>(i)));
  }
  return out;
}

TransportStatus SimulatedRig::Impl::open(std::uint64_t handle, const DeviceMatch& match,
                                         RigBoard& board, DeviceInfo& info) {
  if (match.vendor_id != kPhidgetsVendorId) return TransportStatus::not_found;
  if (match.product_id == kProductMotorControl1065) {
    board = RigBoard::motor_1065;
  } else if (match.product_id == kProductEncoder1047) {
    board = RigBoard::encoder_1047;
  } else {
    return TransportStatus::not_found;
  }
  const std::string& serial =
      board == RigBoard::motor_1065 ? config_.serial_1065 : config_.serial_1047;
  if (match.serial && *match.serial != serial) return TransportStatus::not_found;

  std::lock_guard lock(mutex_);
  advance_locked(clock_.now_ns());
  Board& b = board_of(board);
  if (!b.connected) return TransportStatus::not_found;
  if (b.owner != 0 && b.owner != handle) return TransportStatus::busy;
  b.owner = handle;
  // A fresh handle sees only reports that arrive after it opened, as with a new hidraw reader.
  b.queue.clear();
  info = info_of(board);
  return TransportStatus::ok;
}

void SimulatedRig::Impl::release(std::uint64_t handle, RigBoard board) {
  std::lock_guard lock(mutex_);
  Board& b = board_of(board);
  if (b.owner != handle) return;  // a stale handle after a disconnect owns nothing
  b.owner = 0;
  b.queue.clear();
}

TransportStatus SimulatedRig::Impl::read(std::uint64_t handle, RigBoard board, UsbReport& report,
                                         std::chrono::nanoseconds timeout) {
  const std::int64_t deadline =
      clock_.now_ns() + std::max<std::int64_t>(0, static_cast<std::int64_t>(timeout.count()));
  for (;;) {
    const std::int64_t now = clock_.now_ns();
    std::int64_t wake = 0;
    {
      std::lock_guard lock(mutex_);
      advance_locked(now);
      if (!handle_valid(handle, board)) return TransportStatus::disconnected;
      Board& b = board_of(board);
      if (!b.queue.empty() && b.queue.front().delivery_ns <= now) {
        const PendingReport& p = b.queue.front();
        std::copy_n(p.bytes.begin(), p.length, report.bytes.begin());
        report.length = p.length;
        report.host_time_ns = p.delivery_ns;
        b.queue.pop();
        return report.length < input_report_bytes(board) ? TransportStatus::short_report
                                                         : TransportStatus::ok;
      }
      if (now >= deadline) return TransportStatus::timeout;
      wake = std::min(next_delivery_estimate(b), deadline);
    }
    // Sleep without the lock so that the other board's handle and the fault API stay usable.
    clock_.sleep_until_ns(wake);
  }
}

TransportStatus SimulatedRig::Impl::write(std::uint64_t handle, RigBoard board,
                                          std::span<const std::uint8_t> bytes) {
  std::lock_guard lock(mutex_);
  advance_locked(clock_.now_ns());
  if (!handle_valid(handle, board)) return TransportStatus::disconnected;
  if (board == RigBoard::motor_1065) {
    if (bytes.size() != config_.output_report_bytes_1065) return TransportStatus::invalid_argument;
    MotorOutput1065 output;
    if (decode_output_1065(bytes, output) != CodecStatus::ok) {
      return TransportStatus::invalid_argument;
    }
    motor_output_ = output;
    target_duty_ = output.duty_cycle();
    if (config_.record_motor_commands) {
      motor_commands_.push_back({clock_.now_ns(), target_duty_, false});
    }
  } else {
    if (bytes.size() != k1047OutputReportBytes) return TransportStatus::invalid_argument;
    std::uint8_t mask = 0;
    if (decode_output_1047(bytes, mask) != CodecStatus::ok)
      return TransportStatus::invalid_argument;
    enable_mask_ = mask;
  }
  return TransportStatus::ok;
}

void SimulatedRig::Impl::drop_reports(RigBoard board, int count) {
  std::lock_guard lock(mutex_);
  advance_locked(clock_.now_ns());
  board_of(board).faults.drop = std::max(0, count);
}

void SimulatedRig::Impl::delay_reports(RigBoard board, int count, std::int64_t extra_latency_ns) {
  std::lock_guard lock(mutex_);
  advance_locked(clock_.now_ns());
  FaultPlan& f = board_of(board).faults;
  f.delay = std::max(0, count);
  f.delay_ns = std::max<std::int64_t>(0, extra_latency_ns);
}

void SimulatedRig::Impl::truncate_reports(RigBoard board, int count, std::size_t length_bytes) {
  std::lock_guard lock(mutex_);
  advance_locked(clock_.now_ns());
  FaultPlan& f = board_of(board).faults;
  f.truncate = std::max(0, count);
  f.truncate_bytes = length_bytes;
}

void SimulatedRig::Impl::corrupt_reports(RigBoard board, int count) {
  std::lock_guard lock(mutex_);
  advance_locked(clock_.now_ns());
  board_of(board).faults.corrupt = std::max(0, count);
}

void SimulatedRig::Impl::stall(RigBoard board, std::int64_t duration_ns) {
  std::lock_guard lock(mutex_);
  const std::int64_t now = clock_.now_ns();
  advance_locked(now);
  FaultPlan& f = board_of(board).faults;
  f.stall_until_ns = std::max(f.stall_until_ns, now + std::max<std::int64_t>(0, duration_ns));
}

void SimulatedRig::Impl::disconnect(RigBoard board) {
  std::lock_guard lock(mutex_);
  advance_locked(clock_.now_ns());
  Board& b = board_of(board);
  b.connected = false;
  b.owner = 0;
  b.queue.clear();
  // Inferred: the 1065's logic is powered from USB, so unplugging it stops the H-bridge (coast).
  if (board == RigBoard::motor_1065) {
    reset_motor();
    if (config_.record_motor_commands) motor_commands_.push_back({clock_.now_ns(), 0.0, true});
  }
}

void SimulatedRig::Impl::reconnect(RigBoard board) {
  std::lock_guard lock(mutex_);
  advance_locked(clock_.now_ns());
  Board& b = board_of(board);
  if (b.connected) return;
  b.connected = true;
  power_up(board);
}

void SimulatedRig::Impl::stick_encoder(RigBoard board, bool stuck) {
  std::lock_guard lock(mutex_);
  advance_locked(clock_.now_ns());
  const double angle = board == RigBoard::motor_1065 ? state_.q1 : state_.q2;
  board_of(board).encoder.set_stuck(stuck, angle);
}

void SimulatedRig::Impl::set_supply_voltage(double volts) {
  std::lock_guard lock(mutex_);
  advance_locked(clock_.now_ns());
  supply_v_ = volts;
}

void SimulatedRig::Impl::set_over_temperature(bool on) {
  std::lock_guard lock(mutex_);
  advance_locked(clock_.now_ns());
  over_temperature_ = on;
}

void SimulatedRig::Impl::set_under_voltage(bool on) {
  std::lock_guard lock(mutex_);
  advance_locked(clock_.now_ns());
  under_voltage_ = on;
}

void SimulatedRig::Impl::clamp_arm(bool clamped) {
  std::lock_guard lock(mutex_);
  advance_locked(clock_.now_ns());
  arm_clamped_ = clamped;
  if (clamped) state_.dq1 = 0.0;
}

namespace {

class SimulatedTransport final : public Transport {
 public:
  explicit SimulatedTransport(SimulatedRig::Impl& rig) : rig_(rig), id_(rig.new_handle_id()) {}
  ~SimulatedTransport() override { close(); }

  TransportStatus open(const DeviceMatch& match) override {
    close();
    const TransportStatus status = rig_.open(id_, match, board_, info_);
    open_ = status == TransportStatus::ok;
    return status;
  }
  TransportStatus read_report(UsbReport& report, std::chrono::nanoseconds timeout) override {
    if (!open_) return TransportStatus::not_open;
    return rig_.read(id_, board_, report, timeout);
  }
  TransportStatus write_report(std::span<const std::uint8_t> report) override {
    if (!open_) return TransportStatus::not_open;
    return rig_.write(id_, board_, report);
  }
  void close() override {
    if (!open_) return;
    rig_.release(id_, board_);
    open_ = false;
  }
  bool is_open() const override { return open_; }
  const DeviceInfo& device_info() const override { return info_; }

 private:
  SimulatedRig::Impl& rig_;
  const std::uint64_t id_;
  bool open_ = false;
  RigBoard board_ = RigBoard::motor_1065;
  DeviceInfo info_;
};

}  // namespace

SimulatedRig::SimulatedRig(SimulatedRigConfig config, Clock& clock)
    : impl_(std::make_unique<Impl>(std::move(config), clock)) {}
SimulatedRig::~SimulatedRig() = default;

std::unique_ptr<Transport> SimulatedRig::make_transport() {
  return std::make_unique<SimulatedTransport>(*impl_);
}
std::vector<DeviceInfo> SimulatedRig::devices() const {
  return impl_->devices();
}
void SimulatedRig::drop_reports(RigBoard board, int count) {
  impl_->drop_reports(board, count);
}
void SimulatedRig::delay_reports(RigBoard board, int count, std::int64_t extra_latency_ns) {
  impl_->delay_reports(board, count, extra_latency_ns);
}
void SimulatedRig::truncate_reports(RigBoard board, int count, std::size_t length_bytes) {
  impl_->truncate_reports(board, count, length_bytes);
}
void SimulatedRig::corrupt_reports(RigBoard board, int count) {
  impl_->corrupt_reports(board, count);
}
void SimulatedRig::stall(RigBoard board, std::int64_t duration_ns) {
  impl_->stall(board, duration_ns);
}
void SimulatedRig::disconnect(RigBoard board) {
  impl_->disconnect(board);
}
void SimulatedRig::reconnect(RigBoard board) {
  impl_->reconnect(board);
}
void SimulatedRig::stick_encoder(RigBoard board, bool stuck) {
  impl_->stick_encoder(board, stuck);
}
void SimulatedRig::set_supply_voltage(double volts) {
  impl_->set_supply_voltage(volts);
}
void SimulatedRig::set_over_temperature(bool on) {
  impl_->set_over_temperature(on);
}
void SimulatedRig::set_under_voltage(bool on) {
  impl_->set_under_voltage(on);
}
void SimulatedRig::clamp_arm(bool clamped) {
  impl_->clamp_arm(clamped);
}
const SimulatedRigConfig& SimulatedRig::config() const {
  return impl_->config();
}
const model::Parameters<double>& SimulatedRig::true_parameters() const {
  return impl_->config().parameters;
}
model::PendulumState SimulatedRig::true_state() const {
  return impl_->true_state();
}
std::int64_t SimulatedRig::physics_time_ns() const {
  return impl_->physics_time_ns();
}
const std::vector<TruthRecord>& SimulatedRig::truth() const {
  return impl_->truth();
}
const std::vector<MotorCommandRecord>& SimulatedRig::motor_commands() const {
  return impl_->motor_commands();
}
void SimulatedRig::advance_to_now() {
  impl_->advance_to_now();
}
std::int64_t SimulatedRig::now_ns() const {
  return impl_->now_ns();
}
std::unique_ptr<UsbBus> SimulatedRig::make_usb_bus() {
  return make_simulated_usb_bus(*this);
}

}  // namespace furuta::bridge
