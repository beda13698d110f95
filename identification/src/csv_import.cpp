#include "furuta/identification/csv_import.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <fstream>
#include <iomanip>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>
#include <string_view>
#include <utility>

#include "furuta/config/rig_config.hpp"
#include "furuta/config/toml_section.hpp"
#include "furuta/identification/preprocessing.hpp"

namespace furuta::identification {

namespace {

// Same shape as ConfigError's message, so a user sees one style for every located problem.
std::string located(const std::string& file, int line, const std::string& field,
                    const std::string& problem) {
  return file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " +
         (field.empty() ? std::string() : field + ": ") + problem;
}

// Shortest text that reads back as the same double: two close time stamps must not print alike.
std::string exact(double v) {
  std::array<char, 32> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), v);
  return std::string(buffer.data(), result.ptr);
}

std::string milliseconds(double seconds) {
  std::ostringstream out;
  out << std::setprecision(4) << seconds * 1e3 << " ms";
  return out.str();
}

// A 1-based column index written as text ("3"); nullopt when the text is anything else.
std::optional<std::size_t> column_index(const std::string& text) {
  std::size_t index = 0;
  const char* end = text.data() + text.size();
  const auto result = std::from_chars(text.data(), end, index);
  if (text.empty() || result.ec != std::errc() || result.ptr != end || index < 1 ||
      index > 100'000) {
    return std::nullopt;
  }
  return index;
}

// ---------------------------------------------------------------------------------------------
// The import spec (TOML)

// The spec's tables ([csv], [motor]) are read with config::Section, the rig configuration's
// checked reader: a mistyped key must never become a silent default.
using config::Choice;
using config::Section;

bool positive(double v) {
  return v > 0;
}

// Radians per unit of an angle column (one count with angle_unit = "counts"), before its scale.
double angle_factor(AngleUnit unit, double counts_per_rev) {
  switch (unit) {
    case AngleUnit::deg:
      return std::numbers::pi / 180.0;
    case AngleUnit::counts:
      return 2.0 * std::numbers::pi / counts_per_rev;
    case AngleUnit::rad:
      break;
  }
  return 1.0;
}

double joint_angle_factor(const CsvImportSpec& spec, std::size_t joint) {
  return angle_factor(spec.angle_unit,
                      joint == 0 ? spec.arm_counts_per_rev : spec.pendulum_counts_per_rev);
}

// Past these no recording is of a rig: an angle of a million radians is 160,000 turns, an input
// of a million volts or newton-metres none; values beyond them are a wrong column or scale.
constexpr double kMaxAngleRad = 1e6;
constexpr const char* kAngleRange = "no rig's angle is beyond 1e6 rad";
constexpr double kMaxInputMagnitude = 1e6;
constexpr const char* kInputRange = "no rig's input is beyond 1e6 (V or N m)";
// A column's scale is a unit change or a sign: within these it is one.
constexpr double kMinScale = 1e-6, kMaxScale = 1e6;

CsvColumn read_column(Section& s, const std::string& key, bool has_header, bool has_scale,
                      const char* what) {
  CsvColumn c;
  c.name = s.required_text(key, what);
  if (!has_header) {
    const auto index = column_index(c.name);
    if (!index) {
      s.fail(
          key, s.node(key),
          "'" + c.name + "' is not a 1-based column index (has_header = false): write e.g. \"2\"");
    }
    c.name = std::to_string(*index);  // "02" and "2" are the same column
  }
  if (has_scale) {
    const std::string scale_key = key + "_scale";
    c.scale = s.number(
        scale_key, 1.0,
        [](double v) { return std::abs(v) >= kMinScale && std::abs(v) <= kMaxScale; },
        "a unit change or a sign: 1e-6 <= |scale| <= 1e6");
  }
  return c;
}

// Each column is named once: two quantities read from one column is a typo.
void read_columns(Section& s, CsvImportSpec& spec) {
  const bool h = spec.has_header;
  spec.time = read_column(s, "time", h, false, "the time column");
  spec.arm_angle = read_column(s, "arm_angle", h, true, "the arm angle column");
  spec.pendulum_angle = read_column(s, "pendulum_angle", h, true, "the pendulum angle column");
  spec.input = read_column(s, "input", h, true, "the input column (duty, voltage or torque)");
  const auto optional = [&](const char* key, CsvColumn& column) {
    if (s.has(key)) column = read_column(s, key, h, false, "");
  };
  optional("arm_time", spec.arm_time);
  optional("pendulum_time", spec.pendulum_time);
  optional("input_time", spec.input_time);
  optional("supply", spec.supply);
  optional("arm_board_time", spec.arm_board_time);
  optional("pendulum_board_time", spec.pendulum_board_time);
  const std::array<std::pair<const char*, const CsvColumn*>, 10> columns = {{
      {"time", &spec.time},
      {"arm_angle", &spec.arm_angle},
      {"pendulum_angle", &spec.pendulum_angle},
      {"input", &spec.input},
      {"arm_time", &spec.arm_time},
      {"pendulum_time", &spec.pendulum_time},
      {"input_time", &spec.input_time},
      {"supply", &spec.supply},
      {"arm_board_time", &spec.arm_board_time},
      {"pendulum_board_time", &spec.pendulum_board_time},
  }};
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (columns[i].second->name.empty()) continue;
    for (std::size_t j = 0; j < i; ++j) {
      if (columns[i].second->name == columns[j].second->name) {
        s.fail(columns[i].first, s.node(columns[i].first),
               "same column as " + std::string(columns[j].first) + " ('" + columns[i].second->name +
                   "')");
      }
    }
  }
}

