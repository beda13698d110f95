// results.json and its parts: LSMI, the SIVIA paving, the scenarios.
#include <algorithm>
#include <cmath>

#include "furuta/identification/physical.hpp"
#include "furuta/report/json.hpp"
#include "furuta/report/outputs.hpp"
#include "furuta/report/tables.hpp"

namespace furuta::report {

Json parameters_json(const model::Parameters<double>& p) {
  Json j = Json::object();
  for (std::size_t k = 0; k < p.size(); ++k) j[model::kParameterNames[k]] = p[k];
  return j;
}

Json interval_json(const interval::Interval& x) {
  if (x.is_empty()) return nullptr;
  return Json::array({x.lo(), x.hi()});
}

Json box_json(const interval::Box& box) {
  Json j = Json::array();
  for (std::size_t k = 0; k < box.size(); ++k) j.push_back(interval_json(box[k]));
  return j;
}

Json lsmi_json(const identification::LsmiResult& r) {
  return Json{{"estimate", parameters_json(r.estimate)},
              {"std_dev", parameters_json(r.std_dev)},
              {"relative_sd", parameters_json(r.relative_sd)},
              {"sigma_nm", r.sigma},
              {"condition_number", r.condition_number},
              {"rank", r.rank},
              {"rows", r.rows},
              {"warnings", r.warnings}};
}

Json results_json(const identification::Identification& id,
                  const std::vector<identification::InputFile>& inputs,
                  const std::string& software_version, const Json& more) {
  Json j;
  j["software_version"] = software_version;
  j["inputs"] = Json::array();
  for (const auto& input : inputs) {
    j["inputs"].push_back(Json{{"path", input.path}, {"sha256", input.sha256}});
  }
  j["experiments"] = Json::array();
  for (std::size_t i = 0; i < id.processed.size(); ++i) {
    Json experiment = {{"name", id.processed[i].name},
                       {"samples", id.processed[i].size()},
                       {"sample_period_s", id.processed[i].sample_period_s}};
    if (i < id.per_experiment.size()) experiment["lsmi"] = lsmi_json(id.per_experiment[i]);
    j["experiments"].push_back(std::move(experiment));
  }
  if (id.lsmi_ran()) {
    j["combined"] = lsmi_json(id.combined);
    j["input_lag_s"] = id.input_lag_s;
  } else {
    j["lsmi_skipped"] = id.lsmi_skipped;
  }
  if (id.nominal) j["nominal"] = parameters_json(*id.nominal);
  if (id.truth) j["truth"] = parameters_json(*id.truth);
  if (id.validation) {
    j["validation"] = Json{{"name", id.validation->name},
                           {"rmse_nm", id.validation->fit.rmse_nm},
                           {"rmse_percent_of_range", id.validation->fit.rmse_percent_of_range},
                           {"samples", id.validation->fit.samples}};
  }
  for (const auto& [key, value] : more.items()) j[key] = value;
  j["warnings"] = id.warnings;
  return j;
}

Json sivia_json(const identification::GuaranteedResult& r,
                const std::vector<identification::IntervalSample>& samples) {
  const interval::SubPaving& p = r.paving;
  // Inner boxes as their proof holds (the carried components where the inner test fixed them).
  const std::vector<interval::Box> proven_inner = r.proven_inner_boxes();
  Json j;
  j["unknowns"] = Json::array();
  j["parameters"] = Json::array();
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    if (r.unknown[k]) j["unknowns"].push_back(model::kParameterNames[k]);
    j["parameters"].push_back(model::kParameterNames[k]);
  }
  j["samples"] = r.samples;
  j["q"] = r.q;
  j["prior"] = box_json(p.prior);
  j["boxes_tested"] = p.boxes_tested;
  j["bisections"] = p.bisections;
  j["inner_count"] = p.inner.size();
  j["probed_inner_count"] = p.probed_inner;
  j["boundary_count"] = p.boundary.size();
  j["outer_count"] = p.outer_count;
  j["truncated"] = p.truncated;
  j["seconds"] = p.seconds;
  j["empty"] = r.empty;
  if (!r.empty) {
    j["outer_hull"] = box_json(p.outer_hull());
    if (!proven_inner.empty()) {
      interval::Box hull(p.prior.size(), interval::Interval::empty());
      for (const interval::Box& b : proven_inner) hull = interval::hull(hull, b);
      j["inner_hull"] = box_json(hull);
      // The largest inner box: parameters every one of which is proven consistent with the data.
      const auto largest =
          std::max_element(proven_inner.begin(), proven_inner.end(),
                           [&](const interval::Box& a, const interval::Box& b) {
                             return identification::unknowns_volume({a}, r.unknown) <
                                    identification::unknowns_volume({b}, r.unknown);
                           });
      j["central_feasible_box"] = box_json(*largest);
    }
  }
  j["inner_measure"] = identification::unknowns_volume(p.inner, r.unknown);
  j["boundary_measure"] = identification::unknowns_volume(p.boundary, r.unknown);
  j["finding"] = r.finding;
  const auto sample_list = [&](const std::vector<std::size_t>& list) {
    Json out = Json::array();
    for (const std::size_t i : list) {
      const identification::IntervalSample& s = samples.at(i);
      out.push_back(Json{{"experiment", s.experiment}, {"index", s.index}, {"t_s", s.t_s}});
    }
    return out;
  };
  j["inconsistent_samples"] = sample_list(r.inconsistent_samples);
  j["excluding_samples"] = sample_list(r.excluding_samples);
  j["inner"] = Json::array();
  for (const interval::Box& b : proven_inner) j["inner"].push_back(box_json(b));
  j["boundary"] = Json::array();
  for (const interval::Box& b : p.boundary) j["boundary"].push_back(box_json(b));
  return j;
}

