// `furuta simulate`: a bang-bang session on the simulated rig, recorded at the USB level, decoded,
// checked against the rig's truth, and replayed from the recording to show the replay reproduces
// it.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <memory>
#include <ostream>

#include "bridge_session.hpp"
#include "commands.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/firmware_bridge/replay_transport.hpp"
#include "furuta/firmware_bridge/simulated_rig.hpp"
#include "furuta/firmware_bridge/usb_trace.hpp"

namespace furuta::app {

namespace {

void write_csv(const std::filesystem::path& path, const std::vector<BridgeSample>& samples,
               std::int64_t start_ns) {
  std::ofstream csv(path);
  csv << "t_s,arm_counts,pendulum_counts,q1_rad,q2_rad,commanded_duty,applied_duty,current_a,"
         "supply_v,motor_reports,encoder_reports,motor_lost,encoder_lost\n";
  csv << std::setprecision(9);
  for (const BridgeSample& s : samples) {
    csv << static_cast<double>(s.time_ns - start_ns) * 1e-9 << ',' << s.arm_counts << ','
        << s.pendulum_counts << ',' << s.arm_angle_rad << ',' << s.pendulum_angle_rad << ','
        << s.commanded_duty << ',' << s.applied_duty << ',' << s.motor_current_a << ','
        << s.supply_voltage_v << ',' << s.motor_reports << ',' << s.encoder_reports << ','
        << s.motor_lost_total << ',' << s.encoder_lost_total << '\n';
  }
  if (!csv) throw std::runtime_error("cannot write " + path.string());
}

// Largest difference between a decoded angle and the truth at the report it came from.
struct TruthCheck {
  double arm_max_error_rad = 0;
  double pendulum_max_error_rad = 0;
};

TruthCheck check_against_truth(const bridge::SimulatedRig& rig,
                               const std::vector<BridgeSample>& samples) {
  TruthCheck check;
  const auto& truth = rig.truth();
  // Both sequences are in time order, so one forward pass per board finds, for each sample, the
  // newest delivered report generated no later than it was received.
  struct Cursor {
    std::size_t next = 0;
    const bridge::TruthRecord* best = nullptr;
  };
  auto truth_at = [&](Cursor& c, bridge::RigBoard board,
                      std::int64_t host_ns) -> const bridge::TruthRecord* {
    while (c.next < truth.size() && truth[c.next].generated_ns <= host_ns) {
      const auto& t = truth[c.next++];
      if (t.board == board && t.delivered) c.best = &t;
    }
    return c.best;
  };
  Cursor arm, pendulum;
  for (const BridgeSample& s : samples) {
    if (s.motor_reports > 0) {
      if (const auto* t = truth_at(arm, bridge::RigBoard::motor_1065, s.motor_report_host_ns)) {
        check.arm_max_error_rad =
            std::max(check.arm_max_error_rad, std::abs(s.arm_angle_rad - t->state.q1));
      }
    }
    if (s.encoder_reports > 0) {
      if (const auto* t =
              truth_at(pendulum, bridge::RigBoard::encoder_1047, s.encoder_report_host_ns)) {
        check.pendulum_max_error_rad =
            std::max(check.pendulum_max_error_rad, std::abs(s.pendulum_angle_rad - t->state.q2));
      }
    }
  }
  return check;
}

}  // namespace

int run_simulate_command(const SimulateOptions& options, std::ostream& out, std::ostream& err) {
  const config::RigConfig rig_config = config::load_rig_config(options.config_path);
  bridge::SimulatedRigConfig sim = rig_config.simulation;
  if (options.seed) sim.seed = *options.seed;

  std::unique_ptr<bridge::Clock> clock;
  if (options.real_time) {
    clock = std::make_unique<bridge::MonotonicClock>();
  } else {
    clock = std::make_unique<bridge::VirtualClock>(0);
  }
  const std::int64_t start_ns = clock->now_ns();
  bridge::SimulatedRig rig(sim, *clock);

  bridge::RecordingTransport motor(rig.make_transport(), *clock);
  bridge::RecordingTransport encoder(rig.make_transport(), *clock);
  if (auto s = motor.open({bridge::kPhidgetsVendorId, bridge::kProductMotorControl1065, {}});
      s != bridge::TransportStatus::ok) {
    err << "furuta simulate: cannot open the simulated 1065: " << bridge::to_string(s) << "\n";
    return 2;
  }
  if (auto s = encoder.open({bridge::kPhidgetsVendorId, bridge::kProductEncoder1047, {}});
      s != bridge::TransportStatus::ok) {
    err << "furuta simulate: cannot open the simulated 1047: " << bridge::to_string(s) << "\n";
    return 2;
  }

  BridgeSessionSpec spec;
  spec.duration_s = options.duration_s;
  spec.amplitude_duty = options.amplitude_duty;
  spec.switch_period_s = options.switch_period_s;
  spec.pendulum_channel = rig_config.pendulum_channel;
  spec.arm_encoder = rig_config.arm_encoder;
  spec.pendulum_encoder = rig_config.pendulum_encoder;

  const BridgeSessionResult live = run_bridge_session(motor, encoder, *clock, spec);
  motor.close();
  encoder.close();

  std::filesystem::create_directories(options.output_dir);
  const auto csv_path = options.output_dir / "samples.csv";
  const auto motor_trace_path = options.output_dir / "motor_1065.trace";
  const auto encoder_trace_path = options.output_dir / "encoder_1047.trace";
  write_csv(csv_path, live.samples, start_ns);
  bridge::write_usb_trace(motor_trace_path, motor.trace());
  bridge::write_usb_trace(encoder_trace_path, encoder.trace());

  // Replay both recordings on a fresh virtual clock and decode them with the same session code: the
  // decoded values must come out identical, and every command written must match the recorded one.
  bridge::VirtualClock replay_clock(start_ns);
  bridge::ReplayTransport motor_replay(bridge::read_usb_trace(motor_trace_path), replay_clock);
  bridge::ReplayTransport encoder_replay(bridge::read_usb_trace(encoder_trace_path), replay_clock);
  motor_replay.open({bridge::kPhidgetsVendorId, bridge::kProductMotorControl1065, {}});
  encoder_replay.open({bridge::kPhidgetsVendorId, bridge::kProductEncoder1047, {}});
  const BridgeSessionResult replayed =
      run_bridge_session(motor_replay, encoder_replay, replay_clock, spec);
  const bool replay_identical = replayed.samples == live.samples &&
                                motor_replay.mismatches().empty() &&
                                encoder_replay.mismatches().empty();

  const TruthCheck truth = check_against_truth(rig, live.samples);
  double arm_min = 0, arm_max = 0, pend_min = 0, pend_max = 0;
  for (const BridgeSample& s : live.samples) {
    arm_min = std::min(arm_min, s.arm_angle_rad);
    arm_max = std::max(arm_max, s.arm_angle_rad);
    pend_min = std::min(pend_min, s.pendulum_angle_rad);
    pend_max = std::max(pend_max, s.pendulum_angle_rad);
  }
  const BridgeSample last = live.samples.empty() ? BridgeSample{} : live.samples.back();
  constexpr double kDeg = 180.0 / 3.14159265358979323846;

  out << std::fixed << std::setprecision(2);
  out << "simulated rig '" << rig_config.name << "', seed " << sim.seed << ", "
      << (options.real_time ? "real time" : "virtual time") << "\n";
  out << "  session: " << live.samples.size() << " cycles of 16 ms, bang-bang duty +-"
      << options.amplitude_duty << " every " << options.switch_period_s
      << " s; stopped: " << live.stop_reason << "\n";
  out << "  arm angle    [" << arm_min * kDeg << ", " << arm_max * kDeg << "] deg, "
      << "max error vs truth " << std::setprecision(4) << truth.arm_max_error_rad * kDeg << " deg\n"
      << std::setprecision(2);
  out << "  pendulum     [" << pend_min * kDeg << ", " << pend_max * kDeg << "] deg, "
      << "max error vs truth " << std::setprecision(4) << truth.pendulum_max_error_rad * kDeg
      << " deg\n"
      << std::setprecision(2);
  out << "  lost reports 1065: " << last.motor_lost_total << ", 1047: " << last.encoder_lost_total
      << "\n";
  out << "  replay of the recorded USB traffic: "
      << (replay_identical ? "identical decoded values" : "DIFFERS") << " ("
      << replayed.samples.size() << " cycles)\n";
  out << "  wrote " << csv_path.string() << ", " << motor_trace_path.string() << ", "
      << encoder_trace_path.string() << "\n";
  return (live.transport_errors == 0 && replay_identical) ? 0 : 1;
}

}  // namespace furuta::app
