// Figures for the firmware bridge: codec costs on the loop's path, and how much faster than real
// time the simulated rig runs in virtual time. Run: build/release/bench/firmware_bridge_bench
#include <benchmark/benchmark.h>

#include <array>

#include "furuta/firmware_bridge/codec_1047.hpp"
#include "furuta/firmware_bridge/codec_1065.hpp"
#include "furuta/simulator/simulated_rig.hpp"

namespace {

using namespace furuta::bridge;
using furuta::sim::SimulatedRig;
using furuta::sim::SimulatedRigConfig;

void BM_Decode1065Input(benchmark::State& state) {
  MotorReport1065 in;
  in.encoder_position = -123456;
  in.packet_counter = 7;
  std::array<std::uint8_t, 25> bytes{};
  encode_input_1065(in, bytes);
  MotorReport1065 out;
  for (auto _ : state) {
    benchmark::DoNotOptimize(decode_input_1065(bytes, out));
    benchmark::DoNotOptimize(out.applied_duty());
  }
}
BENCHMARK(BM_Decode1065Input);

void BM_Decode1047Input(benchmark::State& state) {
  EncoderReport1047 in;
  in.channels[0].position_delta = -17;
  in.channels[0].packet_time_ticks = 96000;
  std::array<std::uint8_t, 40> bytes{};
  encode_input_1047(in, bytes);
  EncoderReport1047 out;
  for (auto _ : state) benchmark::DoNotOptimize(decode_input_1047(bytes, out));
}
BENCHMARK(BM_Decode1047Input);

void BM_Encode1065Command(benchmark::State& state) {
  std::array<std::uint8_t, 8> bytes{};
  double duty = 0.3;
  for (auto _ : state) {
    MotorOutput1065 output;
    to_output_1065({duty, 6250.0, 0.0, false, false}, output);
    benchmark::DoNotOptimize(encode_output_1065(output, bytes));
    duty = -duty;
  }
}
BENCHMARK(BM_Encode1065Command);

// One iteration = one 16 ms control cycle against the simulated rig in virtual time: drain both
// boards, write a command. items_per_second / 62.5 = how many times faster than real time.
void BM_SimulatedRigCycleVirtualTime(benchmark::State& state) {
  VirtualClock clock(0);
  SimulatedRigConfig config;
  config.record_truth = false;
  config.pendulum_angle_noise_rad = 1e-3;
  config.usb_latency_jitter_ns = 1'000'000;
  SimulatedRig rig(config, clock);
  auto motor = rig.make_transport();
  auto encoder = rig.make_transport();
  motor->open({kPhidgetsVendorId, kProductMotorControl1065, {}});
  encoder->open({kPhidgetsVendorId, kProductEncoder1047, {}});
  const std::array<std::uint8_t, 1> enable{1};
  encoder->write_report(enable);
  std::array<std::uint8_t, 4> command{0x01, 0x4D, 0xFF, 0x00};
  UsbReport report;
  std::int64_t t = 0;
  for (auto _ : state) {
    t += 16'000'000;
    clock.sleep_until_ns(t);
    while (motor->read_report(report, std::chrono::nanoseconds(0)) == TransportStatus::ok) {
    }
    while (encoder->read_report(report, std::chrono::nanoseconds(0)) == TransportStatus::ok) {
    }
    command[0] ^= 0x01;  // bang-bang: flip the direction every cycle
    motor->write_report(command);
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["x_real_time"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * 0.016, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_SimulatedRigCycleVirtualTime);

}  // namespace