namespace {

Json coverage_json(const validated::Coverage& c) {
  return Json{
      {"measurements", c.measurements}, {"in_time", c.in_time}, {"covered", c.covered},
      {"outside_time", c.outside_time}, {"rate", c.rate()},     {"rate_in_time", c.rate_in_time()}};
}

}  // namespace

Json scenarios_json(const std::vector<validated::ScenarioResult>& results) {
  Json rows = Json::array();
  for (const validated::ScenarioResult& r : results) {
    const model::Parameters<interval::Interval>& p = r.parameters.parameters;
    Json parameters = Json::object();
    for (std::size_t k = 0; k < p.size(); ++k) {
      parameters[model::kParameterNames[k]] = interval_json(p[k]);
    }
    rows.push_back(Json{{"scenario", r.scenario.number},
                        {"label", scenario_label(r.scenario)},
                        {"description", scenario_description(r.scenario)},
                        {"q2_initial_rad", r.scenario.q2_initial_rad},
                        {"torque_nm", r.scenario.torque_nm},
                        {"duration_s", r.scenario.duration_s},
                        {"parameter_set", r.parameters.name},
                        {"parameters", parameters},
                        {"initial_uncertainty", Json{{"q1_rad", r.uncertainty.q1_rad},
                                                     {"dq1_rad_s", r.uncertainty.dq1_rad_s},
                                                     {"q2_rad", r.uncertainty.q2_rad},
                                                     {"dq2_rad_s", r.uncertainty.dq2_rad_s}}},
                        {"status", validated::to_string(r.status)},
                        {"reason", r.reason},
                        {"t_reached_s", r.t_reached_s},
                        {"steps", r.steps},
                        {"pieces", r.pieces},
                        {"seconds", r.seconds},
                        {"coverage", Json{{"q2_step", coverage_json(r.q2_step)},
                                          {"q2_interpolated", coverage_json(r.q2_interpolated)},
                                          {"q1_step", coverage_json(r.q1_step)},
                                          {"q1_interpolated", coverage_json(r.q1_interpolated)}}},
                        {"q2_mean_width_rad", r.q2_mean_width_rad},
                        {"q2_max_width_rad", r.q2_max_width_rad}});
  }
  return rows;
}

Json simulation_json(const pipeline::Simulation& s) {
  // The measurement's resolutions as the first scenario's measurement found them.
  const validated::ScenarioMeasurement m0 =
      s.results.empty() ? validated::ScenarioMeasurement{} : s.results.front().measurement;
  std::vector<std::string> figures;
  for (const validated::ScenarioResult& r : s.results) figures.push_back(scenario_figure_name(r));
  return Json{{"truth", parameters_json(s.truth)},
              {"truth_source", measurement_source_text(s.source)},
              {"measurement", Json{{"step_s", s.measurement.step_s},
                                   {"sample_period_s", s.measurement.sample_period_s},
                                   {"arm_resolution_rad", m0.arm_resolution_rad},
                                   {"pendulum_resolution_rad", m0.pendulum_resolution_rad}}},
              {"integrator", Json{{"order", s.integrator.order},
                                  {"tolerance", s.integrator.tolerance},
                                  {"h_min", s.integrator.h_min},
                                  {"max_width", s.integrator.max_width},
                                  {"pieces", s.pieces},
                                  {"taylor_model_pieces", s.taylor_model_pieces}}},
              {"figures", figures},
              {"tubes_file", "tubes.json"},
              {"results", scenarios_json(s.results)}};
}

