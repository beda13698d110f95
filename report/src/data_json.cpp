// tubes.json and paving.json: every tube step of every scenario run, every SIVIA box with its
// verdict and the data boxes SIVIA was given, for checking the results outside the project.
#include <array>

#include "furuta/model/parameters.hpp"
#include "furuta/report/json.hpp"
#include "furuta/report/tables.hpp"

namespace furuta::report {

namespace {

// The tubes' components: the state, then the parameters when they are carried as state, then the
// torque when it is carried too (validated::run_scenario_taylor_models).
constexpr std::size_t kComponentCount = 4 + model::kParameterCount + 1;
// The state's, then model::kParameterNames (or kParameterUnits), then the torque's.
constexpr std::array<const char*, kComponentCount> components(
    const std::array<const char*, 4>& state,
    const std::array<const char*, model::kParameterCount>& parameters, const char* torque) {
  std::array<const char*, kComponentCount> out{};
  for (std::size_t i = 0; i < 4; ++i) out[i] = state[i];
  for (std::size_t k = 0; k < model::kParameterCount; ++k) out[4 + k] = parameters[k];
  out[kComponentCount - 1] = torque;
  return out;
}
constexpr auto kComponents = components({"q1", "dq1", "q2", "dq2"}, model::kParameterNames, "tau");
constexpr auto kUnits = components({"rad", "rad/s", "rad", "rad/s"}, model::kParameterUnits, "N m");
// The same per unit of a drive gain in N m (a set whose torque_scale is not 1).
constexpr const char* kUnitsPerGain[] = {"rad", "rad/s", "rad", "rad/s", "s^2", "s^2",
                                         "s^2", "s^2",   "1",   "s",     "s",   "1"};

Json tube_json(const validated::ScenarioResult& r, const pipeline::TubeSet& tubes) {
  Json run;
  run["scenario"] = r.scenario.number;
  run["label"] = scenario_label(r.scenario);
  run["q2_initial_rad"] = r.scenario.q2_initial_rad;
  run["torque_nm"] = r.scenario.torque_nm;
  run["duration_s"] = r.scenario.duration_s;
  run["parameter_set"] = r.parameters.name;
  Json parameters = Json::object();
  for (std::size_t k = 0; k < r.parameters.parameters.size(); ++k) {
    parameters[model::kParameterNames[k]] = interval_json(r.parameters.parameters[k]);
  }
  run["parameters"] = parameters;
  run["status"] = validated::to_string(r.status);
  run["t_reached_s"] = r.t_reached_s;
  run["steps"] = r.steps;
  const bool per_gain = r.parameters.torque_scale != interval::Interval(1.0);
  if (per_gain) run["torque_scale"] = interval_json(r.parameters.torque_scale);
  run["components"] = Json::array();
  run["units"] = Json::array();
  for (std::size_t i = 0; i < tubes.dimension && i < std::size(kComponents); ++i) {
    run["components"].push_back(kComponents[i]);
    run["units"].push_back(per_gain ? kUnitsPerGain[i] : kUnits[i]);
  }
  // What the integrator was given: the start box (at the pieces' t_start_s) and the torque.
  run["initial_box"] = box_json(tubes.initial);
  run["input_torque_nm"] = interval_json(tubes.torque_nm);
  run["pieces"] = Json::array();
  for (const pipeline::TubePiece& piece : tubes.pieces) {
    Json steps = Json::array();
    for (const pipeline::StepBoxes& s : piece.steps) {
      steps.push_back(Json{{"t", Json::array({s.t0_s, s.t1_s})},
                           {"over", box_json(s.over)},
                           {"end", box_json(s.end)}});
    }
    Json inherits = nullptr;
    if (piece.inherits_from) {
      inherits = Json{{"piece", *piece.inherits_from}, {"steps", piece.inherited_steps}};
    }
    run["pieces"].push_back(Json{{"start_t_s", piece.t_start_s},
                                 {"start_box", box_json(piece.start)},
                                 {"inherits", inherits},
                                 {"steps", steps}});
  }
  return run;
}

Json bound_json(const identification::ChannelErrorBound& b) {
  return Json{{"absolute", b.absolute}, {"relative", b.relative}};
}

const char* inner_test_name(identification::InnerTest kind) {
  switch (kind) {
    case identification::InnerTest::witness:
      return "witness";
    case identification::InnerTest::intermediate_value:
      return "intermediate_value";
    case identification::InnerTest::for_all_data:
      return "for_all_data";
    case identification::InnerTest::none:
      return "none";
  }
  return "none";
}

// The two rows every sample constrains p with (docs/model.md, eq. 5), as text: the file names the
// set it paves.
Json constraint_json() {
  return Json{
      {"row1",
       "mu1 ddq1 + mu2 (s^2 ddq1 + 2 s c dq1 dq2) + mu3 (c ddq2 - s dq2^2) + fv1 dq1 = tau"},
      {"row2", "-mu2 s c dq1^2 + mu3 c ddq1 + mu4 ddq2 + mug s + fv2 dq2 = 0"},
      {"where", "s = sin q2, c = cos q2"},
      {"set",
       "p in prior such that, for all samples but at most q, some (q2, dq1, dq2, ddq1, ddq2, "
       "tau) in its data boxes satisfies row1 and row2"}};
}

}  // namespace

Json tubes_json(const pipeline::Simulation& s) {
  Json j;
  j["truth"] = parameters_json(s.truth);
  j["truth_source"] = measurement_source_text(s.source);
  j["initial_uncertainty"] = Json{{"q1_rad", s.uncertainty.q1_rad},
                                  {"dq1_rad_s", s.uncertainty.dq1_rad_s},
                                  {"q2_rad", s.uncertainty.q2_rad},
                                  {"dq2_rad_s", s.uncertainty.dq2_rad_s}};
  j["runs"] = Json::array();
  for (std::size_t i = 0; i < s.results.size() && i < s.tubes.size(); ++i) {
    j["runs"].push_back(tube_json(s.results[i], s.tubes[i]));
  }
  return j;
}

Json paving_json(const pipeline::Guaranteed& g) {
  const identification::GuaranteedResult& r = g.result;
  const interval::SubPaving& p = r.paving;
  Json j;
  j["parameters"] = Json::array();
  j["unknowns"] = Json::array();
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    j["parameters"].push_back(model::kParameterNames[k]);
    if (r.unknown[k]) j["unknowns"].push_back(model::kParameterNames[k]);
  }
  j["prior"] = box_json(p.prior);
  j["constraint"] = constraint_json();
  j["q"] = r.q;
  j["empty"] = r.empty;
  j["truncated"] = p.truncated;
  j["inner_test"] = inner_test_name(r.inner);
  // The carried components' values the inner boxes are proven (and listed) with.
  j["inner_carried"] = Json::object();
  for (std::size_t k = 0; k < model::kParameterCount && k < r.inner_carried.size(); ++k) {
    if (!r.unknown[k]) {
      j["inner_carried"][model::kParameterNames[k]] = interval_json(r.inner_carried[k]);
    }
  }
  j["outer_count"] = p.outer_count;
  j["outer_kept"] = p.outer.size();
  j["contraction_count"] = p.contraction_count;
  j["contractions_kept"] = p.contractions.size();
  j["boxes"] = Json::array();
  const auto boxes = [&](const std::vector<interval::Box>& list, const char* verdict) {
    for (const interval::Box& b : list) {
      j["boxes"].push_back(Json{{"verdict", verdict}, {"box", box_json(b)}});
    }
  };
  // A box called inner is listed as its proof holds: every point of it is in the set.
  boxes(r.proven_inner_boxes(), "inner");
  boxes(p.boundary, "boundary");
  boxes(p.outer, "outer");
  j["contractions"] = Json::array();
  for (const interval::Contraction& c : p.contractions) {
    j["contractions"].push_back(Json{{"before", box_json(c.before)}, {"after", box_json(c.after)}});
  }
  j["data_error_bounds"] =
      Json{{"q2", bound_json(g.bounds.q2)},     {"dq1", bound_json(g.bounds.dq1)},
           {"dq2", bound_json(g.bounds.dq2)},   {"ddq1", bound_json(g.bounds.ddq1)},
           {"ddq2", bound_json(g.bounds.ddq2)}, {"tau", bound_json(g.bounds.tau)}};
  j["samples"] = Json::array();
  for (const identification::IntervalSample& s : g.samples) {
    j["samples"].push_back(Json{{"experiment", s.experiment},
                                {"index", s.index},
                                {"t_s", s.t_s},
                                {"q2", interval_json(s.q2)},
                                {"dq1", interval_json(s.dq1)},
                                {"dq2", interval_json(s.dq2)},
                                {"ddq1", interval_json(s.ddq1)},
                                {"ddq2", interval_json(s.ddq2)},
                                {"tau", interval_json(s.tau)}});
  }
  return j;
}

}  // namespace furuta::report
