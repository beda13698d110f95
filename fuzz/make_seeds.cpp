// Writes the generated part of the seed corpus (fuzz/corpus/<target>/) with the project's own
// encoders, so the seeds are real reports, commands and logs rather than hand-typed bytes:
//   fuzz_make_seeds <corpus dir>
// The configuration and CSV seeds are plain text files kept in the repository as they are.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <span>
#include <string>
#include <vector>

#include "furuta/command_auth/command_auth.hpp"
#include "furuta/command_auth/status_signature.hpp"
#include "furuta/firmware_bridge/clock.hpp"
#include "furuta/firmware_bridge/codec_1047.hpp"
#include "furuta/firmware_bridge/codec_1065.hpp"
#include "furuta/firmware_bridge/phidget_ids.hpp"
#include "furuta/firmware_bridge/usb_trace.hpp"
#include "furuta/rig_command_t.hpp"
#include "furuta/rig_status_t.hpp"
#include "furuta/session_log/lcm_log.hpp"
#include "furuta/session_log/session_log.hpp"
#include "furuta/simulator/simulated_rig.hpp"

namespace fs = std::filesystem;
using namespace furuta;

namespace {

void write(const fs::path& path, std::span<const std::uint8_t> bytes) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
}

template <typename Message>
std::vector<std::uint8_t> encode(const Message& m) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(out.data(), 0, static_cast<int>(out.size()));
  return out;
}

