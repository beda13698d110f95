#include "furuta/validated/scenarios.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "furuta/common/text_format.hpp"

namespace furuta::validated {

namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

double deg_to_rad(double deg) {
  return deg / kDegPerRad;
}

std::string fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

// A number as a person writes it in a scenario's description: -100, 0.17, 0.
std::string short_number(double v) {
  std::ostringstream s;
  s << std::setprecision(6) << (v == 0.0 ? 0.0 : v);
  return s.str();
}

std::string percent(double rate) {
  return fixed(100.0 * rate, 1) + " %";
}

}  // namespace

std::string Scenario::label() const {
  if (number >= 1 && number <= 26)
    return std::string("(") + static_cast<char>('a' + number - 1) + ")";
  return "#" + std::to_string(number);
}

std::string Scenario::description() const {
  return "x0 = [0, 0, " + short_number(std::round(q2_initial_rad * kDegPerRad * 1e6) / 1e6) +
         " deg, 0], u = " + short_number(torque_nm) + " N m";
}

std::vector<Scenario> paper_scenarios() {
  return {
      Scenario{1, deg_to_rad(-100.0), 0.0, 4.0},
      Scenario{2, deg_to_rad(50.0), 0.0, 4.0},
      Scenario{3, deg_to_rad(-90.0), 0.17, 4.0},
      Scenario{4, deg_to_rad(-45.0), -0.1, 4.0},
  };
}

Scenario paper_scenario(int number) {
  if (number < 1 || number > 4) {
    throw std::invalid_argument("scenario " + std::to_string(number) +
                                ": the paper's scenarios are 1 to 4");
  }
  return paper_scenarios()[static_cast<std::size_t>(number - 1)];
}

ScenarioMeasurement measure_scenario(const Scenario& scenario,
                                     const model::Parameters<double>& truth,
                                     const MeasurementOptions& options) {
  if (!(options.step_s > 0.0) || !(options.sample_period_s > 0.0) || !(scenario.duration_s > 0.0) ||
      !std::isfinite(scenario.duration_s)) {
    throw std::invalid_argument("measure_scenario: step, sample period and duration must be > 0");
  }
  const double steps_real = options.sample_period_s / options.step_s;
  const long steps_per_sample = std::lround(steps_real);
  if (steps_per_sample < 1 || std::abs(steps_real - static_cast<double>(steps_per_sample)) > 1e-9) {
    throw std::invalid_argument(
        "measure_scenario: the sample period " + short_number(options.sample_period_s) +
        " s is not a whole number of steps of " + short_number(options.step_s) + " s");
  }
  if (options.arm_resolution_rad < 0.0 || options.pendulum_resolution_rad < 0.0) {
    throw std::invalid_argument("measure_scenario: negative encoder resolution");
  }
  ScenarioMeasurement m;
  m.arm_resolution_rad = options.arm_resolution_rad > 0.0 ? options.arm_resolution_rad
                                                          : 2 * std::numbers::pi / (512 * 26.0);
  m.pendulum_resolution_rad = options.pendulum_resolution_rad > 0.0
                                  ? options.pendulum_resolution_rad
                                  : 2 * std::numbers::pi / 4096;
  const auto quantise = [](double x, double resolution) {
    return std::round(x / resolution) * resolution;
  };
  model::PendulumState x{0.0, 0.0, scenario.q2_initial_rad, 0.0};
  const auto torque = [&](const model::PendulumState&) { return scenario.torque_nm; };
  // Sample times as k T (not accumulated) so they land on the tube's step ends where they should.
  for (long k = 0;; ++k) {
    const double t = static_cast<double>(k) * options.sample_period_s;
    if (t > scenario.duration_s * (1 + 1e-12)) break;
    m.t_s.push_back(t);
    m.q1_rad.push_back(quantise(x.q1, m.arm_resolution_rad));
    m.q2_rad.push_back(quantise(x.q2, m.pendulum_resolution_rad));
    m.q1_true_rad.push_back(x.q1);
    m.q2_true_rad.push_back(x.q2);
    for (long s = 0; s < steps_per_sample; ++s)
      x = model::rk4_step(truth, x, options.step_s, torque);
  }
  return m;
}

