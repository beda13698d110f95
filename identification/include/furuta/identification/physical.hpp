#pragma once
// Physical consistency of an estimate (docs/model.md, "Physical region"): which conditions it
// violates, by how many standard deviations, and the recording mistake whose pattern of signs and
// magnitudes it shows (docs/csv-import.md, "When a fit is not physical"). LSMI is left
// unconstrained (the paper's reference); this only tells a reader when its answer cannot be a rig.

#include <optional>
#include <string>
#include <vector>

#include "furuta/model/model.hpp"

namespace furuta::identification {

enum class PhysicalCondition {
  mu1_positive,
  mu2_positive,
  mu3_positive,  // not needed for a defined model, but follows from the sign convention
  mu4_positive,
  mug_positive,
  mass_matrix_positive_definite,  // mu1 mu4 > mu3^2: det M > 0 for every q2
  fv1_nonnegative,
  fv2_nonnegative,
};

struct PhysicalViolation {
  PhysicalCondition condition;
  // The condition's margin: the parameter itself, or mu1 mu4 - mu3^2 (kg^2 m^4). Negative (or 0 for
  // a strict condition) when violated.
  double margin = 0;
  // First-order standard deviation of the margin from the parameters' standard deviations, taken
  // as independent (LSMI reports no covariances here); 0 when none were given.
  double margin_sd = 0;
  // How far past the boundary: -margin / margin_sd (infinite when margin_sd is 0).
  double sigmas = 0;
  // Within kNoiseSigmas of the boundary: the data do not exclude the physical side.
  bool within_noise = false;
};

inline constexpr double kNoiseSigmas = 3.0;

// The recording mistakes a fit's signs and magnitudes can point at.
enum class LikelyCause {
  none,                    // consistent, or only within noise of the boundary
  pendulum_sign,           // q2 counted the other way: mu3 < 0, the rest unchanged
  pendulum_zero,           // q2 = 0 upright (off by pi): mug < 0 and mu3 < 0
  pendulum_zero_and_sign,  // off by pi and counted the other way: mug < 0, mu3 > 0
  arm_sign,                // q1 the other way: every parameter < 0 but mu3
  input_sign,              // the input's sign (or a negative gain): every parameter < 0
  angle_unit,              // degrees read as radians (or the reverse)
  time_unit,               // inertias off by the square of a factor, frictions by the factor
  input_gain,              // every parameter off by one factor: the input's scale
  unknown,                 // a clear violation none of the patterns above explains
};

// What the diagnosis compared magnitudes with.
enum class MagnitudeReference {
  cad,       // the configuration's [nominal] values
  internal,  // no CAD values: signs and the parameters' own ratios only
};

struct PhysicalCheck {
  std::vector<PhysicalViolation> violations;  // empty: inside the physical region
  LikelyCause cause = LikelyCause::none;
  // When the pattern fits more than one mistake (cause is the first).
  std::vector<LikelyCause> candidates;
  MagnitudeReference reference = MagnitudeReference::internal;
  // Evidence from magnitudes: |mu1 mu4|^(1/2) against CAD's (cad), and sqrt(|mug / mu4|), the
  // pendulum's small-swing angular frequency in rad/s (about 3 for a pendulum of 1 m, 31 for one of
  // 1 cm; outside 1 to 40 it is no pendulum); absent when the parameters do not give it.
  std::optional<double> inertia_ratio_to_cad;
  std::optional<double> pendulum_frequency_rad_s;
  // |mu4 / mu1|: within 1e-3 to 1e3 on any rig made to swing the pendulum with the arm.
  std::optional<double> pendulum_to_arm_inertia;

  bool consistent() const { return violations.empty(); }
  // Some violation lies beyond the noise.
  bool clear() const;
};

// The estimate against the physical region; `std_dev` (LSMI's) grades each violation, `nominal`
// (CAD) lets magnitudes speak. A consistent estimate is checked for magnitudes only when a clear
// pattern would otherwise be missed (inertias 30 times off CAD: an angle or time unit).
PhysicalCheck check_physical(const model::Parameters<double>& estimate,
                             const std::optional<model::Parameters<double>>& std_dev = {},
                             const std::optional<model::Parameters<double>>& nominal = {});

// "mu3 > 0", "mu1 mu4 > mu3^2", ...
const char* condition_text(PhysicalCondition condition);
// "pendulum sign", "pendulum zero", ...: for results.json and the tests.
const char* cause_name(LikelyCause cause);

// Where the recordings came from: the setting to check differs.
enum class RecordingSource { session_log, csv };

// The short warning identify's callers add ("not physical: mu3 = -7.8e-4 +- 1e-5 (78 sd below 0)
// ... likely cause: the pendulum's sign ... check [encoders.pendulum] sign"), or "" when the check
// found nothing. `what` names the estimate ("the LSMI estimate of all experiments").
std::string physical_warning(const PhysicalCheck& check, RecordingSource source,
                             const std::string& what);

// The warning's opening words, by which a reader of Identification::warnings tells it apart.
inline constexpr const char* kPhysicalWarningPrefix = "not physical: ";

}  // namespace furuta::identification