char read_delimiter(Section& s) {
  const std::string delimiter = s.text("delimiter", ",");
  if (delimiter.size() != 1) {
    s.fail("delimiter", s.node("delimiter"),
           "must be a single ASCII character, e.g. \",\", \";\" or \"\\t\"");
  }
  const auto d = static_cast<unsigned char>(delimiter[0]);
  // Characters that occur inside numbers or quoted fields would split them.
  if (d >= 0x80 || std::isalnum(d) ||
      std::string_view("\".+-\r\n").find(delimiter[0]) != std::string_view::npos) {
    s.fail("delimiter", s.node("delimiter"),
           "'" + delimiter + "' cannot separate fields (it occurs in numbers or quoting)");
  }
  return delimiter[0];
}

// Every unit and convention is required: they change every number, so none of them is guessed.
void read_units(Section& s, CsvImportSpec& spec) {
  spec.time_scale_s =
      s.required_choice<double>("time_unit", {{"s", 1.0}, {"ms", 1e-3}, {"us", 1e-6}});
  spec.angle_unit = s.required_choice<AngleUnit>(
      "angle_unit",
      {{"rad", AngleUnit::rad}, {"deg", AngleUnit::deg}, {"counts", AngleUnit::counts}});
  for (const char* key : {"arm_counts_per_rev", "pendulum_counts_per_rev"}) {
    const std::optional<double> cpr = s.optional_number(key);
    if (spec.angle_unit != AngleUnit::counts) {
      // A resolution that does nothing hints the unit is not what the writer meant.
      if (cpr) s.fail(key, s.node(key), "only applies when angle_unit = \"counts\"");
      continue;
    }
    if (!cpr) s.fail(key, nullptr, "missing: required when angle_unit = \"counts\"");
    if (*cpr <= 0) s.fail(key, s.node(key), "must be > 0");
    // A fraction of a count is no resolution an encoder has: most likely a typo or a ratio
    // folded in, which would scale every angle.
    if (*cpr != std::floor(*cpr)) {
      s.fail(key, s.node(key), "must be a whole number of counts (e.g. 4096), not " + exact(*cpr));
    }
    (std::string_view(key) == "arm_counts_per_rev" ? spec.arm_counts_per_rev
                                                   : spec.pendulum_counts_per_rev) = *cpr;
  }
  // The smallest change each angle can show, in the angle unit: the output-error refinement's
  // angle noise (one resolution / sqrt(12)). With counts it is one count, so stating it is refused.
  for (std::size_t j = 0; j < 2; ++j) {
    const char* key = j == 0 ? "arm_resolution" : "pendulum_resolution";
    const std::optional<double> r = s.optional_number(key);
    if (spec.angle_unit == AngleUnit::counts) {
      if (r)
        s.fail(key, s.node(key), "not with angle_unit = \"counts\": one count is the resolution");
      spec.resolution_rad[j] = joint_angle_factor(spec, j);
      continue;
    }
    if (!r) continue;
    if (!(*r > 0) || !std::isfinite(*r)) s.fail(key, s.node(key), "must be a number > 0");
    spec.resolution_rad[j] = *r * joint_angle_factor(spec, j);
  }
  spec.pendulum_zero = s.required_choice<PendulumZero>(
      "pendulum_zero", {{"down", PendulumZero::down}, {"up", PendulumZero::up}});
  spec.input_kind = s.required_choice<InputKind>(
      "input_kind",
      {{"duty", InputKind::duty}, {"voltage", InputKind::voltage}, {"torque", InputKind::torque}});
  spec.input_between_samples =
      s.choice<InputBetweenSamples>("input_between_samples", InputBetweenSamples::linear,
                                    {{"held", InputBetweenSamples::held},
                                     {"linear", InputBetweenSamples::linear},
                                     {"cubic", InputBetweenSamples::cubic}});
  spec.input_rate_limit_per_s = s.number(
      "input_rate_limit", 0.0, [](double v) { return v > 0 && std::isfinite(v); },
      "> 0 (the input's units per second, after input_scale)");
  spec.input_scale_sd = s.number(
      "input_scale_sd", 0.0, [](double v) { return v >= 0 && v < 1; },
      "in [0, 1): the input scale's relative standard deviation (0.05: known to 5 %)");
  if (const std::optional<double> v = s.optional_number("input_at_start")) {
    spec.input_at_start = *v * spec.input.scale;
  }
  if (!spec.supply.name.empty() && spec.input_kind != InputKind::duty) {
    s.fail("supply", s.node("supply"),
           "only applies when input_kind = \"duty\" (the duty's torque scales with the supply)");
  }
}