const char* noise_source_name(identification::AngleNoiseSource source) {
  return source == identification::AngleNoiseSource::estimated_from_readings
             ? "estimated_from_readings"
             : "encoder_resolution";
}

const char* time_stamps_name(identification::TimeStamps stamps) {
  switch (stamps) {
    case identification::TimeStamps::board_clock:
      return "board_clock";
    case identification::TimeStamps::mixed:
      return "mixed";
    case identification::TimeStamps::host:
      break;
  }
  return "host";
}

Json mistake_fit_json(const identification::MistakeFit& m) {
  Json j{{"mistake", identification::mistake_name(m.mistake)},
         {"value", m.value},
         {"converged", m.converged},
         {"residual_sigma", m.residual_sigma},
         {"physical", m.physical.consistent()},
         {"plausible", m.plausible},
         {"estimate", parameters_json(m.estimate)}};
  if (m.physical.inertia_ratio_to_cad) j["inertia_ratio_to_cad"] = *m.physical.inertia_ratio_to_cad;
  return j;
}

// The refits with each candidate recording mistake undone (identification/diagnosis.hpp).
Json diagnosis_json(const identification::Diagnosis& d) {
  Json candidates = Json::array();
  for (const auto& c : d.candidates) candidates.push_back(mistake_fit_json(c));
  Json j{{"as_recorded", mistake_fit_json(d.as_recorded)}, {"candidates", candidates}};
  j["named"] = d.named ? mistake_fit_json(*d.named) : Json(nullptr);
  return j;
}

Json output_error_json(const pipeline::OutputError& oe) {
  const identification::OutputErrorResult& r = oe.result;
  const auto joints = [](const std::array<double, 2>& v) {
    return Json{{"q1", v[0]}, {"q2", v[1]}};
  };
  Json j{{"estimate", parameters_json(r.estimate)},
         {"std_dev", parameters_json(r.std_dev)},
         {"local_std_dev", parameters_json(r.local_std_dev)},
         {"std_dev_basis",
          "per parameter the larger of two local figures at the optimum: sqrt(diag((J^T J)^-1)) "
          "of the angle residuals scaled by their estimated sigma, and the cluster-robust "
          "sandwich over the segments (errors correlated within a segment); `local_std_dev` "
          "is the first alone; the model and the input taken as exact"},
         {"input_lag_s", r.input_lag_s},
         {"input_lag_std_s", r.input_lag_std_s},
         {"q2_offset_rad", r.q2_offset_rad},
         {"input_gain", r.input_gain},
         {"angle_rms_rad", joints(r.angle_rms_rad)},
         {"continuity_rms", r.continuity_rms},
         {"residual_sigma", r.residual_sigma},
         {"angle_noise_rad", joints(r.angle_noise_rad)},
         {"angle_noise_source", Json{{"q1", noise_source_name(r.angle_noise_source[0])},
                                     {"q2", noise_source_name(r.angle_noise_source[1])}}},
         {"time_stamps", Json{{"q1", time_stamps_name(r.time_stamps[0])},
                              {"q2", time_stamps_name(r.time_stamps[1])}}},
         {"host_delay_mean_s", joints(r.host_delay_mean_s)},
         {"host_delay_max_s", joints(r.host_delay_max_s)},
         {"segments", r.segments},
         {"observations", r.observations},
         {"iterations", r.iterations},
         {"converged", r.converged},
         {"message", r.message},
         {"physical", oe.physical.consistent()},
         {"warnings", r.warnings}};
  if (oe.diagnosis) j["diagnosis"] = diagnosis_json(*oe.diagnosis);
  if (oe.held_out) {
    j["held_out_free_run"] = Json{{"name", oe.held_out->name},
                                  {"refined_rmse_rad", joints(oe.held_out->refined.rmse_rad)}};
    if (oe.held_out->lsmi) {
      j["held_out_free_run"]["lsmi_rmse_rad"] = joints(oe.held_out->lsmi->rmse_rad);
    }
  }
  return j;
}

