#pragma once
// Private to the simulator: the simulated rig's state (SimulatedRig::Impl) and its parts,
// shared by simulated_rig.cpp (the boards' USB side: open, read, write, faults, the public API) and
// simulated_rig_physics.cpp (the model integrated, reports generated on the boards' clocks).

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>
#include <random>
#include <stdexcept>
#include <utility>

#include "furuta/model/duty_ramp.hpp"
#include "furuta/simulator/simulated_rig.hpp"

namespace furuta::sim {

namespace detail {

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

inline int board_index(RigBoard board) {
  return static_cast<int>(board);
}

struct PendingReport {
  std::array<std::uint8_t, bridge::kMaxReportBytes> bytes{};
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

inline bool consume(int& remaining) {
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

}  // namespace detail

// The duty per second the board ramps at for a written command (model::DutyRamp's rate).
double duty_rate_per_s(const bridge::MotorOutput1065& output);

class SimulatedRig::Impl {
 public:
  Impl(SimulatedRigConfig config, bridge::Clock& clock);

  // --- called by the transports ---
  std::uint64_t new_handle_id() {
    std::lock_guard lock(mutex_);
    return next_handle_id_++;
  }
  bridge::TransportStatus open(std::uint64_t handle, const bridge::DeviceMatch& match,
                               RigBoard& board, bridge::DeviceInfo& info);
  void release(std::uint64_t handle, RigBoard board);
  bridge::TransportStatus read(std::uint64_t handle, RigBoard board, bridge::UsbReport& report,
                               std::chrono::nanoseconds timeout);
  bridge::TransportStatus write(std::uint64_t handle, RigBoard board,
                                std::span<const std::uint8_t> bytes);

  // --- the rig's own API ---
  std::vector<bridge::DeviceInfo> devices() const;
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
  const std::vector<TapRecord>& taps() const { return tap_records_; }
  void advance_to_now() {
    std::lock_guard lock(mutex_);
    advance_locked(clock_.now_ns());
  }

 private:
  bridge::DeviceInfo info_of(RigBoard board) const;
  detail::Board& board_of(RigBoard board) { return boards_[detail::board_index(board)]; }
  // The arm torque at `duty`; `idle`: the board has no PWM (duty exactly 0), so it brakes.
  double drive_torque(double duty, double dq1, bool idle) const;
  void reset_motor();
  void power_up(RigBoard board);
  void advance_locked(std::int64_t t_ns);
  void integrate_to(std::int64_t t_ns);
  // Applies every configured tap whose time physics has reached.
  void apply_due_taps();
  void generate(RigBoard board, std::int64_t generated_ns);
  std::size_t build_1065(double torque, std::span<std::uint8_t> out);
  std::size_t build_1047(std::int64_t generated_ns, std::span<std::uint8_t> out);
  void corrupt(detail::PendingReport& report);
  std::int64_t next_delivery_estimate(const detail::Board& b) const;
  bool handle_valid(std::uint64_t handle, RigBoard board) const {
    const detail::Board& b = boards_[detail::board_index(board)];
    return b.connected && b.owner == handle;
  }
  std::size_t input_report_bytes(RigBoard board) const {
    return board == RigBoard::motor_1065 ? config_.input_report_bytes_1065
                                         : config_.input_report_bytes_1047;
  }

  const SimulatedRigConfig config_;
  bridge::Clock& clock_;
  mutable std::mutex mutex_;

  std::int64_t t0_ns_ = 0;
  std::int64_t step_ns_ = 0;
  std::int64_t physics_ns_ = 0;
  model::PendulumState state_{};
  bool arm_clamped_ = false;

  // 1065 motor drive.
  bridge::MotorOutput1065 motor_output_{};
  model::DutyRamp duty_;  // the applied duty ramping towards the newest command
  double supply_v_ = 0.0;
  bool over_temperature_ = false;
  bool under_voltage_ = false;

  // 1047.
  std::uint8_t enable_mask_ = 0;
  double tick_ns_1047_ = 0.0;
  std::uint32_t packet_time_ticks_ = 0;

  std::array<detail::Board, detail::kBoardCount> boards_{};

  std::mt19937_64 noise_rng_;
  std::array<std::mt19937_64, detail::kBoardCount> jitter_rng_;
  std::mt19937_64 corrupt_rng_;
  std::normal_distribution<double> standard_normal_{0.0, 1.0};

  std::vector<TruthRecord> truth_;
  std::vector<MotorCommandRecord> motor_commands_;

  // Taps: their times on the rig's clock, the next one to apply, what each did, and the impulse
  // each board's next truth record reports.
  std::vector<std::int64_t> tap_ns_;
  std::size_t next_tap_ = 0;
  std::vector<TapRecord> tap_records_;
  std::array<double, detail::kBoardCount> tap_since_report_{};
  std::uint64_t next_handle_id_ = 1;
};

}  // namespace furuta::sim