// The [motor] table: the DC motor of a voltage-driven rig. Required with input_kind = "voltage"
// (k_t, k_e and R have no sensible default) and refused with the other kinds, where it would be
// silently ignored: duty input takes eq. 4's motor from the rig configuration, torque needs none.
std::optional<VoltageMotor> read_motor_table(Section& top, Section& csv, InputKind input_kind) {
  if (input_kind != InputKind::voltage) {
    if (!top.has("motor")) return std::nullopt;
    const bool duty = input_kind == InputKind::duty;
    top.fail("motor", top.node("motor"),
             std::string("only applies when csv.input_kind = \"voltage\" (it is \"") +
                 (duty ? "duty" : "torque") + "\"; " +
                 (duty ? "duty input uses the rig configuration's motor, eq. 4)"
                       : "torque input needs no motor)"));
  }
  if (!top.has("motor")) {
    csv.fail("input_kind", csv.node("input_kind"),
             "\"voltage\" needs a [motor] table: torque_constant_nm_per_a, back_emf_v_s_per_rad, "
             "resistance_ohm (gear_ratio and efficiency default to 1)");
  }
  Section m = top.child("motor");
  VoltageMotor motor;
  motor.torque_constant_nm_per_a = m.required_number(
      "torque_constant_nm_per_a", "the motor's torque constant k_t [N m/A]", positive, "> 0");
  motor.back_emf_v_s_per_rad = m.required_number(
      "back_emf_v_s_per_rad", "the motor's back-EMF constant k_e [V s/rad]", positive, "> 0");
  motor.resistance_ohm = m.required_number(
      "resistance_ohm", "the motor's winding resistance R [ohm]", positive, "> 0");
  motor.gear_ratio =
      m.number("gear_ratio", 1.0, positive,
               "> 0 (motor turns per arm turn; a reversed arm is arm_angle_scale = -1)");
  motor.efficiency = m.number(
      "efficiency", 1.0, [](double v) { return v > 0 && v <= 1; }, "in (0, 1]");
  m.reject_unknown_keys();
  return motor;
}

// The [guaranteed] table: the recording's bounds for the windowed set inversion, each stated (a
// bound is a claim about the logger, so none is defaulted). Angles in the spec's angle unit and
// column scale, like the angles themselves.
std::optional<RecordingBounds> read_bounds_table(Section& top, const CsvImportSpec& spec,
                                                 const std::string& source_name) {
  if (!top.has("guaranteed")) return std::nullopt;
  Section g = top.child("guaranteed");
  if (spec.input_kind != InputKind::duty) {
    top.fail("guaranteed", top.node("guaranteed"),
             "only applies when csv.input_kind = \"duty\": the guaranteed set is found in the "
             "parameters scaled by the drive's gain (eq. 4), which a duty has");
  }
  const auto at = [&](const std::string& key) {
    return source_name + ":" + std::to_string(g.node(key)->source().begin.line) + " guaranteed." +
           key;
  };
  const auto angle_per_unit = [&](std::size_t joint) {
    return joint_angle_factor(spec, joint) *
           std::abs(joint == 0 ? spec.arm_angle.scale : spec.pendulum_angle.scale);
  };
  // A [lo, hi] pair, required, each entry `valid`.
  const auto pair = [&](const char* key, const char* missing, const Section::NumberRule& valid,
                        const char* rule) {
    if (!g.has(key)) g.fail(key, nullptr, missing);
    const std::array<double, 2> v = g.numbers<2>(key, {0, 0}, valid, rule);
    if (!(v[0] <= v[1])) g.fail(key, g.node(key), "must be [lo, hi] with lo <= hi");
    return Interval(v[0], v[1]);
  };
  const auto positive_finite = [](double v) { return v > 0 && std::isfinite(v); };
  const auto angle = [&](const char* key, const char* quantity, std::size_t joint,
                         const char* what) {
    const double v = g.required_number(key, what, positive_finite, "> 0 (in csv.angle_unit)") *
                     angle_per_unit(joint);
    return PhysicalInput{quantity, Interval(-v, v), "rad", InputSource::import_spec, at(key)};
  };
  RecordingBounds b;
  b.arm_angle_error =
      angle("arm_angle_error", "arm_angle_error", 0,
            "the most an arm reading is off the true angle, in angle_unit (half a count)");
  b.pendulum_angle_error =
      angle("pendulum_angle_error", "pendulum_angle_error", 1,
            "the most a pendulum reading is off the true angle, in angle_unit (half a count)");
  b.pendulum_zero = angle(
      "pendulum_zero_error", "pendulum_zero", 1,
      "the most the hanging pendulum's true angle is off its zero at the start, in angle_unit");
  const Interval lag_ms = pair(
      "lag_ms",
      "missing: [lo, hi] in ms, each reading's time minus its state's, "
      "against the input's times",
      [](double v) { return std::abs(v) <= 1000; }, "within +-1000 ms");
  b.lag = {"lag", lag_ms / Interval(1000.0), "s", InputSource::import_spec, at("lag_ms")};
  b.arm_rest_speed_rad_s = g.required_number(
      "arm_rest_speed_rad_s", "the most the arm's speed is at the first command [rad/s]",
      [](double v) { return v >= 0 && v <= 10; }, "in [0, 10]");
  if (!spec.supply.name.empty()) {
    if (g.has("supply_v")) {
      g.fail("supply_v", g.node("supply_v"),
             "not with csv.supply: the supply comes from its readings (give supply_error_v)");
    }
    const double e = g.required_number(
        "supply_error_v", "the most a supply reading is off the supply [V] (half its step)",
        [](double v) { return v >= 0 && v < 100; }, "in [0, 100)");
    b.supply_error = {"supply_error", Interval(-e, e), "V", InputSource::import_spec,
                      at("supply_error_v")};
  } else {
    if (g.has("supply_error_v")) {
      g.fail("supply_error_v", g.node("supply_error_v"),
             "only applies with a csv.supply column; without one give supply_v = [lo, hi]");
    }
    const Interval supply = pair(
        "supply_v",
        "missing: [lo, hi] in V, the supply during the recordings (no csv.supply column)",
        [](double x) { return x > 0 && x < 1000; }, "volts in (0, 1000)");
    b.supply = PhysicalInput{"supply", supply, "V", InputSource::import_spec, at("supply_v")};
  }
  g.reject_unknown_keys();
  return b;
}