namespace {

using identification::kScaledParameterNames;

Json intervals_json(const model::Parameters<interval::Interval>& p, bool scaled) {
  Json j = Json::object();
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    j[scaled ? kScaledParameterNames[k] : model::kParameterNames[k]] = interval_json(p[k]);
  }
  return j;
}

const char* input_source_name(identification::InputSource s) {
  switch (s) {
    case identification::InputSource::encoder_counts:
      return "encoder_counts";
    case identification::InputSource::rest_check:
      return "rest_check";
    case identification::InputSource::duty_steps:
      return "duty_steps";
    case identification::InputSource::supply_readings:
      return "supply_readings";
    case identification::InputSource::data_sheet:
      return "data_sheet";
    case identification::InputSource::configured:
      return "configured";
    case identification::InputSource::cad:
      return "cad";
    case identification::InputSource::import_spec:
      return "import_spec";
  }
  return "configured";
}

const char* windowed_verdict_name(identification::WindowedSetVerdict v) {
  switch (v) {
    case identification::WindowedSetVerdict::contracted:
      return "contracted";
    case identification::WindowedSetVerdict::empty:
      return "empty";
    case identification::WindowedSetVerdict::unresolved:
      return "unresolved";
  }
  return "unresolved";
}

}  // namespace

Json windowed_json(const pipeline::WindowedGuaranteed& w,
                   const std::vector<pipeline::EstimateOutsideSet>& excludes_output_error) {
  const identification::WindowedSet& r = w.result;
  Json j;
  j["method"] = "windowed set inversion through the Taylor-model flow";
  j["verdict"] = windowed_verdict_name(r.verdict);
  j["finding"] = r.finding;
  j["scaled_parameters"] = Json{
      {"names", kScaledParameterNames},
      {"definition",
       "mu_k / g, b = (fv1 + k_w) / g, fv2 / g: g the drive's gain [N m per unit duty], k_w its "
       "back-EMF damping [N m s]; the model with the applied duty as its input"}};
  j["search"] =
      Json{{"centre", "output-error estimate"}, {"sd", w.search_sd},
           {"estimate_gain_nm", w.gain_nm},     {"estimate_back_emf_nm_s", w.back_emf_nm_s},
           {"estimate_scaled", Json::object()}, {"box_scaled", intervals_json(r.search, true)}};
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    j["search"]["estimate_scaled"][kScaledParameterNames[k]] = w.estimate_scaled[k];
  }
  j["set_scaled"] = intervals_json(r.set, true);
  if (r.verdict != identification::WindowedSetVerdict::empty) {
    j["set_rig"] = intervals_json(w.rig_set, false);
    Json share = Json::object();
    for (std::size_t k = 0; k < model::kParameterCount; ++k) {
      share[model::kParameterNames[k]] = w.drive_share[k];
    }
    j["drive_share_of_rig_width"] = share;
  }
  if (w.truth_scaled) {
    Json truth = Json::object();
    for (std::size_t k = 0; k < model::kParameterCount; ++k) {
      truth[kScaledParameterNames[k]] = (*w.truth_scaled)[k];
    }
    j["truth_scaled"] = truth;
  }
  j["drive"] =
      Json{{"gain_nm", interval_json(w.inputs.drive.gain_nm())},
           {"back_emf_damping_nm_s", interval_json(w.inputs.drive.back_emf_damping_nm_s())}};
  j["lag_s"] = interval_json(r.lag_s);
  j["pendulum_zero_rad"] = interval_json(r.pendulum_zero_rad);
  j["windows"] = Json::array();
  for (const identification::WindowRecord& record : r.windows) {
    j["windows"].push_back(Json{{"recording", record.recording},
                                {"index", record.index},
                                {"t0_s", record.t0_s},
                                {"t1_s", record.t1_s},
                                {"reached_s", record.reached_s},
                                {"readings", record.readings},
                                {"verdict", window_verdict_name(record.verdict)},
                                {"reason", record.reason}});
  }
  j["set_after_step"] = Json::array();
  for (const auto& p : r.set_after_step) j["set_after_step"].push_back(intervals_json(p, true));
  j["seconds"] = r.seconds;
  j["flow_seconds"] = r.flow_seconds;
  j["flow_steps"] = r.flow_steps;
  j["shrink_wraps"] = r.shrink_wraps;
  j["physical_inputs"] = Json::array();
  for (const identification::PhysicalInput& in : w.inputs.provenance) {
    j["physical_inputs"].push_back(Json{{"quantity", in.quantity},
                                        {"value", interval_json(in.value)},
                                        {"unit", in.unit},
                                        {"source", input_source_name(in.source)},
                                        {"setting", in.setting}});
  }
  Json excluded = Json::array();
  for (const pipeline::EstimateOutsideSet& e : excludes_output_error) {
    excluded.push_back(Json{{"parameter", kScaledParameterNames[e.parameter]},
                            {"output_error_estimate", e.estimate},
                            {"set", interval_json(e.set)},
                            {"sd_away", std::isinf(e.sd_away) ? Json(nullptr) : Json(e.sd_away)},
                            {"text", windowed_excluded_text(e)}});
  }
  j["excludes_output_error"] = excluded;
  return j;
}

