#pragma once
// Physical consistency of an estimate (docs/model.md, "Physical region"): which conditions it
// violates, by how many standard deviations, and the recording mistake whose pattern of signs and
// magnitudes it shows (docs/csv-import.md, "When a fit is not physical"). LSMI is left
// unconstrained (the paper's reference); this only tells a reader when its answer cannot be a rig.

#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "furuta/identification/preprocessing.hpp"
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
  too_short,               // a recording shorter than kShortRecordingS
  spike,                   // a few samples jump faster than any joint can move
  // Not a mistake: the input came from a controller acting on the measured angles, so it is
  // correlated with their noise and least squares is biased (any sign pattern may follow).
  closed_loop,
  unknown,  // a clear violation no check above found a cause for
};

// What the recordings themselves show, so that a cause the parameters' magnitudes cannot tell
// apart is named only when a check on the data found it.
struct RecordingEvidence {
  double shortest_s = std::numeric_limits<double>::infinity();  // the shortest recording
  // Steps between consecutive samples of either joint faster than kFastestJointRadS, and all
  // steps: a few are spikes, many a unit that is not radians.
  std::size_t fast_steps = 0, steps = 0;
  // The arm's largest |q1 - q1 at the start| over the samples no fast step leads into.
  double largest_arm_travel_rad = 0;
  // The share of the samples whose input a controller computed from the angles (balance
  // sessions); recording_evidence cannot tell, its caller sets it from where the samples came.
  double closed_loop_share = 0;

  bool short_recording() const;
  bool spikes() const;
  bool angles_not_radians() const;
  // Most samples are in closed loop: a sign pattern is then the loop's bias, not a mistake.
  bool closed_loop() const;
};
RecordingEvidence recording_evidence(const std::vector<RawExperiment>& experiments);

// Shorter than this, an estimate no rig has is put down to the recording's length: LSMI's
// filters drop about 0.6 s at each end (39 samples of 16 ms with the configuration's 31-tap
// differentiator), so under 3 s less than half of it is left for the regressor's rows. (The
// output-error refinement needs no derivatives and fits shorter ones.)
inline constexpr double kShortRecordingS = 3.0;
// No joint of a rig check_physical accepts turns faster: its fastest pendulum (40 rad/s small-
// swing frequency) falling from upright passes the bottom at twice that; the arm, geared and held
// to under a turn, moves slower.
inline constexpr double kFastestJointRadS = 80.0;
// Fast steps are spikes while they are at most this share of the steps (isolated samples); more
// is the whole signal in another unit.
inline constexpr double kSpikeShare = 0.01;
// The arm of a Furuta rig is cabled to its motor and never turns a whole turn from where the
// session started (this rig's [safety] arm_limit_deg is 150): farther, its angles are degrees or
// counts read as radians.
inline constexpr double kLargestArmTravelRad = 6.283185307179586;

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
// `evidence` (the recordings'): a cause the magnitudes point at is named only when the data show
// it (too short, spikes, angles not in radians); without evidence, or when none shows, "unknown".
// When the evidence says closed loop, the cause is closed_loop (and what the data themselves show),
// never a recording mistake read from the signs.
PhysicalCheck check_physical(const model::Parameters<double>& estimate,
                             const std::optional<model::Parameters<double>>& std_dev = {},
                             const std::optional<model::Parameters<double>>& nominal = {},
                             const RecordingEvidence* evidence = nullptr);

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