// The document's top level: [csv] is required; other tables may hold other readers' settings, but
// a bare key at the top belongs to nobody and is most likely a [csv] key written above the table.
Section read_csv_table(const toml::table& root, Section& top) {
  Section csv = top.child("csv");
  for (auto&& [key, node] : root) {
    if (!node.is_table()) {
      const std::string name(key.str());
      top.fail(name, &node,
               name == "motor" ? "must be a table ([motor])"
                               : "unknown key (the import keys belong in [csv])");
    }
  }
  if (!csv.present()) top.fail("csv", nullptr, "missing table [csv]");
  return csv;
}

}  // namespace

CsvImportError::CsvImportError(const std::string& file, int line, const std::string& field,
                               const std::string& problem)
    : std::runtime_error(located(file, line, field, problem)),
      file_(file),
      line_(line),
      field_(field) {}

CsvImportSpec parse_csv_import_spec(const std::string& text, const std::string& source_name) {
  const toml::table root = config::parse_toml(text, source_name);
  Section top(root, source_name);
  Section s = read_csv_table(root, top);
  CsvImportSpec spec;
  spec.delimiter = read_delimiter(s);
  spec.has_header = s.boolean("has_header", true);
  read_columns(s, spec);
  read_units(s, spec);
  // A column scale (a flipped or geared encoder) scales its resolution too.
  spec.resolution_rad[0] *= std::abs(spec.arm_angle.scale);
  spec.resolution_rad[1] *= std::abs(spec.pendulum_angle.scale);
  spec.time_unit_at = source_name + ":" + std::to_string(s.node("time_unit")->source().begin.line);
  s.reject_unknown_keys();
  spec.voltage_motor = read_motor_table(top, s, spec.input_kind);
  spec.bounds = read_bounds_table(top, spec, source_name);
  return spec;
}

CsvImportSpec load_csv_import_spec(const std::filesystem::path& path) {
  return parse_csv_import_spec(config::read_config_text(path), path.string());
}

// ---------------------------------------------------------------------------------------------
// The CSV file

namespace {

constexpr std::size_t kMinRows = 16;
constexpr double kIrregularTolerance = 0.01;  // of the median step
// A grid much denser than the recording means a gap of many periods (files joined, logger paused):
// interpolating across it would invent data.
constexpr std::size_t kMaxResampleGrowth = 4;

bool blank(std::string_view line) {
  return line.find_first_not_of(" \t") == std::string_view::npos;
}

// Splits one line into fields. Quoted fields ("a,b", "" for a quote) lose their quotes; blanks
// around a field are dropped unless the delimiter is itself a blank. False on an open quote.
bool split_fields(std::string_view line, char delimiter, std::vector<std::string>& fields) {
  fields.clear();
  std::string field;
  bool in_quotes = false, quoted = false;
  auto is_blank = [delimiter](char c) { return (c == ' ' || c == '\t') && c != delimiter; };
  auto finish = [&] {
    if (!quoted) {
      const auto first = std::find_if_not(field.begin(), field.end(), is_blank);
      const auto last = std::find_if_not(field.rbegin(), field.rend(), is_blank).base();
      field = first < last ? std::string(first, last) : std::string();
    }
    fields.push_back(std::move(field));
    field.clear();
    quoted = false;
  };
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (in_quotes) {
      if (c != '"') {
        field += c;
      } else if (i + 1 < line.size() && line[i + 1] == '"') {
        field += '"';
        ++i;
      } else {
        in_quotes = false;
      }
    } else if (c == delimiter) {
      finish();
    } else if (c == '"' && !quoted && std::all_of(field.begin(), field.end(), is_blank)) {
      field.clear();
      in_quotes = quoted = true;
    } else if (!(quoted && is_blank(c))) {
      field += c;
    }
  }
  if (in_quotes) return false;
  finish();
  return true;
}

// Strict: the whole cell is one finite number ("1e-3", "-2", "+0.5"); nothing else is guessed.
std::optional<double> parse_number(std::string_view cell) {
  if (cell.starts_with('+')) {
    cell.remove_prefix(1);  // from_chars takes no '+', but loggers write one
    if (cell.starts_with('+') || cell.starts_with('-')) return std::nullopt;
  }
  double value = 0;
  const char* end = cell.data() + cell.size();
  const auto result = std::from_chars(cell.data(), end, value);
  if (result.ec != std::errc() || result.ptr != end || !std::isfinite(value)) return std::nullopt;
  return value;
}

