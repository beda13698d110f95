// The simulation stage: the paper's scenarios as guaranteed tubes with every parameter set the
// stages before it found.
#include "stages.hpp"

namespace furuta::pipeline {

namespace {

// The paper's scenarios with the fitted parameters: SIVIA's outer hull when it found a set (the
// carried mu's as their Table II intervals), the LSMI estimate as points. The measurements come
// from the simulated rig: the truth when the sessions were simulated, else the configuration's
// simulated-rig parameters.
Simulation scenarios(const SimulationSettings& settings, const Run& run, const Batch& batch,
                     Progress* progress) {
  std::vector<validated::ParameterSet> sets;
  if (run.sivia && !run.sivia->result.empty) {
    const interval::Box h = run.sivia->result.paving.outer_hull();
    sets.push_back({kSiviaSetName, model::Parameters<interval::Interval>{h[0], h[1], h[2], h[3],
                                                                         h[4], h[5], h[6]}});
  }
  if (run.identification.lsmi_ran()) {
    sets.push_back(validated::point_parameters("LSMI", run.identification.combined.estimate));
  }
  // A fit that did not converge is not an answer to simulate.
  if (run.output_error && run.output_error->result.converged) {
    sets.push_back(
        validated::point_parameters(kOutputErrorSetName, run.output_error->result.estimate));
  }
  if (run.windowed && run.windowed->result.verdict != identification::WindowedSetVerdict::empty) {
    // The scaled set as the rig's parameters per unit of gain under the torque per unit of gain:
    // the drive's tolerance then stays in one variable instead of widening all seven.
    const identification::DriveData& drive = run.windowed->inputs.drive;
    validated::ParameterSet set;
    set.name = kWindowedSetName;
    set.parameters = identification::rig_parameters_per_gain(run.windowed->result.set, drive);
    set.torque_scale = interval::Interval(1.0) / drive.gain_nm();
    set.taylor_models = true;
    sets.push_back(std::move(set));
  }
  MeasurementSource source;
  source.kind = batch.truth ? MeasurementSource::Kind::sessions_truth
                            : MeasurementSource::Kind::configured_rig;
  return simulate(settings.scenarios, sets, batch.truth.value_or(batch.rig.simulation.parameters),
                  source, settings.pieces, progress, settings.taylor_model_pieces);
}

}  // namespace

namespace detail {

void run_simulation(const Batch& batch, const Settings& settings, Run& run, Progress* progress) {
  run.simulation = scenarios(settings.simulation, run, batch, progress);
  if (run.sivia && run.sivia->result.empty) {
    run.warnings.push_back({Warning::Stage::simulation, Warning::Kind::skipped,
                            "SIVIA's set is empty: no SIVIA tubes"});
  }
}

}  // namespace detail
}  // namespace furuta::pipeline
