// The controller file's reader (controller_file.hpp). Every key is required: the file is written
// by `furuta controller design`, never by hand, so a key left out is a damaged or foreign file,
// not a wish for a default. What the balance law checks (ranges, one limit against another) is
// left to its constructor, whose error names the spec's member; that member is mapped back to the
// key it was read from.
#include "furuta/config/controller_file.hpp"

#include <glib.h>

#include <array>
#include <cctype>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "furuta/config/rig_config.hpp"
#include "furuta/config/toml_section.hpp"
#include "furuta/control/upright_lqr.hpp"
#include "sections.hpp"

namespace furuta::config {

namespace {

// GLib's SHA-256 (the project links GLib already, through LCM): no checksum of our own.
std::string controller_file_sha256(std::string_view bytes) {
  const std::unique_ptr<gchar, decltype(&g_free)> hex(
      g_compute_checksum_for_data(G_CHECKSUM_SHA256, reinterpret_cast<const guchar*>(bytes.data()),
                                  bytes.size()),
      &g_free);
  return hex.get();
}

// A table the file must have: absent, the error names it (there is no line to point at).
Section required_controller_table(Section& top, const std::string& key, const char* what) {
  if (!top.has(key))
    top.fail(key, nullptr, std::string("missing: the [") + key + "] table, " + what);
  return top.child(key);
}

std::int64_t required_controller_integer(Section& s, const std::string& key,
                                         const std::string& what, const Section::IntegerRule& valid,
                                         const char* rule) {
  if (!s.has(key)) s.fail(key, nullptr, "missing: " + what);
  return s.integer(key, 0, valid, rule);
}

// The tables of one file, kept to point at a key after they are read.
struct ControllerTables {
  Section controller, parameters, weights, gain, prediction, observer, drive, swing_up,
      catch_region, limits;
};

// The table and key a member of BalanceControllerSpec was read from (BalanceSpecError::field).
std::optional<std::pair<const Section*, std::string>> key_of_spec_member(const ControllerTables& t,
                                                                         const std::string& field) {
  const auto after = [&](std::string_view prefix) -> std::optional<std::string> {
    if (field.rfind(prefix, 0) != 0) return std::nullopt;
    return field.substr(prefix.size());
  };
  static const std::array<std::array<const char*, 3>, 16> kPlain = {{
      {"observer_gain", "observer", "m"},
      {"period_s", "controller", "period_ns"},
      {"delayed", "gain", "k"},
      {"gain", "gain", "k"},
      {"max_duty", "limits", "max_duty"},
      {"duty_step", "limits", "duty_step"},
      {"duty_torque_nm", "drive", "duty_torque_nm"},
      {"back_emf_nm_s", "drive", "back_emf_nm_s"},
      {"region.catch_rad", "catch", "catch_deg"},
      {"region.release_rad", "catch", "release_deg"},
      {"region.settle_s", "catch", "settle_s"},
      {"region.fall_rad", "catch", "fall_deg"},
      {"region.entry_duty_ratio", "catch", "entry_duty_ratio"},
      {"swing_up.pump_arm_rad", "swing_up", "pump_arm_deg"},
      {"duty_path.lag_s", "controller", "lag_s"},
      {"duty_path.ramp_duty_per_s", "controller", "ramp_duty_per_s"},
  }};
  for (const auto& [member, table, key] : kPlain) {
    if (field != member) continue;
    const std::string_view name = table;
    const Section* s = name == "controller" ? &t.controller
                       : name == "gain"     ? &t.gain
                       : name == "observer" ? &t.observer
                       : name == "limits"   ? &t.limits
                       : name == "drive"    ? &t.drive
                       : name == "swing_up" ? &t.swing_up
                                            : &t.catch_region;
    return std::pair{s, std::string(key)};
  }
  if (auto key = after("parameters.")) return std::pair{&t.parameters, *key};
  if (auto key = after("swing_up.")) return std::pair{&t.swing_up, *key};
  return std::nullopt;
}

void read_controller_table(Section& s, ControllerFile& f) {
  f.kind = s.required_text("kind", "the controller's kind (upright_lqr)");
  if (f.kind != kUprightLqrKind) {
    s.fail("kind", s.node("kind"),
           "'" + f.kind + "' is not a kind this reader knows: " + std::string(kUprightLqrKind));
  }
  f.rig = s.required_text("rig", "the [rig] name of the configuration it was designed for");
  f.period_ns = required_controller_integer(
      s, "period_ns", "the loop period", [](std::int64_t v) { return v > 0; }, "> 0");
  f.lag_s = s.required_number("lag_s", "the data path's lag", detail::non_negative, ">= 0");
  f.ramp_lag_s =
      s.required_number("ramp_lag_s", "the duty ramp's delay", detail::non_negative, ">= 0");
  // A gain carries at most kMaxDelayedDuties duties on their way: no gain fits a longer delay.
  const double period_s = static_cast<double>(f.period_ns) * 1e-9;
  if (!(f.lag_s + f.ramp_lag_s <= control::kMaxDelayedDuties * period_s)) {
    s.fail("ramp_lag_s", s.node("ramp_lag_s"),
           "with lag_s must be at most " + std::to_string(control::kMaxDelayedDuties) +
               " periods (the duties a gain can carry on their way)");
  }
  f.ramp_step_duty = s.required_number(
      "ramp_step_duty", "the duty step the ramp's delay is for",
      [](double v) { return v > 0 && v <= 1; }, "in (0, 1]");
  // The filter takes duties as the board does: lag_s after their sample, ramped to.
  f.spec.duty_path.lag_s = f.lag_s;
  f.spec.duty_path.ramp_duty_per_s = s.required_number(
      "ramp_duty_per_s", "the board's duty ramp (0: none)", detail::non_negative, ">= 0");
  f.supply_v =
      s.required_number("supply_v", "the supply the design assumed", detail::positive, "> 0");
  f.designed_by = s.required_text("designed_by", "the software that designed it");
  s.reject_unknown_keys();
}

void read_parameters_table(Section& s, ControllerFile& f) {
  f.parameters_source = s.required_choice<const char*>(
      "source", {{"output-error", "output-error"}, {"lsmi", "lsmi"}, {"cad", "cad"}});
  f.results = s.required_text("results", "the results.json the parameters came from");
  f.results_sha256 = s.required_text("results_sha256", "the SHA-256 of that results.json");
  if (!is_sha256_hex(f.results_sha256)) {
    s.fail("results_sha256", s.node("results_sha256"), "must be 64 lowercase hex digits");
  }
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const std::string name = model::kParameterNames[k];
    f.spec.parameters[k] = s.required_number(name, "the model parameter " + name);
  }
  s.reject_unknown_keys();
}

// Read to know the keys; the loop does not use the weights.
void read_weights_table(Section& s) {
  for (const char* key : {"q1", "q2", "dq1", "dq2"}) {
    s.required_number(key, std::string("the LQR weight on ") + key, detail::non_negative, ">= 0");
  }
  s.required_number("duty", "the LQR weight on the duty", detail::positive, "> 0");
  s.reject_unknown_keys();
}

void read_gain_table(Section& s, ControllerFile& f) {
  const std::vector<double> k =
      s.required_numbers("k", "the gain", 4, static_cast<std::size_t>(control::kMaxGains));
  for (std::size_t i = 0; i < k.size(); ++i) f.spec.gain[i] = k[i];
  f.spec.delayed = static_cast<int>(k.size()) - 4;
  // The gain carries one entry per duty on its way, which the lag it was designed with fixes.
  const int delayed = control::delayed_duties(f.spec.period_s, f.lag_s + f.ramp_lag_s);
  if (delayed != f.spec.delayed) {
    s.fail("k", s.node("k"),
           "has " + std::to_string(k.size()) + " entries, but controller.lag_s + ramp_lag_s at " +
               "its period_ns needs " + std::to_string(4 + delayed) +
               " (4 states and the duties on their way)");
  }
  s.reject_unknown_keys();
}

// Read to know the keys and to refuse a design predicted unstable.
void read_prediction_table(Section& s, const ControllerFile& f) {
  const std::size_t n = 4 + static_cast<std::size_t>(f.spec.delayed);
  s.required_numbers("closed_loop_poles_re", "the closed-loop poles' real parts", n, n);
  s.required_numbers("closed_loop_poles_im", "the closed-loop poles' imaginary parts", n, n);
  s.required_number(
      "spectral_radius", "the largest closed-loop pole's magnitude",
      [](double v) { return v >= 0 && v < 1; }, "in [0, 1) (a design predicted stable)");
  s.reject_unknown_keys();
}

void read_observer_table(Section& s, ControllerFile& f) {
  for (const char* key :
       {"arm_acceleration_sd", "pendulum_acceleration_sd", "arm_count_rad", "pendulum_count_rad"}) {
    s.required_number(key, std::string("the filter's ") + key, detail::positive, "> 0");
  }
  // The gain corrects the last sample's state with the angles read since: a gain designed for
  // another reading (older files corrected this sample's) is refused by this key's absence.
  if (!s.has("reading_age_s")) {
    s.fail("reading_age_s", nullptr,
           "missing: the filter's gain of a file without it corrects another state than the loop's "
           "filter does; design the controller again (furuta controller design)");
  }
  const double period_s = f.spec.period_s;
  f.reading_age_s = s.required_number(
      "reading_age_s", "the reading age the filter's gain is designed for",
      [period_s](double v) { return v >= 0 && v <= period_s; }, "in [0, the period]");
  const std::vector<double> m = s.required_numbers("m", "the filter's gain (4 x 2)", 8, 8);
  for (std::size_t i = 0; i < m.size(); ++i) f.spec.observer_gain[i] = m[i];
  for (const char* key : {"spectral_radius", "worst_spectral_radius"}) {
    s.required_number(
        key, "the estimation error's largest pole's magnitude",
        [](double v) { return v >= 0 && v < 1; }, "in [0, 1) (a filter that converges)");
  }
  s.reject_unknown_keys();
}

// The model the filter predicts with, from the file's parameters and drive: the numbers the
// design linearised, so they are not written twice.
void set_the_model(ControllerFile& f) {
  control::set_continuous_plant(
      control::linearize_upright(f.spec.parameters, {f.spec.duty_torque_nm, f.spec.back_emf_nm_s}),
      f.spec);
}

void read_drive_table(Section& s, ControllerFile& f) {
  f.spec.duty_torque_nm =
      s.required_number("duty_torque_nm", "eq. 4's torque per unit duty at the supply");
  f.spec.back_emf_nm_s = s.required_number("back_emf_nm_s", "eq. 4's torque per arm rad/s");
  s.reject_unknown_keys();
}

void read_swing_up_table(Section& s, ControllerFile& f) {
  control::SwingUp& u = f.spec.swing_up;
  u.energy_gain = s.required_number("energy_gain", "the swing-up's gain on the energy error");
  u.max_acceleration = s.required_number("max_acceleration", "the swing-up's acceleration limit");
  u.arm_gain = s.required_number("arm_gain", "the swing-up's gain on the arm's angle");
  u.arm_damping = s.required_number("arm_damping", "the swing-up's gain on the arm's speed");
  u.max_duty = s.required_number("max_duty", "the swing-up's duty limit");
  u.energy_margin = s.required_number("energy_margin", "how far above E0 the swing-up aims");
  u.start_below_energy_ratio =
      s.required_number("start_below_energy_ratio", "the energy ratio below which it starts");
  u.start_acceleration = s.required_number("start_acceleration", "the starting acceleration");
  u.pump_arm_rad = s.required_number("pump_arm_deg",
                                     "the arm angle beyond which the pump drives it no further") *
                   detail::kDegToRad;
  s.reject_unknown_keys();
}

void read_catch_table(Section& s, ControllerFile& f) {
  control::CatchRegion& r = f.spec.region;
  // Degrees in the file, for a person to read; radians in the spec.
  r.catch_rad = s.required_number("catch_deg", "the catch angle from upright") * detail::kDegToRad;
  r.release_rad =
      s.required_number("release_deg", "the release angle from upright") * detail::kDegToRad;
  r.entry_duty_ratio = s.required_number(
      "entry_duty_ratio", "the largest share of max_duty the gain may ask for at the catch");
  r.settle_s = s.required_number("settle_s", "the time inside the catch angle before balancing");
  r.fall_rad = s.required_number("fall_deg", "the fall angle from upright") * detail::kDegToRad;
  s.reject_unknown_keys();
}

void read_limits_table(Section& s, ControllerFile& f) {
  f.spec.max_duty = s.required_number("max_duty", "the duty limit");
  f.spec.duty_step = s.required_number("duty_step", "the board's duty resolution");
  s.reject_unknown_keys();
}

}  // namespace