// A spec built in code skips the TOML checks; the import still refuses one it cannot honour.
void check_spec(const CsvImportSpec& spec) {
  auto bad = [](const std::string& what) {
    throw std::invalid_argument("CSV import spec: " + what);
  };
  for (const CsvColumn* c : {&spec.time, &spec.arm_angle, &spec.pendulum_angle, &spec.input}) {
    if (c->name.empty()) bad("a column has no name");
    if (!spec.has_header && !column_index(c->name)) {
      bad("column '" + c->name + "' is not a 1-based index (has_header = false)");
    }
    if (!std::isfinite(c->scale) || c->scale == 0) bad("column '" + c->name + "' has scale 0");
  }
  if (!(spec.time_scale_s > 0) || !std::isfinite(spec.time_scale_s))
    bad("time_scale_s must be > 0");
  if (spec.angle_unit == AngleUnit::counts) {
    for (const double cpr : {spec.arm_counts_per_rev, spec.pendulum_counts_per_rev}) {
      if (!(cpr > 0) || cpr != std::floor(cpr)) {
        bad("counts per revolution must be whole numbers > 0 when angle_unit = counts");
      }
    }
  }
}

struct Channel {
  const char* role;
  const CsvColumn* column;
  std::size_t index = 0;  // 0-based field
  std::string label;      // what an error calls the column
};

double median(std::vector<double> v) {
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
  const double upper = v[mid];
  if (v.size() % 2 == 1) return upper;
  const double lower = *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid));
  return 0.5 * (lower + upper);
}

// Linear interpolation of (t, x) at the increasing times `grid`, all within [t.front(), t.back()].
std::vector<double> interpolate(const std::vector<double>& t, const std::vector<double>& x,
                                const std::vector<double>& grid) {
  std::vector<double> out;
  out.reserve(grid.size());
  std::size_t j = 0;
  for (const double tk : grid) {
    while (j + 2 < t.size() && t[j + 1] <= tk) ++j;
    const double w = (tk - t[j]) / (t[j + 1] - t[j]);
    out.push_back(x[j] + w * (x[j + 1] - x[j]));
  }
  return out;
}

std::string duration_text(double seconds) {
  std::ostringstream out;
  out << std::setprecision(3);
  if (seconds >= 7200) {
    out << seconds / 3600 << " h";
  } else if (seconds >= 120) {
    out << seconds / 60 << " min";
  } else if (seconds >= 1) {
    out << seconds << " s";
  } else if (seconds >= 1e-3) {
    out << seconds * 1e3 << " ms";
  } else {
    out << seconds * 1e6 << " us";
  }
  return out.str();
}

// A period outside what a pendulum recording can have is, in practice, a time column read in the
// wrong unit: refused here, before a filter design fails on it with a message about cut-offs.
void check_sample_period(const std::string& file, const std::string& column,
                         const CsvImportSpec& spec, double period, double span) {
  if (period >= kMinSamplePeriodS && period <= kMaxSamplePeriodS) return;
  struct Unit {
    const char* name;
    double seconds;
  };
  constexpr std::array<Unit, 3> units = {{{"s", 1.0}, {"ms", 1e-3}, {"us", 1e-6}}};
  // A spec built in code may hold any scale; one read from TOML holds one of the units.
  std::string problem = "time_scale_s = " + exact(spec.time_scale_s);
  for (const Unit& u : units) {
    if (u.seconds == spec.time_scale_s) problem = "time_unit = \"" + std::string(u.name) + "\"";
  }
  // The unit that would put the period in range, nearest the daemon's 16 ms when two would.
  const double step = period / spec.time_scale_s;  // in the column's own numbers
  const Unit* likely = nullptr;
  for (const Unit& u : units) {
    const double p = step * u.seconds;
    if (u.seconds == spec.time_scale_s || p < kMinSamplePeriodS || p > kMaxSamplePeriodS) continue;
    if (!likely ||
        std::abs(std::log(p / 16e-3)) < std::abs(std::log(step * likely->seconds / 16e-3))) {
      likely = &u;
    }
  }
  if (!spec.time_unit_at.empty()) problem += " (" + spec.time_unit_at + ")";
  problem += " gives a sample period of " + duration_text(period) + " (the median step; " +
             duration_text(span) + " in all), outside the " + duration_text(kMinSamplePeriodS) +
             " to " + duration_text(kMaxSamplePeriodS) + " a pendulum recording has: ";
  if (likely) {
    problem += "is the column in " + std::string(likely->name) + "? Then write time_unit = \"" +
               likely->name + "\" (a period of " + duration_text(step * likely->seconds) + ")";
  } else {
    problem += "check the time column and time_unit";
  }
  throw CsvImportError(file, 0, column, problem);
}

// A reading at time t from readings at their own increasing times: linear between them (or the one
// in force, `held`), the first or last outside.
double reading_at(const std::vector<double>& t, const std::vector<double>& x, double at,
                  bool held) {
  const auto after = std::upper_bound(t.begin(), t.end(), at);
  if (after == t.begin()) return x.front();
  const auto i = static_cast<std::size_t>(after - t.begin()) - 1;
  if (held || i + 1 == t.size()) return x[i];
  const double w = (at - t[i]) / (t[i + 1] - t[i]);
  return x[i] + w * (x[i + 1] - x[i]);
}

