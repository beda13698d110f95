#include "furuta/config/rig_config.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <numbers>
#include <set>
#include <sstream>

#include "furuta/config/toml_section.hpp"

namespace furuta::config {

namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

bool positive(double v) {
  return v > 0;
}
bool fraction(double v) {
  return v > 0 && v <= 1;
}
bool non_negative(double v) {
  return v >= 0;
}
bool unit_sign(std::int64_t v) {
  return v == 1 || v == -1;
}

bridge::EncoderGeometry read_encoder(Section s, double default_cpr) {
  bridge::EncoderGeometry g;
  g.counts_per_rev = s.number("counts_per_rev", default_cpr, positive, "> 0");
  g.sign = static_cast<int>(s.integer("sign", 1, unit_sign, "1 or -1"));
  g.zero_offset_rad = s.number("zero_offset_deg", 0.0) * kDegToRad;
  s.reject_unknown_keys();
  return g;
}

bridge::ModelParameters read_parameters(Section s, const bridge::ModelParameters& d) {
  bridge::ModelParameters p;
  p.mu1 = s.number("mu1", d.mu1, positive, "> 0");
  p.mu2 = s.number("mu2", d.mu2);
  p.mu3 = s.number("mu3", d.mu3);
  p.mu4 = s.number("mu4", d.mu4, positive, "> 0");
  p.mug = s.number("mug", d.mug, non_negative, ">= 0");
  p.fv1 = s.number("fv1", d.fv1, non_negative, ">= 0");
  p.fv2 = s.number("fv2", d.fv2, non_negative, ">= 0");
  s.reject_unknown_keys();
  return p;
}

}  // namespace

