#pragma once
// The stages of pipeline::run, one per method, each in its own file: a stage reads the batch, its
// own settings and what the stages before it put in the Run, and fills its own slot of the Run
// (and its warnings). pipeline::run calls them in this order; report/ has a section for each.

#include "furuta/identification/output_error.hpp"
#include "furuta/pipeline/pipeline.hpp"

namespace furuta::pipeline::detail {

// LSMI over the fitted recordings and the check on the held-out one (Run::identification,
// inputs, sessions, physical), with the data's and LSMI's warnings.
void run_lsmi(const Batch& batch, const Settings& settings, Run& run, Progress* progress);
// The output-error refinement (Run::output_error): settings.output_error.
void run_output_error(const Batch& batch, const Settings& settings, Run& run, Progress* progress);
// SIVIA (Run::sivia, sivia_excludes_output_error): settings.sivia.
void run_sivia(const Batch& batch, const Settings& settings, Run& run, Progress* progress);
// The windowed set inversion (Run::windowed, windowed_excludes_output_error): settings.windowed.
void run_windowed(const Batch& batch, const Settings& settings, Run& run, Progress* progress);
// The paper's scenarios as guaranteed tubes (Run::simulation): settings.simulation.
void run_simulation(const Batch& batch, const Settings& settings, Run& run, Progress* progress);

// A recording's input and angles at their own times, as the refinement and the windows take them:
// a log's own (Recording::oe), else made from its RawExperiment.
identification::OeExperiment oe_experiment(const Recording& r, const Batch& batch);

}  // namespace furuta::pipeline::detail
