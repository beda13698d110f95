// rig.toml: parse_rig_config, which reads it one section at a time, and the readers of the rig's
// own sections ([rig], [boards.*], [motor], [encoders.*], [simulation], [nominal]). The daemon's
// and identification's sections are read in daemon_sections.cpp and identification_sections.cpp.
#include "furuta/config/rig_config.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <sstream>

#include "furuta/config/toml_section.hpp"
#include "furuta/firmware_bridge/board_roles.hpp"
#include "sections.hpp"

namespace furuta::config {

namespace {

using detail::fraction;
using detail::kDegToRad;
using detail::non_negative;
using detail::non_negative_integer;
using detail::positive;

bool unit_sign(std::int64_t v) {
  return v == 1 || v == -1;
}

bridge::EncoderGeometry read_encoder(Section s, double default_cpr) {
  bridge::EncoderGeometry g;
  g.counts_per_rev = s.number("counts_per_rev", default_cpr, positive, "> 0");
  // An encoder counts whole steps: a fraction is a typo (or a gear ratio folded in, which
  // motor_ratio and gear_ratio hold), and would scale every angle the rig reports.
  if (g.counts_per_rev != std::floor(g.counts_per_rev)) {
    s.fail("counts_per_rev", s.node("counts_per_rev"),
           "must be a whole number of counts (e.g. 1024; the gear ratios are [motor]'s)");
  }
  g.sign = static_cast<int>(s.integer("sign", 1, unit_sign, "1 or -1"));
  g.zero_offset_rad = s.number("zero_offset_deg", 0.0) * kDegToRad;
  s.reject_unknown_keys();
  return g;
}

model::Parameters<double> read_parameters(Section s, const model::Parameters<double>& d) {
  // The inertias on the diagonal of M are positive, gravity's and the frictions' coefficients
  // not negative; mu2 and mu3 take either sign (docs/model.md).
  struct Rule {
    Section::NumberRule valid;
    const char* text;
  };
  const std::array<Rule, model::kParameterCount> rules = {Rule{positive, "> 0"},
                                                          Rule{{}, ""},
                                                          Rule{{}, ""},
                                                          Rule{positive, "> 0"},
                                                          Rule{non_negative, ">= 0"},
                                                          Rule{non_negative, ">= 0"},
                                                          Rule{non_negative, ">= 0"}};
  model::Parameters<double> p;
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    p[k] = s.number(model::kParameterNames[k], d[k], rules[k].valid, rules[k].text);
  }
  s.reject_unknown_keys();
  return p;
}

void read_rig(Section rig, RigConfig& c) {
  c.name = rig.text("name", "furuta");
  c.backend = rig.choice("backend", UsbBackend::simulated,
                         {{"simulated", UsbBackend::simulated},
                          {"hidapi", UsbBackend::hidapi},
                          {"libusb", UsbBackend::libusb}});
  rig.reject_unknown_keys();
}

BoardSelection read_board(Section& s, const std::string& model,
                          const std::vector<std::string>& models) {
  BoardSelection b;
  b.model = s.text("model", model);
  if (std::find(models.begin(), models.end(), b.model) == models.end()) {
    std::string known;
    for (const std::string& m : models) known += (known.empty() ? "" : ", ") + m;
    s.fail("model", s.node("model"),
           "'" + b.model + "' is not a board this build has an adapter for (" + known + ")");
  }
  const std::string serial = s.text("serial", "");
  if (!serial.empty()) b.serial = serial;
  b.allow_untested_firmware = s.boolean("allow_untested_firmware", false);
  return b;
}

// [boards.motor] (the motor board) and [boards.encoder] (the encoder board, and the pendulum's
// channel on it).
void read_boards(Section boards, RigConfig& c) {
  Section motor = boards.child("motor");
  c.motor_board = read_board(motor, RigConfig{}.motor_board.model, bridge::motor_board_kinds());
  motor.reject_unknown_keys();
  Section encoder = boards.child("encoder");
  c.encoder_board =
      read_board(encoder, RigConfig{}.encoder_board.model, bridge::encoder_board_kinds());
  c.pendulum_channel = static_cast<int>(encoder.integer(
      "pendulum_channel", 0, [](std::int64_t v) { return v >= 0 && v < 4; }, "0..3"));
  encoder.reject_unknown_keys();
  boards.reject_unknown_keys();
}

model::MotorData read_motor(Section motor) {
  const model::MotorData dm;
  model::MotorData m;
  m.rotor_inertia_kg_m2 =
      motor.number("rotor_inertia_kg_m2", dm.rotor_inertia_kg_m2, non_negative, ">= 0");
  m.no_load_speed_rpm = motor.number("no_load_speed_rpm", dm.no_load_speed_rpm, positive, "> 0");
  m.speed_torque_gradient_rpm_per_nm = motor.number(
      "speed_torque_gradient_rpm_per_nm", dm.speed_torque_gradient_rpm_per_nm, positive, "> 0");
  m.motor_efficiency = motor.number("motor_efficiency", dm.motor_efficiency, fraction, "in (0, 1]");
  m.gear_efficiency = motor.number("gear_efficiency", dm.gear_efficiency, fraction, "in (0, 1]");
  m.motor_ratio = motor.number("motor_ratio", dm.motor_ratio, positive, "> 0");
  m.gear_ratio = motor.number("gear_ratio", dm.gear_ratio, positive, "> 0");
  m.nominal_voltage_v = motor.number("nominal_voltage_v", dm.nominal_voltage_v, positive, "> 0");
  motor.reject_unknown_keys();
  return m;
}

// [encoders.arm] and [encoders.pendulum]; the arm's gear ratio is the motor's (read before).
void read_encoders(Section encoders, RigConfig& c) {
  c.arm_encoder = read_encoder(encoders.child("arm"), 1024.0);
  c.arm_encoder.gear_ratio = c.motor.total_ratio();
  c.pendulum_encoder = read_encoder(encoders.child("pendulum"), 4096.0);
  encoders.reject_unknown_keys();
}

// [simulation.initial_state], in degrees.
void read_initial_state(Section x0, sim::SimulatedRigConfig& s) {
  s.initial_state.q1 = x0.number("q1_deg", 0.0) * kDegToRad;
  s.initial_state.dq1 = x0.number("dq1_deg_per_s", 0.0) * kDegToRad;
  s.initial_state.q2 = x0.number("q2_deg", 0.0) * kDegToRad;
  s.initial_state.dq2 = x0.number("dq2_deg_per_s", 0.0) * kDegToRad;
  x0.reject_unknown_keys();
}

// tap_times_s and tap_impulse_mnm_s: the taps on the simulated pendulum, with one impulse for
// every tap or one per tap.
void read_taps(Section& sim, sim::SimulatedRigConfig& s) {
  const std::vector<double> times = sim.number_list(
      "tap_times_s", {}, [](double v) { return v >= 0 && v <= sim::kMaxTapTimeS; }, "in [0, 1e9]");
  for (std::size_t i = 1; i < times.size(); ++i) {
    // Taps are applied in order: an unordered list is a typo, not a schedule to sort.
    if (!(times[i] > times[i - 1])) {
      sim.fail("tap_times_s", sim.node("tap_times_s")->as_array()->get(i),
               "must be strictly increasing");
    }
  }
  std::vector<double> impulses_mnm_s;
  const toml::node* impulse = sim.node("tap_impulse_mnm_s");
  if (impulse && impulse->is_array()) {
    impulses_mnm_s = sim.number_list("tap_impulse_mnm_s", {});
    if (impulses_mnm_s.size() != times.size()) {
      sim.fail("tap_impulse_mnm_s", impulse,
               "must be one number or an array as long as tap_times_s (" +
                   std::to_string(times.size()) + ")");
    }
  } else {
    impulses_mnm_s.assign(times.size(), sim.number("tap_impulse_mnm_s", 0.0));
  }
  s.taps.clear();
  for (std::size_t i = 0; i < times.size(); ++i) {
    s.taps.push_back({times[i], impulses_mnm_s[i] * 1e-3});
  }
}

// [simulation]: the simulated rig's own settings (its boards are the configured ones, see
// simulate_the_configured_rig).
sim::SimulatedRigConfig read_simulation(Section sim) {
  sim::SimulatedRigConfig s;
  s.seed = static_cast<std::uint64_t>(sim.integer("seed", 1, non_negative_integer, ">= 0"));
  s.integration_step_s = sim.number(
      "integration_step_s", s.integration_step_s, [](double v) { return v > 0 && v <= 1e-3; },
      "in (0, 1e-3]");
  s.arm_angle_noise_rad = sim.number("arm_angle_noise_rad", 0.0, non_negative, ">= 0");
  s.pendulum_angle_noise_rad = sim.number("pendulum_angle_noise_rad", 0.0, non_negative, ">= 0");
  s.usb_latency_ns = sim.integer("usb_latency_ns", s.usb_latency_ns, non_negative_integer, ">= 0");
  s.usb_latency_jitter_ns = sim.integer("usb_latency_jitter_ns", 0, non_negative_integer, ">= 0");
  s.supply_voltage_v = sim.number("supply_voltage_v", s.supply_voltage_v, positive, "> 0");
  s.supply_noise_v = sim.number("supply_noise_v", 0.05, non_negative, ">= 0");
  const auto firmware = [](std::int64_t v) { return v >= 100 && v <= 999; };
  s.firmware_1065 =
      static_cast<int>(sim.integer("firmware_1065", s.firmware_1065, firmware, "in [100, 999]"));
  s.firmware_1047 =
      static_cast<int>(sim.integer("firmware_1047", s.firmware_1047, firmware, "in [100, 999]"));
  read_taps(sim, s);
  s.parameters = read_parameters(sim.child("parameters"), model::paper_run1());
  read_initial_state(sim.child("initial_state"), s);
  sim.reject_unknown_keys();
  return s;
}

// The simulated boards are built like the configured ones.
void simulate_the_configured_rig(RigConfig& c) {
  sim::SimulatedRigConfig& s = c.simulation;
  s.motor = c.motor;
  s.motor_encoder_counts_per_rev = c.arm_encoder.counts_per_rev;
  s.pendulum_encoder_counts_per_rev = c.pendulum_encoder.counts_per_rev;
  s.pendulum_channel = c.pendulum_channel;
  if (c.motor_board.serial) s.serial_1065 = *c.motor_board.serial;
  if (c.encoder_board.serial) s.serial_1047 = *c.encoder_board.serial;
}

}  // namespace

