#pragma once
// The SVG figures: self-contained documents, written to files and inlined in report.html.

#include <string>
#include <vector>

#include "furuta/identification/guaranteed.hpp"
#include "furuta/identification/identify.hpp"
#include "furuta/identification/output_error.hpp"
#include "furuta/pipeline/pipeline.hpp"
#include "furuta/validated/scenarios.hpp"

namespace furuta::report {

// Fig. 2/3: an experiment's angles, velocities, accelerations and torque, with uncertainty bands:
// the data error bounds SIVIA uses when given (every channel), else the pendulum encoder's
// quantisation.
std::string svg_signals(const identification::RawExperiment& raw,
                        const identification::JointSeries& processed, double angle_resolution_rad,
                        const identification::DataErrorBounds* bounds = nullptr);
// Fig. 5: measured vs LSMI-predicted torque on the held-out session.
std::string svg_torque_validation(const identification::ValidationResult& validation);

// The held-out recording's measured q1 and q2 against free runs (no re-shooting) with the LSMI
// and the output-error parameters, each run's angle RMSE in the panel titles.
std::string svg_free_runs(const std::string& name, const identification::FreeRun* lsmi,
                          const identification::FreeRun& refined);

// Fig. 4: the paving projected on two parameters (default fv1, fv2): inner, boundary and outer
// boxes in three colours, axes with units, the truth or a reference point if given.
std::string svg_paving(const identification::GuaranteedResult& result, int x_parameter = 5,
                       int y_parameter = 6, const std::vector<double>* reference = nullptr);

// The windowed set (identify --guaranteed) as the paper's Fig. 4 is SIVIA's: one row per scaled
// parameter, its search box, the set and the estimate in the estimate's sd (the truth when
// known), and on the right the set's half-width and the step that narrowed it (deciding_step).
std::string svg_windowed_set(const pipeline::WindowedGuaranteed& windowed);
// The step (1-based: the k-th windows of every recording) after which parameter k's set was
// within 1 % of its final width; 0 when the windows did not narrow it.
std::size_t deciding_step(const pipeline::WindowedGuaranteed& windowed, std::size_t k);

// Fig. 6: the q2 tube (filled step boxes) with the measured q2 over it (samples outside the
// paper's test in red), axes in s and deg, the scenario as the title, the coverage rates in the
// legend.
std::string svg_scenario(const validated::ScenarioResult& result);

}  // namespace furuta::report
