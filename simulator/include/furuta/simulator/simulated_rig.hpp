#pragma once
// The simulated rig: a 1065 and a 1047 that speak the boards' byte protocol, with the pendulum's
// physics behind them, known true parameters, injectable faults and injectable time.
//
// Physics advances lazily to the Clock's time whenever a transport reads or writes, so with a
// VirtualClock a test runs minutes of rig time in milliseconds, and with a MonotonicClock reads
// block in real time like the hardware. Everything random comes from the seed: the same seed and
// the same calls at the same times give the same bytes.

#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "furuta/firmware_bridge/clock.hpp"
#include "furuta/firmware_bridge/codec_1047.hpp"
#include "furuta/firmware_bridge/codec_1065.hpp"
#include "furuta/firmware_bridge/transport.hpp"
#include "furuta/firmware_bridge/usb_device.hpp"
#include "furuta/model/model.hpp"

namespace furuta::sim {

enum class RigBoard : std::uint8_t { motor_1065 = 0, encoder_1047 = 1 };

// The latest tap time: its nanoseconds stay well inside the rig's int64 clock.
inline constexpr double kMaxTapTimeS = 1e9;

// A tap: an angular impulse on the pendulum's joint at one instant, the push a balance controller
// is tested against. It changes the generalized momentum M(q) dq by [0, impulse] at once, so the
// velocities jump by M(q)^-1 [0, impulse] and the angles do not move.
struct Tap {
  double time_s = 0.0;        // on the rig's clock, after its construction; in [0, kMaxTapTimeS]
  double impulse_nm_s = 0.0;  // N m s, positive towards positive q2
};

struct SimulatedRigConfig {
  model::Parameters<double> parameters = model::paper_run1();
  model::MotorData motor{};
  model::PendulumState initial_state{};

  double integration_step_s = 1e-4;
  std::int64_t report_period_ns = 8'000'000;
  std::int64_t encoder_report_phase_ns = 3'000'000;  // 1047 reports are offset from the 1065's

  double motor_encoder_counts_per_rev = 1024.0;  // motor shaft, before the gears
  double pendulum_encoder_counts_per_rev = 4096.0;
  int pendulum_channel = 0;  // 1047 input wired to the pendulum

  double arm_angle_noise_rad = 0.0;       // std dev, added before quantisation
  double pendulum_angle_noise_rad = 0.0;  // std dev, added before quantisation
  double supply_noise_v = 0.0;  // std dev of the 1065's supply reading, before quantisation
  std::int64_t usb_latency_ns = 1'000'000;
  std::int64_t usb_latency_jitter_ns = 0;  // uniform in [0, jitter]

  double supply_voltage_v = 12.0;
  std::uint64_t seed = 1;

  // Strictly increasing times, finite impulses. Each lands exactly at its time: a physics step
  // ends there, so the result does not depend on the step or on when the host polls.
  std::vector<Tap> taps;

  std::string serial_1065 = "300001";
  int firmware_1065 = 105;
  std::size_t input_report_bytes_1065 = 25;
  std::size_t output_report_bytes_1065 = 4;
  std::string serial_1047 = "300002";
  // 1xx: a HID board; 2xx and later: a vendor-class interface (as the 1047_2), ticking at 6 MHz.
  int firmware_1047 = 101;
  std::size_t input_report_bytes_1047 = 40;
  // wMaxPacketSize of the vendor-class 1047's IN endpoint: its 40-byte reports come in a 64-byte
  // endpoint. (A HID board's endpoint is as long as its report.)
  std::uint16_t usb_packet_bytes_1047 = 64;

  bool record_truth =
      true;  // keep a TruthRecord per generated report (allocates; off for RT tests)
  // Keep a MotorCommandRecord per command the 1065 takes (allocates): what a soak checks the
  // daemon's stops against.
  bool record_motor_commands = false;
};

// What really happened at each report: for tests that check decoded data against the truth.
struct TruthRecord {
  RigBoard board = RigBoard::motor_1065;
  std::int64_t generated_ns = 0;  // board time the report describes
  std::int64_t report_index = 0;  // per board, counting dropped reports too
  model::PendulumState state{};
  double applied_duty = 0.0;
  double arm_torque_nm = 0.0;
  bool delivered = true;  // false when a fault dropped it
  // The taps on the pendulum since this board's previous report, summed (N m s); a tap at the
  // report's own time is in it, and in its state.
  double tap_impulse_nm_s = 0.0;
};

// A tap as it was applied: the state the instant before and after it.
struct TapRecord {
  std::int64_t time_ns = 0;  // the rig's clock
  double impulse_nm_s = 0.0;
  model::PendulumState before{};
  model::PendulumState after{};
};

// What the 1065 was told to do, and when it took it.
struct MotorCommandRecord {
  std::int64_t time_ns = 0;
  double duty = 0.0;  // the target duty written, -1..1
  // Not a command: the board lost its USB power (unplugged) and stopped driving; duty is 0.
  bool power_loss = false;
};

class SimulatedRig {
 public:
  SimulatedRig(SimulatedRigConfig config, bridge::Clock& clock);
  ~SimulatedRig();
  SimulatedRig(const SimulatedRig&) = delete;
  SimulatedRig& operator=(const SimulatedRig&) = delete;

  // A new USB handle onto this rig; open() it with the product id of the board wanted.
  // The rig must outlive its transports.
  std::unique_ptr<bridge::Transport> make_transport();
  // What discovery would list: the boards currently connected.
  std::vector<bridge::DeviceInfo> devices() const;
  // The rig as a USB bus: the boards with their descriptors (bcdDevice, interface class, endpoints,
  // HID report descriptor) and their control and interrupt endpoints, for the USB transport and
  // discovery (make_usb_transport, discover_phidgets). A vendor-class 1047 answers only the
  // vendor's interface-recipient write request. The rig must outlive the bus.
  std::unique_ptr<bridge::UsbBus> make_usb_bus();

  // --- faults (each applies to reports generated from now on) ---
  void drop_reports(RigBoard board, int count);
  void delay_reports(RigBoard board, int count, std::int64_t extra_latency_ns);
  void truncate_reports(RigBoard board, int count, std::size_t length_bytes);
  void corrupt_reports(RigBoard board, int count);  // flips seeded random bits
  // Reports generated during the stall are held and delivered together when it ends.
  void stall(RigBoard board, std::int64_t duration_ns);
  // Open handles fail with disconnected; the board resets as on power-up when reconnected
  // (1065: motor off, position and packet counter restart; 1047: channels disabled).
  void disconnect(RigBoard board);
  void reconnect(RigBoard board);
  void stick_encoder(RigBoard board, bool stuck);
  void set_supply_voltage(double volts);
  void set_over_temperature(bool on);
  void set_under_voltage(bool on);
  // Hold the arm still (for physics checks of the pendulum alone).
  void clamp_arm(bool clamped);

  // --- truth ---
  const SimulatedRigConfig& config() const;
  const model::Parameters<double>& true_parameters() const;
  model::PendulumState true_state() const;  // at the time physics has reached
  std::int64_t physics_time_ns() const;
  const std::vector<TruthRecord>& truth() const;
  // Empty unless config.record_motor_commands. Read while no transport is in use.
  const std::vector<MotorCommandRecord>& motor_commands() const;
  // The configured taps applied so far, in order (kept without allocating: the room for all of
  // them is taken at construction). Read while no transport is in use.
  const std::vector<TapRecord>& taps() const;
  // Brings physics up to the clock's time (reads and writes do this themselves).
  void advance_to_now();
  std::int64_t now_ns() const;  // the rig's clock

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace furuta::sim