// Sections are read in this order (a file with several problems reports the first): a section
// checked against another comes after it.
RigConfig parse_rig_config(const std::string& text, const std::string& source_name) {
  const toml::table root = parse_toml(text, source_name);
  RigConfig c;
  c.source_text = text;
  c.source_name = source_name;
  Section top(root, source_name);
  read_rig(top.child("rig"), c);
  read_boards(top.child("boards"), c);
  c.motor = read_motor(top.child("motor"));
  read_encoders(top.child("encoders"), c);
  c.simulation = read_simulation(top.child("simulation"));
  simulate_the_configured_rig(c);
  c.daemon = detail::read_daemon(top.child("daemon"));
  c.safety = detail::read_safety(top.child("safety"), c.daemon);
  c.limits = detail::read_limits(top.child("limits"), c.safety);
  c.excitation = detail::read_excitation(top.child("excitation"), c.limits,
                                         bridge::motor_board_kind(c.motor_board.model));
  c.identification = detail::read_identification(top.child("identification"), c.daemon);
  c.output_error = detail::read_output_error(top.child("output_error"));
  c.sivia = detail::read_sivia(top.child("sivia"));
  c.guaranteed = detail::read_guaranteed(top.child("guaranteed"));
  c.automation = detail::read_automation(top.child("automation"));
  Section nominal = top.child("nominal");
  if (nominal.present()) c.nominal = read_parameters(nominal, model::Parameters<double>{});
  top.reject_unknown_keys();
  return c;
}