bool is_sha256_hex(std::string_view text) {
  if (text.size() != 64) return false;
  for (const char c : text) {
    if (!std::isdigit(static_cast<unsigned char>(c)) && (c < 'a' || c > 'f')) return false;
  }
  return true;
}

ControllerFile parse_controller_file(std::string_view text, const std::string& file_name) {
  ControllerFile f;
  f.text = std::string(text);
  f.sha256 = controller_file_sha256(text);
  const toml::table root = parse_toml(f.text, file_name);
  Section top(root, file_name);
  // In the file's order, each table read whole before the next; [gain] after [controller], whose
  // period and lags fix its length.
  ControllerTables t{
      required_controller_table(top, "controller", "what the controller is and the rig it is for"),
      required_controller_table(top, "parameters", "the model the design used"),
      required_controller_table(top, "weights", "the LQR's weights"),
      required_controller_table(top, "gain", "the LQR's gain"),
      required_controller_table(top, "prediction", "the closed loop's poles"),
      required_controller_table(top, "observer", "the filter that estimates the velocities"),
      required_controller_table(top, "drive", "eq. 4 as the swing-up uses it"),
      required_controller_table(top, "swing_up", "the swing-up's settings"),
      required_controller_table(top, "catch", "the catch region"),
      required_controller_table(top, "limits", "the duty's limit and resolution")};
  top.reject_unknown_keys();
  read_controller_table(t.controller, f);
  f.spec.period_s = static_cast<double>(f.period_ns) * 1e-9;
  read_parameters_table(t.parameters, f);
  read_weights_table(t.weights);
  read_gain_table(t.gain, f);
  read_prediction_table(t.prediction, f);
  read_observer_table(t.observer, f);
  read_drive_table(t.drive, f);
  set_the_model(f);
  read_swing_up_table(t.swing_up, f);
  read_catch_table(t.catch_region, f);
  read_limits_table(t.limits, f);
  // The balance law's own checks, reported at the key each member came from.
  try {
    const control::BalanceLaw law(f.spec);
  } catch (const control::BalanceSpecError& e) {
    const auto where = key_of_spec_member(t, e.field());
    if (!where) throw ConfigError(file_name, 0, "", e.what());
    const auto& [section, key] = *where;
    section->fail(key, section->node(key), e.rule() + " (the balance law's " + e.field() + ")");
  }
  return f;
}

ControllerFile load_controller_file(const std::filesystem::path& path) {
  ControllerFile f = parse_controller_file(read_config_text(path), path.string());
  f.path = path;
  return f;
}

}  // namespace furuta::config
