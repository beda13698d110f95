// pipeline::simulate: the paper's scenarios measured on the simulated rig, a tube per parameter
// set.
#include <stdexcept>
#include <utility>

#include "furuta/pipeline/pipeline.hpp"

namespace furuta::pipeline {

namespace {

bool same_step(const validated::TubeStep& a, const validated::TubeStep& b) {
  return a.t0 == b.t0 && a.t1 == b.t1 && a.over == b.over && a.end == b.end;
}

// How many leading steps two tubes have in common.
std::size_t common_steps(const validated::Tube& a, const validated::Tube& b) {
  std::size_t n = 0;
  while (n < a.steps.size() && n < b.steps.size() && same_step(a.steps[n], b.steps[n])) ++n;
  return n;
}

// The steps' boxes of every piece (the integrator's Taylor data are left behind: they are large
// and nobody outside the integrator reads them). The pieces of a split run carry copies of the
// steps before their split (validated::integrate_sub_box): each piece keeps only the steps after
// the longest prefix it shares with an earlier piece, and names that piece.
TubeSet step_boxes(const validated::ScenarioTubes& tubes) {
  TubeSet set;
  set.initial = tubes.initial;
  set.torque_nm = tubes.torque_nm;
  for (std::size_t j = 0; j < tubes.pieces.size(); ++j) {
    const validated::Tube& tube = tubes.pieces[j];
    set.dimension = tube.dimension;
    TubePiece& piece = set.pieces.emplace_back();
    piece.t_start_s = tube.t_start;
    piece.start = tube.initial;
    for (std::size_t i = 0; i < j; ++i) {
      const std::size_t shared = common_steps(tubes.pieces[i], tube);
      if (shared > piece.inherited_steps) {
        piece.inherits_from = i;
        piece.inherited_steps = shared;
      }
    }
    piece.steps.reserve(tube.steps.size() - piece.inherited_steps);
    for (std::size_t k = piece.inherited_steps; k < tube.steps.size(); ++k) {
      const validated::TubeStep& s = tube.steps[k];
      piece.steps.push_back({s.t0, s.t1, s.over, s.end});
    }
  }
  return set;
}

}  // namespace

std::vector<StepBoxes> TubeSet::all_steps(std::size_t piece) const {
  const TubePiece& p = pieces.at(piece);
  std::vector<StepBoxes> out;
  if (p.inherits_from && *p.inherits_from >= piece) {
    throw std::logic_error("tube set: a piece inherits from a later one");
  }
  if (p.inherits_from) {
    out = all_steps(*p.inherits_from);
    out.resize(p.inherited_steps);
  }
  out.insert(out.end(), p.steps.begin(), p.steps.end());
  return out;
}

Simulation simulate(const std::vector<validated::Scenario>& scenarios,
                    const std::vector<validated::ParameterSet>& sets,
                    const model::Parameters<double>& truth, const MeasurementSource& source,
                    std::size_t pieces, Progress* progress, std::size_t taylor_model_pieces) {
  Simulation out;
  out.source = source;
  out.truth = truth;
  out.integrator = validated::scenario_integrator_options();
  out.pieces = pieces;
  out.taylor_model_pieces = taylor_model_pieces;
  for (const validated::Scenario& scenario : scenarios) {
    const validated::ScenarioMeasurement measurement =
        validated::measure_scenario(scenario, truth, out.measurement);
    for (const validated::ParameterSet& set : sets) {
      if (progress != nullptr) progress->scenario(scenario, set.name);
      validated::SplitOptions split =
          validated::scenario_split_options(pieces, scenario.duration_s);
      if (set.taylor_models) split.max_pieces = taylor_model_pieces;
      const validated::ScenarioTubes tubes =
          validated::run_scenario_tubes(scenario, set, out.uncertainty, out.integrator, split);
      out.results.push_back(
          validated::evaluate_tubes(scenario, set, out.uncertainty, measurement, tubes));
      out.tubes.push_back(step_boxes(tubes));
    }
  }
  if (progress != nullptr) progress->scenarios_done();
  return out;
}

}  // namespace furuta::pipeline
