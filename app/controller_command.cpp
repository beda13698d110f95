// `furuta controller design`: the balance controller from an identification's results.json
// (control/, docs/control.md), written as a controller file the daemon's balance session reads.
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <ostream>
#include <sstream>

#include "commands.hpp"
#include "furuta/config/config_error.hpp"
#include "furuta/config/controller_file.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/control/balance_law.hpp"
#include "furuta/control/upright_lqr.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/firmware_bridge/phidget_ids.hpp"
#include "furuta/identification/identify.hpp"
#include "furuta/report/json.hpp"
#include "furuta/report/run_directory.hpp"

namespace furuta::app {

namespace {

// The parameters named by --parameters, or why the results file has none.
std::optional<model::Parameters<double>> chosen(const report::ResultsFile& r,
                                                ControllerParameters source, std::string& why) {
  switch (source) {
    case ControllerParameters::output_error:
      if (!r.output_error) why = "no converged output-error estimate (output_error.estimate)";
      return r.output_error;
    case ControllerParameters::lsmi:
      if (!r.lsmi) why = "no LSMI estimate (combined.estimate)";
      return r.lsmi;
    case ControllerParameters::cad:
      if (!r.nominal) why = "no CAD values (nominal: the configuration had no [nominal])";
      return r.nominal;
  }
  return std::nullopt;
}

// Every double in the shortest text that reads back as the same double (std::to_chars, in %g's
// style: an exponent only for the very small and the very large), so the file is read back into
// the design's numbers; with a decimal point or exponent, so that TOML reads a float where one is
// meant.
std::string exact(double v) {
  std::array<char, 64> buffer{};
  const auto [end, ec] =
      std::to_chars(buffer.data(), buffer.data() + buffer.size(), v, std::chars_format::general);
  std::string text(buffer.data(), ec == std::errc() ? end : buffer.data());
  if (text.find_first_of(".en") == std::string::npos) text += ".0";  // "n": inf and nan
  return text;
}

// Degrees in the file, for a person to read: the reader multiplies by the same factor.
constexpr double kDegToRad = std::numbers::pi / 180.0;

// A TOML basic string: quotes and backslashes escaped, control characters as \uXXXX.
std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (u < 0x20 || u == 0x7F) {
      std::ostringstream code;
      code << "\\u" << std::hex << std::setw(4) << std::setfill('0') << static_cast<int>(u);
      out += code.str();
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string array_text(const std::vector<double>& values) {
  std::string text = "[";
  for (std::size_t i = 0; i < values.size(); ++i) text += (i ? ", " : "") + exact(values[i]);
  return text + "]";
}

}  // namespace

const char* to_string(ControllerParameters source) {
  switch (source) {
    case ControllerParameters::output_error:
      return "output-error";
    case ControllerParameters::lsmi:
      return "lsmi";
    case ControllerParameters::cad:
      return "cad";
  }
  return "?";
}

int run_controller_design_command(const ControllerDesignOptions& options, std::ostream& out,
                                  std::ostream& err) {
  const auto refuse = [&](const std::string& what) {
    err << "furuta controller design: " << what << "\n";
    return kExitNotDone;
  };
  if (options.output.empty()) return refuse("-o is empty: give the controller file to write");
  if (report::same_file(options.output, options.results) ||
      report::same_file(options.output, options.config_path)) {
    return refuse("-o " + options.output.string() + " is one of the inputs: give another file");
  }
  report::ResultsFile results;
  try {
    results = report::read_results(options.results);
  } catch (const report::ResultsFileError& e) {
    return refuse(options.results.string() + ": " + e.what());
  }
  std::string why;
  const auto parameters = chosen(results, options.parameters, why);
  if (!parameters) {
    return refuse(options.results.string() + " has " + why + ": choose another --parameters");
  }
  const config::RigConfig rig = config::load_rig_config(options.config_path);
  const double supply_v = options.supply_v.value_or(rig.backend == config::UsbBackend::simulated
                                                        ? rig.simulation.supply_voltage_v
                                                        : rig.motor.nominal_voltage_v);
  const double period_s = static_cast<double>(rig.daemon.period_ns) * 1e-9;
  const double lag_s = rig.identification.input_lag_ms.value_or(0.0) * 1e-3;
  // The board ramps every new duty at its acceleration: on a typical balance step that is a short
  // delay, which the design adds to the data path's lag.
  const double ramp_lag_s =
      control::ramp_lag_s(rig.excitation.board_acceleration_pct_per_s, control::kRampStepDuty);
  // The filter takes each duty as the board does: after the data path's lag, ramped to.
  const control::DutyPath duty_path{lag_s, rig.excitation.board_acceleration_pct_per_s / 100};
  const control::DesignPlant plant{*parameters, rig.motor, supply_v};
  const double max_duty = rig.limits.max_amplitude_duty;
  control::BalanceGain gain;
  control::ObserverGain observer;
  control::ObserverWeights observer_weights;
  // The filter trusts each angle to within a count of its encoder.
  observer_weights.arm_count_rad = bridge::resolution_rad(rig.arm_encoder);
  observer_weights.pendulum_count_rad = bridge::resolution_rad(rig.pendulum_encoder);
  // A board's newest report is anywhere from just read to a report period old at a sample: the
  // gain is designed for the middle of that, and the loop gives each reading's own age.
  observer_weights.reading_age_s =
      0.5 * std::min(period_s, static_cast<double>(bridge::kReportPeriodNs) * 1e-9);
  control::BalanceControllerSpec spec;
  try {
    const control::SampledPlant sampled =
        control::sample(control::linearize_upright(plant), period_s, lag_s + ramp_lag_s);
    gain = control::design_lqr(sampled, options.weights);
    observer = control::design_observer(sampled, observer_weights);
    spec = control::balance_spec(plant, sampled, gain, observer, duty_path, max_duty,
                                 config::motor_resolution(rig).duty_step);
  } catch (const std::exception& e) {
    return refuse(std::string("the design failed: ") + e.what());
  }
  const control::SwingUp& swing_up = spec.swing_up;
  const control::CatchRegion& region = spec.region;

  std::ostringstream file;
  file << "# A balance controller designed by `furuta controller design` (docs/control.md): the "
          "model\n# linearised about upright, sampled at the loop period with the data path's "
          "lag and the\n# board's duty ramp, a discrete LQR; the swing-up, catch region and limits "
          "the loop runs.\n\n";
  file << "[controller]\nkind = " << quoted(std::string(config::kUprightLqrKind))
       << "\nrig = " << quoted(rig.name) << "\nperiod_ns = " << rig.daemon.period_ns
       << "\nlag_s = " << exact(lag_s) << "\n# the duty ramp as a delay on a step of "
       << "ramp_step_duty; the design's lag is lag_s + ramp_lag_s\nramp_lag_s = "
       << exact(ramp_lag_s) << "\nramp_step_duty = " << exact(control::kRampStepDuty)
       << "\n# the board's ramp itself (duty per second), which the filter "
          "follows\nramp_duty_per_s = "
       << exact(duty_path.ramp_duty_per_s) << "\nsupply_v = " << exact(supply_v)
       << "\ndesigned_by = " << quoted(daemon::kSoftwareVersion) << "\n\n";
  file << "[parameters]\nsource = \"" << to_string(options.parameters)
       << "\"\nresults = " << quoted(std::filesystem::weakly_canonical(options.results).string())
       << "\nresults_sha256 = \"" << identification::sha256_file(options.results.string())
       << "\"\n";
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    file << model::kParameterNames[k] << " = " << exact((*parameters)[k]) << "\n";
  }
  const control::LqrWeights& w = options.weights;
  file << "\n[weights]\nq1 = " << exact(w.state[0]) << "\nq2 = " << exact(w.state[1])
       << "\ndq1 = " << exact(w.state[2]) << "\ndq2 = " << exact(w.state[3])
       << "\nduty = " << exact(w.duty) << "\n\n";
  std::vector<double> k(gain.k.data(), gain.k.data() + gain.k.size());
  file << "[gain]\n# duty = -k . [q1, q2 - pi, dq1, dq2, the duties still on their way, oldest "
          "first]\nk = "
       << array_text(k) << "\n\n";
  std::vector<double> re, im;
  for (const auto& pole : gain.closed_loop_poles) {
    re.push_back(pole.real());
    im.push_back(pole.imag());
  }
  file << "[prediction]\nclosed_loop_poles_re = " << array_text(re)
       << "\nclosed_loop_poles_im = " << array_text(im)
       << "\nspectral_radius = " << exact(gain.spectral_radius) << "\n\n";
  std::vector<double> m;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 2; ++j) m.push_back(observer.m(i, j));
  }
  file << "[observer]\n# the filter's velocities: x^ = x^- + m ([q1, q2 - pi] - y^), m "
          "row-major 4 x 2,\n# x^- the last sample's predicted state, y^ its angles carried "
          "to when the angles were read\n# (reading_age_s before this sample, typically)\n"
       << "arm_acceleration_sd = " << exact(observer_weights.arm_acceleration_sd)
       << "\npendulum_acceleration_sd = " << exact(observer_weights.pendulum_acceleration_sd)
       << "\narm_count_rad = " << exact(observer_weights.arm_count_rad)
       << "\npendulum_count_rad = " << exact(observer_weights.pendulum_count_rad)
       << "\nreading_age_s = " << exact(observer.reading_age_s) << "\nm = " << array_text(m)
       << "\n# the error's largest pole at reading_age_s, and at the worst age in [0, period]"
       << "\nspectral_radius = " << exact(observer.spectral_radius)
       << "\nworst_spectral_radius = " << exact(observer.worst_spectral_radius) << "\n\n";
  file << "[drive]\n# eq. 4 at supply_v: torque = duty_torque_nm duty - back_emf_nm_s dq1\n"
       << "duty_torque_nm = " << exact(spec.duty_torque_nm)
       << "\nback_emf_nm_s = " << exact(spec.back_emf_nm_s) << "\n\n";
  file << "[swing_up]\nenergy_gain = " << exact(swing_up.energy_gain)
       << "\nmax_acceleration = " << exact(swing_up.max_acceleration)
       << "\narm_gain = " << exact(swing_up.arm_gain)
       << "\narm_damping = " << exact(swing_up.arm_damping)
       << "\nmax_duty = " << exact(swing_up.max_duty)
       << "\nenergy_margin = " << exact(swing_up.energy_margin)
       << "\nstart_below_energy_ratio = " << exact(swing_up.start_below_energy_ratio)
       << "\nstart_acceleration = " << exact(swing_up.start_acceleration)
       << "\npump_arm_deg = " << exact(swing_up.pump_arm_rad / kDegToRad) << "\n\n";
  file << "[catch]\n# angles from upright; the catch only where the gain asks for at most "
          "entry_duty_ratio of max_duty\ncatch_deg = "
       << exact(region.catch_rad / kDegToRad)
       << "\nentry_duty_ratio = " << exact(region.entry_duty_ratio)
       << "\nrelease_deg = " << exact(region.release_rad / kDegToRad)
       << "\nsettle_s = " << exact(region.settle_s)
       << "\nfall_deg = " << exact(region.fall_rad / kDegToRad) << "\n\n";
  file << "[limits]\nmax_duty = " << exact(spec.max_duty)
       << "\nduty_step = " << exact(spec.duty_step) << "\n";

  // What is written is what the loop's reader accepts: a rig whose limits the balance law refuses
  // (a duty limit below one duty step) gets no file.
  try {
    config::parse_controller_file(file.str(), options.output.string());
  } catch (const config::ConfigError& e) {
    return refuse(std::string("the controller would be refused: ") + e.what());
  }

  std::ofstream written(options.output, std::ios::binary | std::ios::trunc);
  written << file.str();
  written.close();
  if (!written) return refuse("cannot write " + options.output.string());
  out << "designed from the " << to_string(options.parameters) << " parameters of "
      << options.results.string() << ": " << gain.k.size() << " gains, largest closed-loop pole "
      << gain.spectral_radius << " (stable) at " << period_s * 1e3 << " ms with a " << lag_s * 1e3
      << " ms lag and a " << ramp_lag_s * 1e3 << " ms duty ramp; the filter's error pole "
      << observer.spectral_radius << " (at most " << observer.worst_spectral_radius
      << " at any reading age)\nwrote " << options.output.string() << "\n";
  return kExitDone;
}

}  // namespace furuta::app
