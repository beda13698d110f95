// rig.toml's sections for identification: [identification], [output_error], [sivia],
// [guaranteed], [automation].
#include <algorithm>
#include <cmath>
#include <string>

#include "sections.hpp"

namespace furuta::config::detail {

namespace {

// [sivia]'s error bounds of the preprocessed data, [absolute, relative] per channel.
void read_data_bounds(Section& s, SiviaConfig& sc) {
  sc.q2_bound = s.numbers("q2_bound", sc.q2_bound, non_negative, ">= 0");
  sc.dq1_bound = s.numbers("dq1_bound", sc.dq1_bound, non_negative, ">= 0");
  sc.dq2_bound = s.numbers("dq2_bound", sc.dq2_bound, non_negative, ">= 0");
  sc.ddq1_bound = s.numbers("ddq1_bound", sc.ddq1_bound, non_negative, ">= 0");
  sc.ddq2_bound = s.numbers("ddq2_bound", sc.ddq2_bound, non_negative, ">= 0");
  sc.tau_bound = s.numbers("tau_bound", sc.tau_bound, non_negative, ">= 0");
}

}  // namespace

IdentificationConfig read_identification(Section s, const DaemonConfig& daemon) {
  IdentificationConfig ic;
  const double nyquist_hz = 0.5e9 / static_cast<double>(daemon.period_ns);
  ic.cutoff_hz = s.number(
      "cutoff_hz", ic.cutoff_hz, [&](double v) { return v > 0 && 2 * v < nyquist_hz; },
      "in (0, Nyquist / 2) (the differentiator's stop band starts at twice it)");
  ic.butterworth_order = static_cast<int>(s.integer(
      "butterworth_order", ic.butterworth_order, [](std::int64_t v) { return v >= 1 && v <= 16; },
      "in [1, 16]"));
  ic.differentiator_taps = static_cast<int>(s.integer(
      "differentiator_taps", ic.differentiator_taps,
      [](std::int64_t v) { return v >= 5 && v <= 201 && v % 2 == 1; }, "odd, in [5, 201]"));
  ic.input_lag_ms = s.optional_number(
      "input_lag_ms", [](double v) { return v >= 0 && v <= 100; },
      "in [0, 100] (the angles cannot lead the input)");
  s.reject_unknown_keys();
  return ic;
}

OutputErrorConfig read_output_error(Section s) {
  OutputErrorConfig oc;
  oc.enabled = s.boolean("enabled", oc.enabled);
  // A segment needs several pendulum swings' worth of angles against its 4 initial states, and
  // beyond a few seconds the upright region's divergence makes the fit lose phase.
  oc.segment_s = s.number(
      "segment_s", oc.segment_s, [](double v) { return v >= 0.05 && v <= 10; }, "in [0.05, 10]");
  oc.substep_s = s.number(
      "substep_s", oc.substep_s, [](double v) { return v > 0 && v <= 0.01; },
      "in (0, 0.01] (the arm's time constant is 4.4 ms)");
  oc.estimate_lag = s.boolean("estimate_lag", oc.estimate_lag);
  oc.max_iterations = static_cast<int>(s.integer(
      "max_iterations", oc.max_iterations, [](std::int64_t v) { return v >= 1 && v <= 10000; },
      "in [1, 10000]"));
  s.reject_unknown_keys();
  return oc;
}

SiviaConfig read_sivia(Section s) {
  SiviaConfig sc;
  sc.unknowns = s.choices("unknowns", sc.unknowns, model::kParameterNames);
  if (sc.unknowns.empty()) {
    s.fail("unknowns", s.node("unknowns"), "must name at least one parameter");
  }
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
                           {{"witness", SiviaInnerTest::witness},
                            {"intermediate_value", SiviaInnerTest::intermediate_value},
                            {"for_all_data", SiviaInnerTest::for_all_data},
                            {"none", SiviaInnerTest::none}});
  sc.q = static_cast<int>(s.integer("q", sc.q, non_negative_integer, ">= 0"));
  sc.threads = static_cast<int>(s.integer(
      "threads", sc.threads, [](std::int64_t v) { return v >= 0 && v <= 1024; }, "in [0, 1024]"));
  read_data_bounds(s, sc);
  s.reject_unknown_keys();
  return sc;
}

GuaranteedConfig read_guaranteed(Section s) {
  GuaranteedConfig gc;
  gc.prior_percent = s.number(
      "prior_percent", gc.prior_percent, [](double v) { return v > 0 && v < 100; },
      "in (0, 100) (a mu's prior must stay positive)");
  const auto ordered = [&](const char* key, std::array<double, 2> fallback, double low,
                           const char* what) {
    const std::array<double, 2> v = s.numbers(key, fallback);
    if (!(v[0] >= low && v[0] < v[1])) s.fail(key, s.node(key), what);
    return v;
  };
  gc.friction_prior = ordered("friction_prior", gc.friction_prior, 0.0,
                              "must be [low, high] with 0 <= low < high (friction takes energy)");
  gc.lag_ms = ordered("lag_ms", gc.lag_ms, 0.0,
                      "must be [low, high] with 0 <= low < high (an angle cannot lead its state)");
  gc.motor_tolerance_pct = s.numbers(
      "motor_tolerance_pct", gc.motor_tolerance_pct, [](double v) { return v >= 0 && v < 50; },
      "in [0, 50)");
  gc.search_sd = s.number(
      "search_sd", gc.search_sd, [](double v) { return v > 0 && v <= 1000; }, "in (0, 1000]");
  gc.window_s = s.number(
      "window_s", gc.window_s, [](double v) { return v >= 0.01 && v <= 1.0; },
      "in [0.01, 1] s (the flow carries a box a fraction of a second)");
  gc.windows = static_cast<int>(s.integer(
      "windows", gc.windows, [](std::int64_t v) { return v >= 1 && v <= 1000; }, "in [1, 1000]"));
  gc.arm_rest_speed_rad_s = s.number(
      "arm_rest_speed_rad_s", gc.arm_rest_speed_rad_s, [](double v) { return v >= 0 && v <= 10; },
      "in [0, 10] rad/s");
  s.reject_unknown_keys();
  return gc;
}

AutomationConfig read_automation(Section s) {
  AutomationConfig ac;
  ac.fit_labels = s.names("fit_labels", ac.fit_labels);
  if (ac.fit_labels.empty()) {
    s.fail("fit_labels", s.node("fit_labels"), "must name at least one label");
  }
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
  ac.guaranteed = s.boolean("guaranteed", ac.guaranteed);
  ac.simulate = s.boolean("simulate", ac.simulate);
  ac.simulate_seconds = s.number(
      "simulate_seconds", ac.simulate_seconds, [](double v) { return v >= 0.01 && v <= 60; },
      "in [0.01, 60]");
  ac.identifications_dir = s.text("identifications_dir", ac.identifications_dir);
  if (ac.identifications_dir.empty()) {
    s.fail("identifications_dir", s.node("identifications_dir"), "must not be empty");
  }
  s.reject_unknown_keys();
  return ac;
}

}  // namespace furuta::config::detail