// One quantity's readings at their own times: in the project's units, a reading whose time repeats
// the previous one's dropped as the same reading; a time that goes back, or a repeat with another
// value, is refused with both lines.
std::vector<std::size_t> own_times(const std::string& file, const Channel& time,
                                   const Channel& value, const std::vector<double>& t_raw,
                                   const std::vector<double>& x, const std::vector<int>& row_line,
                                   double time_scale, std::vector<double>& t_out,
                                   std::vector<double>& x_out) {
  std::vector<std::size_t> kept;
  std::size_t last = 0;
  for (std::size_t i = 0; i < t_raw.size(); ++i) {
    const double t = t_raw[i] * time_scale;
    if (!t_out.empty()) {
      const std::string before = "line " + std::to_string(row_line[last]);
      if (t < t_out.back()) {
        throw CsvImportError(file, row_line[i], time.label,
                             exact(t_raw[i]) + " goes back from " + exact(t_raw[last]) + " on " +
                                 before + " (the time of " + value.label + ")");
      }
      if (t == t_out.back()) {
        if (x[i] != x_out.back()) {
          throw CsvImportError(file, row_line[i], value.label,
                               "a second value at the same time " + exact(t_raw[i]) + " as " +
                                   before + " (" + time.label + "); one time, one reading");
        }
        continue;
      }
    }
    t_out.push_back(t);
    x_out.push_back(x[i]);
    kept.push_back(i);
    last = i;
  }
  return kept;
}

// An angle's readings also stamped by the board's clock: their times mapped from it onto the host
// clock (fit_board_clock), the board's unit whatever it is (its rate is fitted). The board's stamps
// must increase with the readings; a board clock that does not keep time is a warning, and the
// host's stamps stay.
void map_board_times(const std::string& file, const Channel& board_column,
                     const std::vector<double>& board_raw, const std::vector<std::size_t>& kept,
                     const std::vector<int>& row_line, std::vector<double>& t,
                     std::optional<BoardClock>& clock, std::vector<std::string>& warnings) {
  std::vector<double> board;
  for (std::size_t k = 0; k < kept.size(); ++k) {
    const std::size_t i = kept[k];
    if (k > 0 && !(board_raw[i] > board.back())) {
      throw CsvImportError(file, row_line[i], board_column.label,
                           exact(board_raw[i]) + " does not increase from " + exact(board.back()) +
                               " on line " + std::to_string(row_line[kept[k - 1]]) +
                               " though the reading is a new one");
    }
    board.push_back(board_raw[i]);
  }
  clock = fit_board_clock(t, board, kBoardClockMaxDelay_s);
  if (!clock) {
    warnings.push_back(board_column.label +
                       ": the board's clock does not keep time against the host's stamps (more "
                       "than a tenth of them lie over " +
                       milliseconds(kBoardClockMaxDelay_s) + " off its line); the host's are used");
    return;
  }
  for (std::size_t k = 0; k < t.size(); ++k) t[k] = clock->host_time(board[k]);
}

template <typename Slot>
RecordedSeries recorded_series(const std::string& file, const CsvImportSpec& spec,
                               const std::vector<Channel>& channels,
                               const std::vector<std::vector<double>>& raw,
                               const std::vector<int>& row_line, const Slot& slot) {
  const double arm_factor = joint_angle_factor(spec, 0) * spec.arm_angle.scale;
  const double pendulum_factor = joint_angle_factor(spec, 1) * spec.pendulum_angle.scale;
  // Upright-zero rigs report the angle from the top; the project's q2 is from hanging down. Not
  // wrapped: a pendulum that swings over keeps a continuous angle, which differentiation needs.
  const double pendulum_offset = spec.pendulum_zero == PendulumZero::up ? std::numbers::pi : 0.0;
  std::vector<double> q1, q2, u;
  // Each value in range where it enters, the first one that is not named by its row and column:
  // an angle no rig records (a value far past this would overflow the filters and derivatives
  // into NaN), a duty outside [-1, 1] (a percentage, or a column that is not the input).
  const auto check = [&](double value, std::size_t i, const Channel& channel, double limit,
                         const char* what) {
    if (!(std::abs(value) <= limit)) {
      throw CsvImportError(file, row_line[i], channel.label,
                           exact(value) + " after the spec's unit and scale: " + what);
    }
  };
  for (std::size_t i = 0; i < row_line.size(); ++i) {
    q1.push_back(raw[1][i] * arm_factor);
    q2.push_back(raw[2][i] * pendulum_factor + pendulum_offset);
    u.push_back(raw[3][i] * spec.input.scale);
    check(q1.back(), i, channels[1], kMaxAngleRad, kAngleRange);
    check(q2.back(), i, channels[2], kMaxAngleRad, kAngleRange);
    if (spec.input_kind == InputKind::duty) {
      check(u.back(), i, channels[3], 1.0,
            "a duty is in [-1, 1] (a percentage needs input_scale = 0.01)");
    } else {
      check(u.back(), i, channels[3], kMaxInputMagnitude, kInputRange);
    }
  }
  const auto time_of = [&](const CsvColumn& own) -> std::size_t {
    return slot(own).value_or(0);  // the row's time when the spec names none
  };
  RecordedSeries r;
  const std::size_t a = time_of(spec.arm_time), p = time_of(spec.pendulum_time),
                    c = time_of(spec.input_time);
  const std::vector<std::size_t> q1_rows = own_times(
      file, channels[a], channels[1], raw[a], q1, row_line, spec.time_scale_s, r.q1_t_s, r.q1_rad);
  const std::vector<std::size_t> q2_rows = own_times(
      file, channels[p], channels[2], raw[p], q2, row_line, spec.time_scale_s, r.q2_t_s, r.q2_rad);
  if (const auto b = slot(spec.arm_board_time)) {
    map_board_times(file, channels[*b], raw[*b], q1_rows, row_line, r.q1_t_s, r.board_clock[0],
                    r.warnings);
  }
  if (const auto b = slot(spec.pendulum_board_time)) {
    map_board_times(file, channels[*b], raw[*b], q2_rows, row_line, r.q2_t_s, r.board_clock[1],
                    r.warnings);
  }
  own_times(file, channels[c], channels[3], raw[c], u, row_line, spec.time_scale_s, r.input_t_s,
            r.input);
  if (const auto v = slot(spec.supply)) {
    r.supply_v = raw[*v];
    for (std::size_t i = 0; i < r.supply_v.size(); ++i) {
      if (!(r.supply_v[i] > 0)) {
        throw CsvImportError(file, row_line[i], channels[*v].label,
                             "a supply of " + exact(r.supply_v[i]) + " V (it must be > 0)");
      }
    }
  }
  return r;
}

}  // namespace

