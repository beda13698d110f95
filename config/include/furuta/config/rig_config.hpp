#pragma once
// The rig configuration (TOML): boards, encoder geometry, motor data, the simulated rig.
// Unknown keys are errors, not ignored: a mistyped limit must never become a silent default.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>

#include "furuta/firmware_bridge/encoder_geometry.hpp"
#include "furuta/firmware_bridge/rig_model.hpp"
#include "furuta/firmware_bridge/simulated_rig.hpp"

namespace furuta::config {

// A configuration problem, located: "rig.toml:12: encoders.arm.counts_per_rev: must be > 0".
class ConfigError : public std::runtime_error {
 public:
  ConfigError(std::string file, int line, std::string field, const std::string& problem);
  const std::string& file() const { return file_; }
  int line() const { return line_; }  // 0 when the problem has no line (a missing key)
  const std::string& field() const { return field_; }

 private:
  std::string file_;
  int line_;
  std::string field_;
};

enum class UsbBackend : std::uint8_t { simulated, hidapi, libusb };

struct BoardSelection {
  std::optional<std::string> serial;  // none: the first board of that product
};

struct RigConfig {
  std::string name;
  UsbBackend backend = UsbBackend::simulated;
  BoardSelection motor_board;    // 1065
  BoardSelection encoder_board;  // 1047
  int pendulum_channel = 0;
  bridge::EncoderGeometry arm_encoder;  // gear_ratio = motor.total_ratio()
  bridge::EncoderGeometry pendulum_encoder;
  bridge::MotorData motor;
  bridge::SimulatedRigConfig simulation;           // geometry and motor copied in from the above
  std::optional<bridge::ModelParameters> nominal;  // CAD values, for comparison only
  std::string source_text;                         // the file verbatim, so logs can carry it
  std::string source_name;
};

RigConfig load_rig_config(const std::filesystem::path& path);  // throws ConfigError
RigConfig parse_rig_config(const std::string& text, const std::string& source_name);
// The configuration shipped in config/rig.toml, for tools run without --config.
std::filesystem::path default_rig_config_path();

}  // namespace furuta::config
