#include "furuta/simulator/simulated_rig.hpp"

#include "furuta/firmware_bridge/phidget_ids.hpp"
#include "simulated_rig_impl.hpp"
#include "simulated_usb.hpp"

namespace furuta::sim {

using namespace bridge;  // NOLINT(google-build-using-namespace): the boards' types and codecs
using namespace detail;  // NOLINT(google-build-using-namespace): this file is the rig's own

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
    duty_.command(output.duty_cycle(), duty_rate_per_s(output));
    if (config_.record_motor_commands) {
      motor_commands_.push_back({clock_.now_ns(), duty_.target(), false});
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
const std::vector<TapRecord>& SimulatedRig::taps() const {
  return impl_->taps();
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

}  // namespace furuta::sim