Json results_json(const pipeline::Run& run, const std::string& software_version) {
  Json more = Json::object();
  if (run.output_error) more["output_error"] = output_error_json(*run.output_error);
  if (run.sivia) {
    more["sivia"] = sivia_json(run.sivia->result, run.sivia->samples);
    more["sivia"]["paving_file"] = "paving.json";
    // Only when the set excludes it: a consistent run's results.json stays as it was.
    if (!run.sivia_excludes_output_error.empty()) {
      Json excluded = Json::array();
      for (const pipeline::EstimateOutsideSet& e : run.sivia_excludes_output_error) {
        excluded.push_back(
            Json{{"parameter", model::kParameterNames[e.parameter]},
                 {"output_error_estimate", e.estimate},
                 {"set", interval_json(e.set)},
                 {"sd_away", std::isinf(e.sd_away) ? Json(nullptr) : Json(e.sd_away)},
                 {"text", excluded_estimate_text(e)}});
      }
      more["sivia"]["excludes_output_error"] = excluded;
    }
  }
  if (!run.sivia && run.settings.sivia.run) {
    more["sivia"] =
        Json{{"skipped", pipeline::warning_text(run.warnings, pipeline::Warning::Stage::sivia,
                                                pipeline::Warning::Kind::skipped)}};
  }
  if (run.windowed) {
    more["guaranteed"] = windowed_json(*run.windowed, run.windowed_excludes_output_error);
  } else if (run.settings.windowed.run) {
    more["guaranteed"] =
        Json{{"verdict", "skipped"},
             {"finding", pipeline::warning_text(run.warnings, pipeline::Warning::Stage::guaranteed,
                                                pipeline::Warning::Kind::skipped)}};
  }
  if (run.simulation) more["simulation"] = simulation_json(*run.simulation);
  // Only when there is something to say: a consistent fit's results.json stays as it was.
  const identification::PhysicalCheck& physical = run.physical;
  if (!physical.consistent() || physical.cause != identification::LikelyCause::none) {
    Json violations = Json::array();
    for (const auto& v : physical.violations) {
      violations.push_back(
          Json{{"condition", identification::condition_text(v.condition)},
               {"margin", v.margin},
               {"margin_sd", v.margin_sd},
               {"sigmas", std::isfinite(v.sigmas) ? Json(v.sigmas) : Json(nullptr)},
               {"within_noise", v.within_noise}});
    }
    Json candidates = Json::array();
    for (const auto c : physical.candidates) candidates.push_back(identification::cause_name(c));
    more["physical"] =
        Json{{"consistent", physical.consistent()},
             {"violations", violations},
             {"likely_cause", identification::cause_name(physical.cause)},
             {"candidates", candidates},
             {"reference",
              physical.reference == identification::MagnitudeReference::cad ? "cad" : "internal"}};
    if (physical.inertia_ratio_to_cad) {
      more["physical"]["inertia_ratio_to_cad"] = *physical.inertia_ratio_to_cad;
    }
    if (physical.pendulum_frequency_rad_s) {
      more["physical"]["pendulum_frequency_rad_s"] = *physical.pendulum_frequency_rad_s;
    }
  }
  return results_json(run.identification, run.inputs, software_version, more);
}

Json batch_json(const BatchManifest& batch) {
  const auto entry = [](const BatchManifest::Log& log) {
    return Json{{"log", log.log}, {"label", log.label}};
  };
  Json j;
  j["identification"] = batch.identification;
  j["identified_at"] = batch.identified_at;
  j["logs_dir"] = batch.logs_dir;
  j["fit"] = Json::array();
  for (const auto& log : batch.fit) j["fit"].push_back(entry(log));
  j["validation"] = batch.validation ? entry(*batch.validation) : Json();
  return j;
}

}  // namespace furuta::report