interval::Box initial_state_box(const Scenario& scenario, const StateUncertainty& u) {
  for (const double h : {u.q1_rad, u.dq1_rad_s, u.q2_rad, u.dq2_rad_s}) {
    if (!(h >= 0.0) || !std::isfinite(h)) {
      throw std::invalid_argument("initial state uncertainty: half-widths must be finite and >= 0");
    }
  }
  const auto around = [](double centre, double half) {
    return interval::Interval(centre) + interval::Interval(-half, half);
  };
  return interval::Box{around(0.0, u.q1_rad), around(0.0, u.dq1_rad_s),
                       around(scenario.q2_initial_rad, u.q2_rad), around(0.0, u.dq2_rad_s)};
}

ParameterSet point_parameters(std::string name, const model::Parameters<double>& p) {
  return ParameterSet{std::move(name), interval_parameters(p)};
}

ParameterSet interval_parameters(std::string name, const model::Parameters<double>& mu_centre,
                                 const std::array<double, 5>& mu_percent,
                                 const interval::Interval& fv1, const interval::Interval& fv2) {
  for (const double pct : mu_percent) {
    if (!(pct >= 0.0) || !std::isfinite(pct)) {
      throw std::invalid_argument("interval parameters: the mu's percentages must be >= 0");
    }
  }
  if (fv1.is_empty() || !fv1.is_bounded() || fv2.is_empty() || !fv2.is_bounded()) {
    throw std::invalid_argument("interval parameters: fv1 and fv2 must be bounded, non-empty");
  }
  // Enclosed in interval arithmetic: centre * (1 +- pct / 100).
  const auto widen = [](double centre, double pct) {
    return interval::Interval(centre) *
           (interval::Interval(1.0) + interval::Interval(-pct, pct) / interval::Interval(100.0));
  };
  ParameterSet set;
  set.name = std::move(name);
  set.parameters.mu1 = widen(mu_centre.mu1, mu_percent[0]);
  set.parameters.mu2 = widen(mu_centre.mu2, mu_percent[1]);
  set.parameters.mu3 = widen(mu_centre.mu3, mu_percent[2]);
  set.parameters.mu4 = widen(mu_centre.mu4, mu_percent[3]);
  set.parameters.mug = widen(mu_centre.mug, mu_percent[4]);
  set.parameters.fv1 = fv1;
  set.parameters.fv2 = fv2;
  return set;
}

std::vector<const Tube*> ScenarioTubes::views() const {
  std::vector<const Tube*> out;
  for (const Tube& t : pieces) out.push_back(&t);
  return out;
}

IntegratorOptions scenario_integrator_options() {
  IntegratorOptions o;
  o.tolerance = 1e-11;
  o.max_inflation = 1.0;
  o.max_width = 2 * std::numbers::pi;
  return o;
}

SplitOptions scenario_split_options(std::size_t pieces, double duration_s) {
  if (pieces == 1) return single_tube();
  if (pieces == 0 || (pieces & (pieces - 1)) != 0 || pieces > 64) {
    throw std::invalid_argument("pieces: " + std::to_string(pieces) +
                                " is not one of 1, 2, 4, 8, 16, 32, 64");
  }
  SplitOptions o;
  o.max_pieces = pieces;
  o.planned_depth = std::countr_zero(pieces);
  o.max_depth = o.planned_depth;
  o.planned_split_s = std::min(0.5, duration_s / 8);
  return o;
}

namespace {

bool all_points(const model::Parameters<Interval>& p) {
  for (const Interval* x : {&p.mu1, &p.mu2, &p.mu3, &p.mu4, &p.mug, &p.fv1, &p.fv2}) {
    if (x->width() != 0.0) return false;
  }
  return true;
}

}  // namespace