RigConfig parse_rig_config(const std::string& text, const std::string& source_name) {
  const toml::table root = parse_toml(text, source_name);

  RigConfig c;
  c.source_text = text;
  c.source_name = source_name;
  Section top(root, source_name);

  Section rig = top.child("rig");
  c.name = rig.text("name", "furuta");
  const std::string backend = rig.choice("backend", "simulated", {"simulated", "hidapi", "libusb"});
  c.backend = backend == "hidapi"   ? UsbBackend::hidapi
              : backend == "libusb" ? UsbBackend::libusb
                                    : UsbBackend::simulated;
  rig.reject_unknown_keys();

  Section boards = top.child("boards");
  auto read_board = [](Section& s) {
    BoardSelection b;
    const std::string serial = s.text("serial", "");
    if (!serial.empty()) b.serial = serial;
    b.allow_untested_firmware = s.boolean("allow_untested_firmware", false);
    return b;
  };
  {
    Section motor = boards.child("motor");
    c.motor_board = read_board(motor);
    motor.reject_unknown_keys();
    Section encoder = boards.child("encoder");
    c.encoder_board = read_board(encoder);
    c.pendulum_channel = static_cast<int>(encoder.integer(
        "pendulum_channel", 0, [](std::int64_t v) { return v >= 0 && v < 4; }, "0..3"));
    encoder.reject_unknown_keys();
  }
  boards.reject_unknown_keys();

  Section motor = top.child("motor");
  const bridge::MotorData dm;
  c.motor.rotor_inertia_kg_m2 =
      motor.number("rotor_inertia_kg_m2", dm.rotor_inertia_kg_m2, non_negative, ">= 0");
  c.motor.no_load_speed_rpm =
      motor.number("no_load_speed_rpm", dm.no_load_speed_rpm, positive, "> 0");
  c.motor.speed_torque_gradient_rpm_per_nm = motor.number(
      "speed_torque_gradient_rpm_per_nm", dm.speed_torque_gradient_rpm_per_nm, positive, "> 0");
  c.motor.motor_efficiency =
      motor.number("motor_efficiency", dm.motor_efficiency, fraction, "in (0, 1]");
  c.motor.gear_efficiency =
      motor.number("gear_efficiency", dm.gear_efficiency, fraction, "in (0, 1]");
  c.motor.motor_ratio = motor.number("motor_ratio", dm.motor_ratio, positive, "> 0");
  c.motor.gear_ratio = motor.number("gear_ratio", dm.gear_ratio, positive, "> 0");
  c.motor.nominal_voltage_v =
      motor.number("nominal_voltage_v", dm.nominal_voltage_v, positive, "> 0");
  motor.reject_unknown_keys();

  Section encoders = top.child("encoders");
  c.arm_encoder = read_encoder(encoders.child("arm"), 1024.0);
  c.arm_encoder.gear_ratio = c.motor.total_ratio();
  c.pendulum_encoder = read_encoder(encoders.child("pendulum"), 4096.0);
  encoders.reject_unknown_keys();

  Section sim = top.child("simulation");
  bridge::SimulatedRigConfig& s = c.simulation;
  s.seed = static_cast<std::uint64_t>(sim.integer(
      "seed", 1, [](std::int64_t v) { return v >= 0; }, ">= 0"));
  s.integration_step_s = sim.number(
      "integration_step_s", s.integration_step_s, [](double v) { return v > 0 && v <= 1e-3; },
      "in (0, 1e-3]");
  s.arm_angle_noise_rad = sim.number("arm_angle_noise_rad", 0.0, non_negative, ">= 0");
  s.pendulum_angle_noise_rad = sim.number("pendulum_angle_noise_rad", 0.0, non_negative, ">= 0");
  s.usb_latency_ns = sim.integer(
      "usb_latency_ns", s.usb_latency_ns, [](std::int64_t v) { return v >= 0; }, ">= 0");
  s.usb_latency_jitter_ns = sim.integer(
      "usb_latency_jitter_ns", 0, [](std::int64_t v) { return v >= 0; }, ">= 0");
  s.supply_voltage_v = sim.number("supply_voltage_v", s.supply_voltage_v, positive, "> 0");
  const auto firmware = [](std::int64_t v) { return v >= 100 && v <= 999; };
  s.firmware_1065 =
      static_cast<int>(sim.integer("firmware_1065", s.firmware_1065, firmware, "in [100, 999]"));
  s.firmware_1047 =
      static_cast<int>(sim.integer("firmware_1047", s.firmware_1047, firmware, "in [100, 999]"));
  s.parameters = read_parameters(sim.child("parameters"), bridge::ModelParameters::paper_run1());
  {
    Section x0 = sim.child("initial_state");
    s.initial_state.q1 = x0.number("q1_deg", 0.0) * kDegToRad;
    s.initial_state.dq1 = x0.number("dq1_deg_per_s", 0.0) * kDegToRad;
    s.initial_state.q2 = x0.number("q2_deg", 0.0) * kDegToRad;
    s.initial_state.dq2 = x0.number("dq2_deg_per_s", 0.0) * kDegToRad;
    x0.reject_unknown_keys();
  }
  sim.reject_unknown_keys();
  // The simulated boards are built like the configured ones.
  s.motor = c.motor;
  s.motor_encoder_counts_per_rev = c.arm_encoder.counts_per_rev;
  s.pendulum_encoder_counts_per_rev = c.pendulum_encoder.counts_per_rev;
  s.pendulum_channel = c.pendulum_channel;
  if (c.motor_board.serial) s.serial_1065 = *c.motor_board.serial;
  if (c.encoder_board.serial) s.serial_1047 = *c.encoder_board.serial;

  {
    Section d = top.child("daemon");
    DaemonConfig& dc = c.daemon;
    const double period_ms = d.number(
        "period_ms", 16.0, [](double v) { return v >= 0.1 && v <= 1000.0; }, "in [0.1, 1000]");
    dc.period_ns = std::llround(period_ms * 1e6);
    dc.lcm_url = d.text("lcm_url", dc.lcm_url);
    dc.logs_dir = d.text("logs_dir", dc.logs_dir);
    if (dc.logs_dir.empty()) d.fail("logs_dir", d.node("logs_dir"), "must not be empty");
    dc.flush_interval_ms = d.integer(
        "flush_interval_ms", dc.flush_interval_ms,
        [](std::int64_t v) { return v >= 10 && v <= 60'000; }, "in [10, 60000]");
    dc.rest_check_s = d.number(
        "rest_check_s", dc.rest_check_s, [](double v) { return v >= 0 && v <= 60; }, "in [0, 60]");
    dc.reconnect_interval_ms = d.integer(
        "reconnect_interval_ms", dc.reconnect_interval_ms,
        [](std::int64_t v) { return v >= 10 && v <= 10'000; }, "in [10, 10000]");
    dc.queue_capacity = d.integer(
        "queue_capacity", dc.queue_capacity,
        [](std::int64_t v) { return v >= 64 && v <= 1'000'000; }, "in [64, 1000000]");
    Section rt = d.child("realtime");
    dc.realtime = rt.boolean("enabled", dc.realtime);
    dc.fifo_priority = static_cast<int>(rt.integer(
        "fifo_priority", dc.fifo_priority, [](std::int64_t v) { return v >= 1 && v <= 99; },
        "in [1, 99]"));
    dc.cpu = static_cast<int>(rt.integer(
        "cpu", dc.cpu, [](std::int64_t v) { return v >= -1 && v < 1024; }, ">= -1"));
    dc.lock_memory = rt.boolean("lock_memory", dc.lock_memory);
    rt.reject_unknown_keys();
    d.reject_unknown_keys();
  }
  {
    Section s = top.child("safety");
    SafetyConfig& sc = c.safety;
    // Safety limits have no silent defaults from a typo: unknown keys are rejected below, and each
    // value is range-checked.
    sc.arm_limit_rad = s.number(
                           "arm_limit_deg", sc.arm_limit_rad / kDegToRad,
                           [](double v) { return v > 0 && v <= 720; }, "in (0, 720]") *
                       kDegToRad;
    sc.max_duty = s.number("max_duty", sc.max_duty, fraction, "in (0, 1]");
    sc.stale_report_cycles = static_cast<int>(s.integer(
        "stale_report_cycles", sc.stale_report_cycles,
        [](std::int64_t v) { return v >= 1 && v <= 1000; }, "in [1, 1000]"));
    // The boards report every 8 ms: fewer than two report periods of silence is not a fault.
    if (static_cast<double>(sc.stale_report_cycles) * static_cast<double>(c.daemon.period_ns) <
        16e6) {
      s.fail("stale_report_cycles", s.node("stale_report_cycles"),
             std::to_string(sc.stale_report_cycles) + " cycles of " +
                 std::to_string(c.daemon.period_ns / 1000) +
                 " us are shorter than two 8 ms report periods");
    }
    sc.min_supply_v = s.number("min_supply_v", sc.min_supply_v, non_negative, ">= 0");
    sc.max_supply_v = s.number("max_supply_v", sc.max_supply_v, positive, "> 0");
    if (sc.max_supply_v <= sc.min_supply_v) {
      // Blame the value the file gave: a min_supply_v above the default max is the min's fault.
      if (s.has("max_supply_v") || !s.has("min_supply_v")) {
        s.fail("max_supply_v", s.node("max_supply_v"), "must be above min_supply_v");
      }
      s.fail("min_supply_v", s.node("min_supply_v"), "must be below max_supply_v");
    }
    sc.stop_braking_fraction = s.number(
        "stop_braking", sc.stop_braking_fraction, [](double v) { return v >= 0 && v <= 1; },
        "in [0, 1]");
    sc.stuck_arm_cycles = static_cast<int>(s.integer(
        "stuck_arm_cycles", sc.stuck_arm_cycles, [](std::int64_t v) { return v >= 1 && v <= 1000; },
        "in [1, 1000]"));
    sc.stuck_arm_min_duty =
        s.number("stuck_arm_min_duty", sc.stuck_arm_min_duty, fraction, "in (0, 1]");
    sc.stuck_pendulum_arm_travel_rad =
        s.number(
            "stuck_pendulum_arm_travel_deg", sc.stuck_pendulum_arm_travel_rad / kDegToRad,
            [](double v) { return v > 0 && v <= 36000; }, "in (0, 36000]") *
        kDegToRad;
    s.reject_unknown_keys();
  }
  {
    Section l = top.child("limits");
    CommandLimitsConfig& lc = c.limits;
    lc.max_amplitude_duty =
        l.number("max_amplitude_duty", lc.max_amplitude_duty, fraction, "in (0, 1]");
    if (lc.max_amplitude_duty > c.safety.max_duty) {
      l.fail("max_amplitude_duty", l.node("max_amplitude_duty"), "must not exceed safety.max_duty");
    }
    lc.max_duration_s = l.number("max_duration_s", lc.max_duration_s, positive, "> 0");
    lc.max_arm_switch_rad =
        l.number("max_arm_switch_deg", lc.max_arm_switch_rad / kDegToRad, positive, "> 0") *
        kDegToRad;
    if (lc.max_arm_switch_rad >= c.safety.arm_limit_rad) {
      l.fail("max_arm_switch_deg", l.node("max_arm_switch_deg"),
             "must be below safety.arm_limit_deg");
    }
    lc.max_commands_per_s = static_cast<int>(l.integer(
        "max_commands_per_s", lc.max_commands_per_s,
        [](std::int64_t v) { return v >= 1 && v <= 1000; }, "in [1, 1000]"));
    l.reject_unknown_keys();
  }
  {
    Section e = top.child("excitation");
    ExcitationConfig& ec = c.excitation;
    ec.profile = e.choice("profile", ec.profile,
                          {"bang_bang", "free_decay", "step", "prbs", "chirp", "multisine"});
    ec.amplitude_duty = e.number("amplitude_duty", ec.amplitude_duty, fraction, "in (0, 1]");
    if (ec.amplitude_duty > c.limits.max_amplitude_duty) {
      e.fail("amplitude_duty", e.node("amplitude_duty"),
             "must not exceed limits.max_amplitude_duty");
    }
    ec.duration_s = e.number("duration_s", ec.duration_s, positive, "> 0");
    ec.seed = e.integer(
        "seed", ec.seed, [](std::int64_t v) { return v >= 0; }, ">= 0");
    ec.switch_period_s = e.number("switch_period_s", ec.switch_period_s, non_negative, ">= 0");
    ec.switch_period_jitter = e.number(
        "switch_period_jitter", ec.switch_period_jitter, [](double v) { return v >= 0 && v < 1; },
        "in [0, 1)");
    ec.arm_switch_rad =
        e.number("arm_switch_deg", ec.arm_switch_rad / kDegToRad, non_negative, ">= 0") * kDegToRad;
    if (ec.arm_switch_rad > c.limits.max_arm_switch_rad) {
      e.fail("arm_switch_deg", e.node("arm_switch_deg"),
             "must not exceed limits.max_arm_switch_deg");
    }
    ec.step_time_s = e.number("step_time_s", ec.step_time_s, non_negative, ">= 0");
    ec.prbs_bit_period_s = e.number("prbs_bit_period_s", ec.prbs_bit_period_s, positive, "> 0");
    ec.prbs_order = static_cast<int>(e.integer(
        "prbs_order", ec.prbs_order, [](std::int64_t v) { return v >= 2 && v <= 16; },
        "in [2, 16]"));
    ec.chirp_f0_hz = e.number("chirp_f0_hz", ec.chirp_f0_hz, non_negative, ">= 0");
    ec.chirp_f1_hz = e.number("chirp_f1_hz", ec.chirp_f1_hz, positive, "> 0");
    ec.multisine_components = static_cast<int>(e.integer(
        "multisine_components", ec.multisine_components,
        [](std::int64_t v) { return v >= 1 && v <= 16; }, "in [1, 16]"));
    ec.multisine_f_min_hz = e.number("multisine_f_min_hz", ec.multisine_f_min_hz, positive, "> 0");
    ec.multisine_f_max_hz = e.number("multisine_f_max_hz", ec.multisine_f_max_hz, positive, "> 0");
    ec.board_acceleration_pct_per_s = e.number(
        "board_acceleration_pct_per_s", ec.board_acceleration_pct_per_s,
        [](double v) {
          return v >= bridge::k1065MinAccelerationPctPerS &&
                 v <= bridge::k1065FullScaleAccelerationPctPerS;
        },
        "in [24.51, 6250] (the vendor library's range for the 1065)");
    e.reject_unknown_keys();
  }

  {
    Section s = top.child("identification");
    IdentificationConfig& ic = c.identification;
    const double nyquist_hz = 0.5e9 / static_cast<double>(c.daemon.period_ns);
    ic.cutoff_hz = s.number(
        "cutoff_hz", ic.cutoff_hz, [&](double v) { return v > 0 && 2 * v < nyquist_hz; },
        "in (0, Nyquist / 2) (the differentiator's stop band starts at twice it)");
    ic.butterworth_order = static_cast<int>(s.integer(
        "butterworth_order", ic.butterworth_order, [](std::int64_t v) { return v >= 1 && v <= 16; },
        "in [1, 16]"));
    ic.differentiator_taps = static_cast<int>(s.integer(
        "differentiator_taps", ic.differentiator_taps,
        [](std::int64_t v) { return v >= 5 && v <= 201 && v % 2 == 1; }, "odd, in [5, 201]"));
    if (s.has("input_lag_ms")) {
      ic.input_lag_ms = s.number(
          "input_lag_ms", 0.0, [](double v) { return std::abs(v) <= 100; }, "in [-100, 100]");
    }
    s.reject_unknown_keys();
  }

  {
    Section s = top.child("sivia");
    SiviaConfig& sc = c.sivia;
    sc.unknowns =
        s.choices("unknowns", sc.unknowns, {"mu1", "mu2", "mu3", "mu4", "mug", "fv1", "fv2"});
    if (sc.unknowns.empty())
      s.fail("unknowns", s.node("unknowns"), "must name at least one parameter");
    sc.mu_uncertainty_pct =
        s.numbers("mu_uncertainty_pct", sc.mu_uncertainty_pct, non_negative, ">= 0");
    const auto ordered_prior = [&](const char* key, std::array<double, 2> fallback) {
      const std::array<double, 2> v = s.numbers(key, fallback);
      if (!(v[0] < v[1])) s.fail(key, s.node(key), "must be [low, high] with low < high");
      return v;
    };
    sc.fv1_prior = ordered_prior("fv1", sc.fv1_prior);
    sc.fv2_prior = ordered_prior("fv2", sc.fv2_prior);
    sc.epsilon = s.number("epsilon", sc.epsilon, positive, "> 0");
    sc.epsilon_relative = s.boolean("epsilon_relative", sc.epsilon_relative);
    sc.contract = s.boolean("contract", sc.contract);
    sc.inner_test = s.choice("inner_test", sc.inner_test,
                             {"witness", "intermediate_value", "for_all_data", "none"});
    sc.q = static_cast<int>(s.integer(
        "q", sc.q, [](std::int64_t v) { return v >= 0; }, ">= 0"));
    sc.threads = static_cast<int>(s.integer(
        "threads", sc.threads, [](std::int64_t v) { return v >= 0 && v <= 1024; }, "in [0, 1024]"));
    sc.q2_bound = s.numbers("q2_bound", sc.q2_bound, non_negative, ">= 0");
    sc.dq1_bound = s.numbers("dq1_bound", sc.dq1_bound, non_negative, ">= 0");
    sc.dq2_bound = s.numbers("dq2_bound", sc.dq2_bound, non_negative, ">= 0");
    sc.ddq1_bound = s.numbers("ddq1_bound", sc.ddq1_bound, non_negative, ">= 0");
    sc.ddq2_bound = s.numbers("ddq2_bound", sc.ddq2_bound, non_negative, ">= 0");
    sc.tau_bound = s.numbers("tau_bound", sc.tau_bound, non_negative, ">= 0");
    s.reject_unknown_keys();
  }

  {
    Section s = top.child("automation");
    AutomationConfig& ac = c.automation;
    ac.fit_labels = s.names("fit_labels", ac.fit_labels);
    if (ac.fit_labels.empty())
      s.fail("fit_labels", s.node("fit_labels"), "must name at least one label");
    ac.fit_sessions = static_cast<int>(s.integer(
        "fit_sessions", ac.fit_sessions, [](std::int64_t v) { return v >= 1 && v <= 100; },
        "in [1, 100]"));
    ac.validation_label = s.text("validation_label", ac.validation_label);
    // A session cannot be both fitted and held out: the validation would not be independent.
    if (std::find(ac.fit_labels.begin(), ac.fit_labels.end(), ac.validation_label) !=
        ac.fit_labels.end()) {
      s.fail("validation_label", s.node("validation_label"),
             "'" + ac.validation_label + "' is also one of fit_labels");
    }
    ac.sivia = s.boolean("sivia", ac.sivia);
    ac.simulate = s.boolean("simulate", ac.simulate);
    ac.simulate_seconds = s.number(
        "simulate_seconds", ac.simulate_seconds, [](double v) { return v >= 0.01 && v <= 60; },
        "in [0.01, 60]");
    ac.identifications_dir = s.text("identifications_dir", ac.identifications_dir);
    if (ac.identifications_dir.empty()) {
      s.fail("identifications_dir", s.node("identifications_dir"), "must not be empty");
    }
    s.reject_unknown_keys();
  }

  Section nominal = top.child("nominal");
  if (nominal.present()) c.nominal = read_parameters(nominal, bridge::ModelParameters{});

  top.reject_unknown_keys();
  return c;
}

std::string read_config_text(const std::filesystem::path& path) {
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

std::filesystem::path default_rig_config_path() {
  const std::filesystem::path installed = FURUTA_INSTALLED_RIG_CONFIG;
  const std::filesystem::path source = FURUTA_DEFAULT_RIG_CONFIG;
  if (std::filesystem::exists(source)) return source;
  return installed;
}

}  // namespace furuta::config