std::string read_config_text(const std::filesystem::path& path) {
  // A directory opens as a stream that reads nothing: it would pass for an empty file.
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw ConfigError(path.string(), 0, "", "is a directory, not a file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path.string(), 0, "", "cannot open the file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw ConfigError(path.string(), 0, "", "cannot read the file");
  return text.str();
}

RigConfig load_rig_config(const std::filesystem::path& path) {
  return parse_rig_config(read_config_text(path), path.string());
}

namespace {

bool running_from_build_tree() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::canonical("/proc/self/exe", ec);
  if (ec) return false;
  const std::filesystem::path tree = std::filesystem::weakly_canonical(FURUTA_BUILD_TREE, ec);
  if (ec) return false;
  const auto [end, _] = std::mismatch(tree.begin(), tree.end(), exe.begin(), exe.end());
  return end == tree.end();
}

}  // namespace

std::filesystem::path default_rig_config_path() {
  // An installed program reads the installed file whatever is left where it was built; a program
  // run from its build tree (tests, a developer) reads the source tree's.
  if (running_from_build_tree()) return FURUTA_DEFAULT_RIG_CONFIG;
  return FURUTA_INSTALLED_RIG_CONFIG;
}

bridge::MotorResolution motor_resolution(const RigConfig& rig) {
  return bridge::make_motor_board(rig.motor_board.model, {}, {})->resolution();
}

double pendulum_resolution_rad(const RigConfig& rig) {
  return bridge::resolution_rad(rig.pendulum_encoder);
}

double arm_angle_rad(const RigConfig& rig, std::int64_t arm_counts) {
  return bridge::counts_to_rad(rig.arm_encoder, arm_counts);
}

double pendulum_angle_rad(const RigConfig& rig, std::int64_t pendulum_counts) {
  return bridge::counts_to_rad(rig.pendulum_encoder, pendulum_counts);
}

}  // namespace furuta::config