ImportedSeries import_csv(const std::filesystem::path& csv, const CsvImportSpec& spec) {
  check_spec(spec);
  const std::string file = csv.string();
  std::string text;
  {
    std::ifstream in(csv, std::ios::binary);
    if (!in) throw CsvImportError(file, 0, "", "cannot open the file");
    std::ostringstream buffer;
    buffer << in.rdbuf();
    if (in.bad()) throw CsvImportError(file, 0, "", "cannot read the file");
    text = buffer.str();
  }
  std::string_view rest(text);
  if (rest.starts_with("\xEF\xBB\xBF")) rest.remove_prefix(3);  // UTF-8 BOM (Excel, MATLAB)

  std::vector<std::string_view> lines;  // lines[i] is line i + 1
  while (!rest.empty()) {
    const std::size_t end = rest.find('\n');
    std::string_view line = rest.substr(0, end);
    if (line.ends_with('\r')) line.remove_suffix(1);
    lines.push_back(line);
    rest = end == std::string_view::npos ? std::string_view() : rest.substr(end + 1);
  }
  while (!lines.empty() && blank(lines.back())) lines.pop_back();
  std::size_t next = 0;
  while (next < lines.size() && blank(lines[next])) ++next;

  // The four required columns first, then the optional ones the spec names.
  std::vector<Channel> channels = {
      {"time", &spec.time, 0, {}},
      {"arm_angle", &spec.arm_angle, 0, {}},
      {"pendulum_angle", &spec.pendulum_angle, 0, {}},
      {"input", &spec.input, 0, {}},
  };
  for (const Channel& optional :
       {Channel{"arm_time", &spec.arm_time, 0, {}},
        Channel{"pendulum_time", &spec.pendulum_time, 0, {}},
        Channel{"input_time", &spec.input_time, 0, {}}, Channel{"supply", &spec.supply, 0, {}},
        Channel{"arm_board_time", &spec.arm_board_time, 0, {}},
        Channel{"pendulum_board_time", &spec.pendulum_board_time, 0, {}}}) {
    if (!optional.column->name.empty()) channels.push_back(optional);
  }
  const auto slot = [&](const CsvColumn& column) -> std::optional<std::size_t> {
    for (std::size_t c = 0; c < channels.size(); ++c) {
      if (channels[c].column == &column) return c;
    }
    return std::nullopt;
  };
  std::vector<std::string> fields;
  if (spec.has_header) {
    if (next == lines.size()) throw CsvImportError(file, 0, "", "the file is empty (no header)");
    const int line_no = static_cast<int>(next + 1);
    if (!split_fields(lines[next], spec.delimiter, fields)) {
      throw CsvImportError(file, line_no, "", "unterminated quote in the header");
    }
    ++next;
    for (Channel& ch : channels) {
      const std::string& name = ch.column->name;
      std::vector<std::size_t> found;
      for (std::size_t i = 0; i < fields.size(); ++i) {
        if (fields[i] == name) found.push_back(i);
      }
      if (found.empty()) {
        std::string available;
        for (const std::string& f : fields)
          available += (available.empty() ? "\"" : ", \"") + f + "\"";
        throw CsvImportError(
            file, line_no, name,
            std::string("no such column for ") + ch.role + "; the header has: " + available);
      }
      if (found.size() > 1) {
        throw CsvImportError(file, line_no, name,
                             "ambiguous: columns " + std::to_string(found[0] + 1) + " and " +
                                 std::to_string(found[1] + 1) + " both have this name");
      }
      ch.index = found.front();
      ch.label = name;
    }
  } else {
    for (Channel& ch : channels) {
      ch.index = *column_index(ch.column->name) - 1;
      ch.label = "column " + ch.column->name;
    }
  }

  std::vector<std::vector<double>> raw(channels.size());
  std::vector<int> row_line;
  for (; next < lines.size(); ++next) {
    const int line_no = static_cast<int>(next + 1);
    if (blank(lines[next])) {
      throw CsvImportError(file, line_no, "", "blank line inside the data");
    }
    if (!split_fields(lines[next], spec.delimiter, fields)) {
      throw CsvImportError(file, line_no, "", "unterminated quote");
    }
    for (std::size_t c = 0; c < channels.size(); ++c) {
      const Channel& ch = channels[c];
      if (ch.index >= fields.size()) {
        throw CsvImportError(
            file, line_no, ch.label,
            "missing: the row has only " + std::to_string(fields.size()) + " fields");
      }
      const std::optional<double> v = parse_number(fields[ch.index]);
      if (!v) {
        throw CsvImportError(file, line_no, ch.label,
                             fields[ch.index].empty()
                                 ? std::string("empty cell")
                                 : "'" + fields[ch.index] + "' is not a finite number");
      }
      raw[c].push_back(*v);
    }
    const std::vector<double>& t = raw[0];
    if (t.size() > 1 && !(t.back() > t[t.size() - 2])) {
      const std::string before = "line " + std::to_string(row_line.back());
      throw CsvImportError(
          file, line_no, channels[0].label,
          "time does not increase: " + (t.back() == t[t.size() - 2]
                                            ? exact(t.back()) + " repeats the time stamp of " +
                                                  before + " (a row written twice?)"
                                            : exact(t.back()) + " after " + exact(t[t.size() - 2]) +
                                                  " on " + before + " (rows out of order?)"));
    }
    row_line.push_back(line_no);
  }
  const std::size_t n = row_line.size();
  if (n < kMinRows) {
    throw CsvImportError(
        file, 0, "",
        std::to_string(n) + " data rows; at least " + std::to_string(kMinRows) + " are needed");
  }
  ImportedSeries out;
  out.recorded = recorded_series(file, spec, channels, raw, row_line, slot);
  out.recorded.input_at_start = spec.input_at_start;
  out.warnings = out.recorded.warnings;
  out.input_rate_limit_per_s = spec.input_rate_limit_per_s;
  out.input_scale_sd = spec.input_scale_sd;

  out.input_kind = spec.input_kind;
  out.t_s.reserve(n);
  out.q1_rad.reserve(n);
  out.q2_rad.reserve(n);
  out.input.reserve(n);
  // At the row times: a reading with its own time interpolated (linear) to them, the input held
  // from when it took effect.
  const RecordedSeries& r = out.recorded;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = raw[0][i] * spec.time_scale_s;
    out.t_s.push_back(t);
    out.q1_rad.push_back(reading_at(r.q1_t_s, r.q1_rad, t, false));
    out.q2_rad.push_back(reading_at(r.q2_t_s, r.q2_rad, t, false));
    out.input.push_back(r.input_at_start && t < r.input_t_s.front()
                            ? *r.input_at_start
                            : reading_at(r.input_t_s, r.input, t, !spec.input_time.name.empty()));
  }

  std::vector<double> steps(n - 1);
  for (std::size_t i = 0; i + 1 < n; ++i) steps[i] = out.t_s[i + 1] - out.t_s[i];
  const double period = median(steps);
  std::size_t worst = 0;
  for (std::size_t i = 1; i < steps.size(); ++i) {
    if (std::abs(steps[i] - period) > std::abs(steps[worst] - period)) worst = i;
  }
  out.sample_period_s = period;
  check_sample_period(file, channels[0].label, spec, period, out.t_s.back() - out.t_s.front());

  if (std::abs(steps[worst] - period) > kIrregularTolerance * period) {
    const double span = out.t_s.back() - out.t_s.front();
    // The small allowance keeps the last time stamp on the grid despite rounding in span / period.
    const double intervals = std::floor(span / period + 1e-9);
    const std::string where = "a step of " + milliseconds(steps[worst]) + " at line " +
                              std::to_string(row_line[worst + 1]) + " against the median " +
                              milliseconds(period);
    if (intervals + 1 > static_cast<double>(kMaxResampleGrowth * n)) {
      std::ostringstream count;
      count << std::fixed << std::setprecision(0) << intervals + 1;
      throw CsvImportError(file, row_line[worst + 1], channels[0].label,
                           "time stamps too irregular to resample (" + where +
                               "): a uniform grid would need " + count.str() + " samples for " +
                               std::to_string(n) + " rows");
    }
    std::vector<double> grid(static_cast<std::size_t>(intervals) + 1);
    for (std::size_t k = 0; k < grid.size(); ++k) {
      grid[k] = std::min(out.t_s.front() + static_cast<double>(k) * period, out.t_s.back());
    }
    out.q1_rad = interpolate(out.t_s, out.q1_rad, grid);
    out.q2_rad = interpolate(out.t_s, out.q2_rad, grid);
    out.input = interpolate(out.t_s, out.input, grid);
    out.t_s = std::move(grid);
    std::ostringstream deviation;
    deviation << std::setprecision(3) << 100.0 * std::abs(steps[worst] - period) / period;
    out.warnings.push_back("irregular time stamps (largest deviation: " + where + ", " +
                           deviation.str() + " % off): resampled by linear interpolation to " +
                           milliseconds(period) + " (" + std::to_string(out.t_s.size()) +
                           " samples from " + std::to_string(n) + " rows)");
  }

  return out;
}

}  // namespace furuta::identification