ScenarioTubes run_scenario_tubes(const Scenario& scenario,
                                 const model::Parameters<Interval>& parameters,
                                 const StateUncertainty& uncertainty, IntegratorOptions options,
                                 const SplitOptions& split) {
  options.t_start = 0.0;
  options.t_end = scenario.duration_s;
  const Interval torque(scenario.torque_nm);
  const Box state = initial_state_box(scenario, uncertainty);
  // Point parameters need not be carried as state: the 4-dimensional system is several times
  // cheaper per step and its q1, dq1, q2, dq2 are the same components.
  SplitResult r =
      all_points(parameters)
          ? integrate_split(FurutaStateDynamics(parameters, torque), state, options, split)
          : integrate_split(FurutaDynamics(torque), FurutaDynamics::initial_box(state, parameters),
                            options, split);
  ScenarioTubes out;
  out.status = r.status;
  out.reason = r.reason;
  out.steps = r.steps;
  out.seconds = r.seconds;
  out.pieces = std::move(r.pieces);
  out.t_reached_s = time_reached(out.views());
  return out;
}

ScenarioResult evaluate_tubes(const Scenario& scenario, const ParameterSet& parameters,
                              const StateUncertainty& uncertainty,
                              const ScenarioMeasurement& measurement, const ScenarioTubes& tubes) {
  const std::vector<const Tube*> pieces = tubes.views();
  ScenarioResult r;
  r.scenario = scenario;
  r.parameters = parameters;
  r.uncertainty = uncertainty;
  r.status = tubes.status;
  r.reason = tubes.reason;
  r.t_reached_s = time_reached(pieces);
  r.steps = tubes.steps;
  r.pieces = tubes.pieces.size();
  r.seconds = tubes.seconds;
  const auto q1 = FurutaDynamics::q1;
  const auto q2 = FurutaDynamics::q2;
  r.q1_step = coverage(pieces, q1, measurement.t_s, measurement.q1_rad, CoverageMode::step);
  r.q1_interpolated =
      coverage(pieces, q1, measurement.t_s, measurement.q1_rad, CoverageMode::interpolated);
  r.q2_step = coverage(pieces, q2, measurement.t_s, measurement.q2_rad, CoverageMode::step,
                       &r.q2_covered_step);
  r.q2_interpolated =
      coverage(pieces, q2, measurement.t_s, measurement.q2_rad, CoverageMode::interpolated);
  double width_sum = 0.0;
  std::size_t widths = 0;
  for (const double t : measurement.t_s) {
    const interval::Interval e = enclosure_at(pieces, q2, t);
    if (e.is_empty()) continue;
    width_sum += e.width();
    r.q2_max_width_rad = std::max(r.q2_max_width_rad, e.width());
    ++widths;
  }
  r.q2_mean_width_rad = widths == 0 ? 0.0 : width_sum / static_cast<double>(widths);
  for (const Tube* tube : pieces) {
    for (const TubeStep& s : tube->steps) {
      r.q2_tube.push_back({s.t0, s.t1, s.over[q2].lo(), s.over[q2].hi()});
    }
  }
  r.measurement = measurement;
  return r;
}

ScenarioResult evaluate_scenario(const Scenario& scenario, const ParameterSet& parameters,
                                 const ScenarioMeasurement& measurement,
                                 const StateUncertainty& uncertainty,
                                 const IntegratorOptions& options, const SplitOptions& split) {
  const ScenarioTubes tubes =
      run_scenario_tubes(scenario, parameters.parameters, uncertainty, options, split);
  return evaluate_tubes(scenario, parameters, uncertainty, measurement, tubes);
}

