#pragma once
// Diagnosis of a recording mistake by fitting it: the output-error fit repeated on the data
// corrected for one candidate mistake at a time (an angle's sign, scale or zero, the input's sign
// or scale), each judged by how well the model then describes the data and whether its estimate
// can be a rig. The candidate the data support is named with the correction's value, so that a
// reader knows which setting to change and to what.

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "furuta/identification/output_error.hpp"
#include "furuta/identification/physical.hpp"
#include "furuta/model/model.hpp"

namespace furuta::identification {

// What a recording can have wrong. Each is a correction of the recorded data by `value`:
// a scale or sign is recorded = value x true (so value -1 is a flipped sign, 0.25 an encoder read
// with four times its counts per revolution); a zero is recorded = true + value (value pi: the
// logger's zero is upright); zero and sign together is recorded = value - true.
enum class Mistake {
  none,                    // the data as recorded
  arm_scale,               // q1's scale or sign (counts per revolution, a gear, arm_angle_scale)
  pendulum_scale,          // q2's scale or sign
  pendulum_zero,           // q2 counted from upright
  pendulum_zero_and_sign,  // from upright and the other way
  angle_unit,              // both angles by one factor (degrees read as radians: 180/pi)
  input_scale,             // the input's scale or sign (a gain, a unit, input_scale)
};

struct MistakeFit {
  Mistake mistake = Mistake::none;
  double value = 1.0;
  bool converged = false;
  double residual_sigma = 0;
  model::Parameters<double> estimate{}, std_dev{};
  PhysicalCheck physical;
  // The largest factor by which mu1, mu2, mu3, mu4 or mug lies off CAD's; nothing without CAD.
  std::optional<double> off_cad;
  // Converged, the model describes the data (residual sigma within the misfit bound), the estimate
  // physical and its magnitudes a rig's (each of mu1 .. mug within kCadFactor of CAD's, when given;
  // the pendulum's small-swing frequency sqrt(mug / mu4) within 1 to 40 rad/s).
  bool plausible = false;
};

// An estimate whose inertias lie further than this factor from CAD's is no fit of that rig: a
// counts-per-revolution mistake of x2, the smallest there is, moves mu1 .. mug by 2, and CAD's own
// values of a rig are within some tens of percent.
inline constexpr double kCadFactor = 1.75;

struct Diagnosis {
  MistakeFit as_recorded;
  std::vector<MistakeFit> candidates;  // every correction tried, the best fit first
  // The correction the data support: plausible, and either the recorded fit is not, or it
  // describes the data at least twice as well. Where two corrections fit alike (an input's scale
  // is nearly the parameters' own scale), the one nearer CAD's magnitudes.
  std::optional<MistakeFit> named;
};

// Whether a fit needs the diagnosis: not converged, a misfit, not physical, or magnitudes no rig's.
bool needs_diagnosis(const MistakeFit& fit);

// The recorded fit as a MistakeFit (Mistake::none), judged like the candidates.
MistakeFit judge_fit(const OutputErrorResult& fit, const OutputErrorOptions& options,
                     const std::optional<model::Parameters<double>>& cad);

// Refits `experiments` once per candidate correction (15 fits, one more with CAD; the best scale
// refined to its fitted value with up to three more), each from CAD's values when given, else from
// the magnitudes of the recorded fit's estimate, and followed for at most 30 iterations. Signs are
// tried first, then zeros, then scales; when the recorded fit is no rig's answer the tries stop at
// the first correction that is one and fits at least as well. Without
// CAD the arm's scale is not tried (it changes the parameters, not the fit) and the input's is
// told only where it moves the friction.
// `start_for`, when given, is a start for a correction's fit without CAD (LSMI on the corrected
// data: preprocessing.hpp's data, corrected_raw).
using CorrectedStart =
    std::function<std::optional<model::Parameters<double>>(Mistake mistake, double value)>;
Diagnosis diagnose_recording(const std::vector<OeExperiment>& experiments,
                             const OutputErrorResult& as_recorded, const model::MotorData& motor,
                             const OutputErrorOptions& options,
                             const std::optional<model::Parameters<double>>& cad,
                             const CorrectedStart& start_for = {});

// The experiments with `mistake` undone (value as in Mistake).
std::vector<OeExperiment> corrected(const std::vector<OeExperiment>& experiments, Mistake mistake,
                                    double value);
// The same for LSMI's data (the uniform series; `recorded` is left as it is).
RawExperiment corrected_raw(const RawExperiment& experiment, Mistake mistake, double value);

const char* mistake_name(Mistake mistake);

// One sentence: the named correction with its value, the residual sigmas, and the setting to
// change (with the counts per revolution it gives where `counts_per_rev` says the angle was in
// counts; 0: not); or that the recording as it is fits best; or that no single mistake explains
// the fit. Opens with kDiagnosisPrefix.
std::string diagnosis_text(const Diagnosis& diagnosis, RecordingSource source,
                           std::array<double, 2> counts_per_rev);
inline constexpr const char* kDiagnosisPrefix = "diagnosis: ";

}  // namespace furuta::identification
