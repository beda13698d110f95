// pipeline::simulate: the paper's scenarios measured on the simulated rig, a tube per parameter
// set.
#include <utility>

#include "furuta/pipeline/pipeline.hpp"

namespace furuta::pipeline {

namespace {

// The steps' boxes of every piece (the integrator's Taylor data are left behind: they are large
// and nobody outside the integrator reads them).
TubeSet step_boxes(const validated::ScenarioTubes& tubes) {
  TubeSet set;
  for (const validated::Tube& tube : tubes.pieces) {
    set.dimension = tube.dimension;
    std::vector<StepBoxes>& steps = set.pieces.emplace_back();
    steps.reserve(tube.steps.size());
    for (const validated::TubeStep& s : tube.steps) steps.push_back({s.t0, s.t1, s.over, s.end});
  }
  return set;
}

}  // namespace

Simulation simulate(const std::vector<validated::Scenario>& scenarios,
                    const std::vector<validated::ParameterSet>& sets,
                    const model::Parameters<double>& truth, const MeasurementSource& source,
                    std::size_t pieces, Progress* progress) {
  Simulation out;
  out.source = source;
  out.truth = truth;
  out.integrator = validated::scenario_integrator_options();
  out.pieces = pieces;
  for (const validated::Scenario& scenario : scenarios) {
    const validated::ScenarioMeasurement measurement =
        validated::measure_scenario(scenario, truth, out.measurement);
    for (const validated::ParameterSet& set : sets) {
      if (progress != nullptr) progress->scenario(scenario, set.name);
      const validated::ScenarioTubes tubes = validated::run_scenario_tubes(
          scenario, set.parameters, out.uncertainty, out.integrator,
          validated::scenario_split_options(pieces, scenario.duration_s));
      out.results.push_back(
          validated::evaluate_tubes(scenario, set, out.uncertainty, measurement, tubes));
      out.tubes.push_back(step_boxes(tubes));
    }
  }
  if (progress != nullptr) progress->scenarios_done();
  return out;
}

}  // namespace furuta::pipeline