std::string svg_scenario(const ScenarioResult& r) {
  const double width = 860, height = 440;
  const double left = 70, right = 20, top = 50, bottom = 120;
  const double plot_w = width - left - right, plot_h = height - top - bottom;
  const ScenarioMeasurement& m = r.measurement;
  const double t_max = std::max(r.scenario.duration_s, m.t_s.empty() ? 0.0 : m.t_s.back());

  // The view follows the measurement (with a margin): a tube that blew up before its run ended
  // would otherwise flatten everything; it is clipped to the plot instead.
  double y_lo = std::numeric_limits<double>::infinity();
  double y_hi = -y_lo;
  for (const double q : m.q2_rad) {
    y_lo = std::min(y_lo, q * kDegPerRad);
    y_hi = std::max(y_hi, q * kDegPerRad);
  }
  if (!(y_lo <= y_hi)) {
    y_lo = r.scenario.q2_initial_rad * kDegPerRad - 10;
    y_hi = y_lo + 20;
  }
  const double margin = std::max(5.0, 0.1 * (y_hi - y_lo));
  y_lo -= margin;
  y_hi += margin;
  const auto px = [&](double t) { return left + plot_w * t / t_max; };
  const auto py = [&](double deg) {
    const double clipped = std::clamp(deg, y_lo, y_hi);
    return top + plot_h * (y_hi - clipped) / (y_hi - y_lo);
  };

  std::ostringstream s;
  s << std::fixed << std::setprecision(2);
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
    << "\" viewBox=\"0 0 " << width << " " << height
    << "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  s << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  s << "<text x=\"" << width / 2 << "\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">"
    << text::xml_escape("Scenario " + r.scenario.label() + ": " + r.scenario.description() + ", " +
                        r.parameters.name + " parameters")
    << "</text>\n";

  // Axes, ticks and grid.
  s << "<g stroke=\"#ccc\" stroke-width=\"0.5\">\n";
  const double t_tick = t_max > 2 ? 0.5 : (t_max > 0.5 ? 0.1 : 0.05);
  for (double t = 0; t <= t_max + 1e-9; t += t_tick) {
    s << "<line x1=\"" << px(t) << "\" y1=\"" << top << "\" x2=\"" << px(t) << "\" y2=\""
      << top + plot_h << "\"/>\n";
  }
  const double span = y_hi - y_lo;
  const double raw_step = span / 8;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw_step)));
  const double y_tick = raw_step / magnitude < 2   ? 2 * magnitude
                        : raw_step / magnitude < 5 ? 5 * magnitude
                                                   : 10 * magnitude;
  for (double y = std::ceil(y_lo / y_tick) * y_tick; y <= y_hi; y += y_tick) {
    s << "<line x1=\"" << left << "\" y1=\"" << py(y) << "\" x2=\"" << left + plot_w << "\" y2=\""
      << py(y) << "\"/>\n";
  }
  s << "</g>\n<g font-size=\"11\">\n";
  for (double t = 0; t <= t_max + 1e-9; t += t_tick) {
    s << "<text x=\"" << px(t) << "\" y=\"" << top + plot_h + 15 << "\" text-anchor=\"middle\">"
      << short_number(std::round(t * 1000) / 1000) << "</text>\n";
  }
  for (double y = std::ceil(y_lo / y_tick) * y_tick; y <= y_hi; y += y_tick) {
    s << "<text x=\"" << left - 6 << "\" y=\"" << py(y) + 4 << "\" text-anchor=\"end\">"
      << short_number(std::round(y * 1e6) / 1e6) << "</text>\n";
  }
  s << "</g>\n";
  s << "<rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << plot_w << "\" height=\""
    << plot_h << "\" fill=\"none\" stroke=\"black\"/>\n";
  s << "<text x=\"" << left + plot_w / 2 << "\" y=\"" << top + plot_h + 34
    << "\" text-anchor=\"middle\">time t [s]</text>\n";
  s << "<text transform=\"translate(18," << top + plot_h / 2
    << ") rotate(-90)\" text-anchor=\"middle\">pendulum angle q2 [deg]</text>\n";

  // The tube: step boxes, merged within a pixel column (a 4 s run has over a thousand steps).
  s << "<g class=\"tube\" fill=\"#6fa8dc\" fill-opacity=\"0.55\" stroke=\"none\">\n";
  const auto emit = [&](const TubeBand& b) {
    const double x0 = px(b.t0_s);
    const double x1 = std::max(px(b.t1_s), x0 + 0.5);
    const double y0 = py(b.hi_rad * kDegPerRad);
    const double y1 = std::max(py(b.lo_rad * kDegPerRad), y0 + 0.5);
    s << "<rect x=\"" << x0 << "\" y=\"" << y0 << "\" width=\"" << x1 - x0 << "\" height=\""
      << y1 - y0 << "\"/>\n";
  };
  bool open = false;
  TubeBand group;
  for (const TubeBand& b : r.q2_tube) {
    if (open && b.t0_s >= group.t0_s && px(b.t1_s) - px(group.t0_s) < 2.0) {
      group.t1_s = std::max(group.t1_s, b.t1_s);
      group.lo_rad = std::min(group.lo_rad, b.lo_rad);
      group.hi_rad = std::max(group.hi_rad, b.hi_rad);
      continue;
    }
    if (open) emit(group);
    group = b;
    open = true;
  }
  if (open) emit(group);
  s << "</g>\n";

  // Where the tube ends before the scenario does.
  if (r.t_reached_s < r.scenario.duration_s) {
    s << "<line class=\"tube-end\" x1=\"" << px(r.t_reached_s) << "\" y1=\"" << top << "\" x2=\""
      << px(r.t_reached_s) << "\" y2=\"" << top + plot_h
      << "\" stroke=\"#cc0000\" stroke-dasharray=\"5,3\"/>\n";
    s << "<text x=\"" << px(r.t_reached_s) + 4 << "\" y=\"" << top + 14
      << "\" fill=\"#cc0000\" font-size=\"11\">tube ends at " << fixed(r.t_reached_s, 3)
      << " s</text>\n";
  }

  // The measurement: a thin line through the samples, the samples the paper's test misses red.
  s << "<polyline class=\"measured\" fill=\"none\" stroke=\"black\" stroke-width=\"0.8\" "
       "points=\"";
  for (std::size_t k = 0; k < m.t_s.size(); ++k) {
    s << (k ? " " : "") << px(m.t_s[k]) << "," << py(m.q2_rad[k] * kDegPerRad);
  }
  s << "\"/>\n<g class=\"samples\">\n";
  for (std::size_t k = 0; k < m.t_s.size(); ++k) {
    const bool covered = k < r.q2_covered_step.size() && r.q2_covered_step[k];
    s << "<circle cx=\"" << px(m.t_s[k]) << "\" cy=\"" << py(m.q2_rad[k] * kDegPerRad)
      << "\" r=\"1.8\" fill=\"" << (covered ? "black" : "#cc0000") << "\"/>\n";
  }
  s << "</g>\n";

  // Legend.
  const double ly = top + plot_h + 55;
  s << "<g class=\"legend\">\n";
  s << "<rect x=\"" << left << "\" y=\"" << ly - 10 << "\" width=\"18\" height=\"10\" "
    << "fill=\"#6fa8dc\" fill-opacity=\"0.55\"/>\n";
  s << "<text x=\"" << left + 24 << "\" y=\"" << ly << "\">"
    << text::xml_escape("tube [q2], " + r.parameters.name +
                        " parameters, x0 +- data uncertainty (" + std::to_string(r.steps) +
                        " steps, " + to_string(r.status) + ", reached " + fixed(r.t_reached_s, 3) +
                        " of " + fixed(r.scenario.duration_s, 1) + " s)")
    << "</text>\n";
  s << "<circle cx=\"" << left + 9 << "\" cy=\"" << ly + 13 << "\" r=\"2.5\" fill=\"black\"/>\n";
  s << "<circle cx=\"" << left + 15 << "\" cy=\"" << ly + 13 << "\" r=\"2.5\" fill=\"#cc0000\"/>\n";
  s << "<text x=\"" << left + 24 << "\" y=\"" << ly + 17 << "\">"
    << text::xml_escape("measured q2 (simulated rig, every " +
                        short_number(m.t_s.size() > 1 ? (m.t_s[1] - m.t_s[0]) * 1000 : 0.0) +
                        " ms, quantised); red: outside the paper's test")
    << "</text>\n";
  s << "<text x=\"" << left << "\" y=\"" << ly + 36 << "\">"
    << text::xml_escape("coverage of q2: step (paper) " + percent(r.q2_step.rate()) +
                        " of all samples, " + percent(r.q2_step.rate_in_time()) +
                        " of those reached; interpolated " + percent(r.q2_interpolated.rate()) +
                        " (" + percent(r.q2_interpolated.rate_in_time()) + ")")
    << "</text>\n";
  s << "</g>\n</svg>\n";
  return s.str();
}

}  // namespace furuta::validated