rig_command_t command(std::int8_t kind, const std::string& profile = "", double amplitude = 0,
                      double duration = 0, const std::string& label = "", std::int64_t seed = 0) {
  rig_command_t c{};
  c.request_id = 7;
  c.kind = kind;
  c.profile = profile;
  c.amplitude_duty = amplitude;
  c.duration_s = duration;
  c.label = label;
  c.seed = seed;
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: fuzz_make_seeds <corpus dir>\n";
    return 2;
  }
  const fs::path root = argv[1];

  // 1065: an input report as the protocol notes describe one (25 bytes, padded to the device's
  // 32), and output reports of the 4-byte layout.
  bridge::MotorReport1065 in;
  in.digital_inputs = 0x01;
  in.status_flags = bridge::k1065FlagBackEmfValid | bridge::k1065FlagActualDirection;
  in.current_raw = 0x0123;
  in.analog_raw[0] = 2048;
  in.supply_raw = bridge::supply_raw_from_v(12.0);
  in.back_emf_plus_raw = 300;
  in.back_emf_minus_raw = 100;
  in.encoder_position = -123456;
  in.encoder_time_raw = 3000;
  in.applied_duty_raw = 77;
  in.commanded_duty_raw = 77;
  in.acceleration_raw = 255;
  in.packet_counter = 41;
  std::vector<std::uint8_t> report(32);
  bridge::encode_input_1065(in, report);
  write(root / "fuzz_codec_1065" / "input_report_32", report);
  write(root / "fuzz_codec_1065" / "input_report_25", std::span(report).first(25));
  const std::uint8_t output[] = {0x05, 0x80, 0x80, 0x40, 0, 0, 0, 0};
  write(root / "fuzz_codec_1065" / "output_report_8", output);

  // 1047: four channels, as in the codec's test (position +5 and -3, full packet time).
  bridge::EncoderReport1047 enc;
  enc.channels[0] = {5, 0, 96000, 0x0123, 0x03};
  enc.channels[1] = {-3, -0x7FFF, 0xFFFFFF, 0xFFFF, 0x06};
  enc.channels[2] = {-0x8000, 12, 48000, 0, 0x02};
  std::vector<std::uint8_t> enc_bytes(40);
  bridge::encode_input_1047(enc, enc_bytes);
  write(root / "fuzz_codec_1047" / "input_report_40", enc_bytes);
  write(root / "fuzz_codec_1047" / "enable_mask", std::vector<std::uint8_t>{0x01});

  // Commands: what `furuta start`, `stop`, `estop` and `status` send.
  const std::vector<std::pair<std::string, rig_command_t>> commands = {
      {"start_bang_bang",
       command(rig_command_t::KIND_START_SESSION, "bang_bang", 0.3, 10, "run-1", 1)},
      {"start_multisine",
       command(rig_command_t::KIND_START_SESSION, "multisine", 0.2, 30, "ms", 4)},
      {"start_prbs", command(rig_command_t::KIND_START_SESSION, "prbs", 0.5, 600, "", 0)},
      {"stop", command(rig_command_t::KIND_STOP)},
      {"estop", command(rig_command_t::KIND_ESTOP)},
      {"status", command(rig_command_t::KIND_STATUS_REQUEST)},
  };
  for (const auto& [name, c] : commands) {
    const std::vector<std::uint8_t> bytes = encode(c);
    write(root / "fuzz_command_decode" / name, bytes);
    // The handler's input: repeats, milliseconds between them, the message. One, and a flood.
    std::vector<std::uint8_t> once = {0, 0};
    once.insert(once.end(), bytes.begin(), bytes.end());
    write(root / "fuzz_command_handler" / name, once);
    std::vector<std::uint8_t> flood = {63, 1};
    flood.insert(flood.end(), bytes.begin(), bytes.end());
    write(root / "fuzz_command_handler" / (name + "_flood"), flood);
  }

  // Signed commands as `furuta start` sends them (the key fuzz_signed_command checks with), and
  // the daemon's signed statuses as the tools receive them.
  command_auth::CommandKey fuzz_key{};
  for (std::size_t i = 0; i < fuzz_key.size(); ++i)
    fuzz_key[i] = static_cast<std::uint8_t>(3 * i + 1);
  const std::int64_t signed_at = 1'800'000'000'000'000'000;
  for (const auto& [name, c] : commands) {
    write(root / "fuzz_signed_command" / name,
          encode(command_auth::sign_command(c, fuzz_key, "ana@rig", signed_at, 1)));
  }
  const command_auth::StatusSigner daemon_key(command_auth::CommandKey{42});
  rig_status_t status{};
  status.state = rig_status_t::STATE_RUNNING;
  status.session = "2026-11-28T12-00-00Z_run1";
  status.cycles = 625;
  status.reply_to_request_id = 7;
  daemon_key.sign(status);
  write(root / "fuzz_status_reply" / "running", encode(status));
  status.request_accepted = false;
  status.request_reason = "bad signature from \"\\x1b[2J\": not signed with this rig's command key";
  status.refused_bad_signature = 1;
  daemon_key.sign(status);
  write(root / "fuzz_status_reply" / "refused", encode(status));

  // A short session log as the daemon writes it: start, samples, USB traffic, a fault, end.
  bridge::VirtualClock clock(1'000'000'000);
  sim::SimulatedRig rig(sim::SimulatedRigConfig{}, clock);
  auto motor = rig.make_transport();
  auto encoder = rig.make_transport();
  motor->open({bridge::kPhidgetsVendorId, bridge::kProductMotorControl1065, {}});
  encoder->open({bridge::kPhidgetsVendorId, bridge::kProductEncoder1047, {}});
  const fs::path tmp = fs::temp_directory_path() / "furuta-make-seeds";
  fs::remove_all(tmp);
  {
    session_log::LcmLogWriter writer({tmp, std::chrono::milliseconds(1000)}, "seed");
    rig_session_t start{};
    start.event = rig_session_t::EVENT_START;
    start.session = "seed";
    start.label = "seed";
    start.profile = "bang_bang";
    start.amplitude_duty = 0.3;
    start.duration_s = 0.048;
    start.seed = 1;
    start.period_ns = 16'000'000;
    start.monotonic_ns = 1'000'000'000;
    start.rig_config_toml = "[safety]\nmax_duty = 0.6\n";
    start.software_version = "0.1.0";
    start.motor_device = bridge::format_trace_device_line(motor->device_info());
    start.encoder_device = bridge::format_trace_device_line(encoder->device_info());
    writer.write(session_log::kChannelSession, start.monotonic_ns / 1000, encode(start));
    for (int i = 0; i < 3; ++i) {
      const std::int64_t t = 1'000'000'000 + i * 16'000'000;
      rig_usb_report_t usb{};
      usb.time_ns = t;
      usb.board = rig_usb_report_t::BOARD_MOTOR;
      usb.kind = rig_usb_report_t::KIND_INPUT;
      usb.bytes.assign(report.begin(), report.end());
      usb.length = static_cast<std::int16_t>(usb.bytes.size());
      writer.write(session_log::kChannelUsb, t / 1000, encode(usb));
      usb.board = rig_usb_report_t::BOARD_ENCODER;
      usb.bytes.assign(enc_bytes.begin(), enc_bytes.end());
      usb.length = static_cast<std::int16_t>(usb.bytes.size());
      writer.write(session_log::kChannelUsb, t / 1000, encode(usb));
      usb.board = rig_usb_report_t::BOARD_MOTOR;
      usb.kind = rig_usb_report_t::KIND_OUTPUT;
      usb.bytes.assign(std::begin(output), std::end(output));
      usb.length = static_cast<std::int16_t>(usb.bytes.size());
      writer.write(session_log::kChannelUsb, t / 1000, encode(usb));
      rig_sample_t s{};
      s.seq = i == 2 ? 3 : i;  // one sample lost
      s.monotonic_ns = t;
      s.session = "seed";
      s.arm_counts = 10 * i;
      s.commanded_duty = 0.3;
      s.supply_voltage_v = 12.0;
      s.n_motor_reports = 2;
      s.motor_report_host_ns = {t - 8'000'000, t};
      s.motor_packet_counter = {1, 2};
      s.motor_encoder_time = {100, 200};
      s.n_encoder_reports = 1;
      s.encoder_report_host_ns = {t};
      s.encoder_packet_ticks = {96000};
      s.encoder_delta_counts = {5};
      writer.write(session_log::kChannelSample, t / 1000, encode(s));
    }
    rig_fault_t fault{};
    fault.monotonic_ns = 1'040'000'000;
    fault.session = "seed";
    fault.seq = 2;
    fault.reason = "lost_reports";
    fault.detail = "1 sample";
    writer.write(session_log::kChannelFault, fault.monotonic_ns / 1000, encode(fault));
    rig_session_t end = start;
    end.event = rig_session_t::EVENT_END;
    end.monotonic_ns = 1'048'000'000;
    end.samples = 3;
    end.end_reason = "duration_reached";
    writer.write(session_log::kChannelSession, end.monotonic_ns / 1000, encode(end));
    fs::path final_path;
    writer.finish(&final_path);
    fs::create_directories(root / "fuzz_log_reader");
    fs::copy_file(final_path, root / "fuzz_log_reader" / "session.lcmlog",
                  fs::copy_options::overwrite_existing);
    // The same log cut short inside its last event, as a crash leaves it.
    fs::copy_file(final_path, root / "fuzz_log_reader" / "session_truncated.lcmlog",
                  fs::copy_options::overwrite_existing);
    fs::resize_file(root / "fuzz_log_reader" / "session_truncated.lcmlog",
                    fs::file_size(final_path) - 20);
  }
  fs::remove_all(tmp);
  std::cout << "seeds written under " << root << "\n";
  return 0;
}
