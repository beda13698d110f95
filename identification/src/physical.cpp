// The physical region of docs/model.md and the sign patterns of recording mistakes. The patterns
// follow from the regressor (docs/model.md, eq. 5) and were confirmed on transformed simulated
// recordings (docs/csv-import.md, "When a fit is not physical"):
//   q2 -> -q2        row 1's mu3 column and row 2 (all but its mu3 term) change sign: mu3 -> -mu3
//   q2 -> q2 + pi    s, c -> -s, -c: mu3 -> -mu3 and mug -> -mug
//   q2 -> pi - q2    both at once: mug -> -mug, mu3 unchanged
//   tau -> -tau      every row-1 term, and so (row 2 fixing the ratios) p -> -p
//   q1 -> -q1        the mirror image of tau -> -tau with q2 -> -q2: p -> -p but mu3
//   t -> k t         inertias by k^2, frictions by k, mug unchanged
//   tau -> g tau     p -> g p
// An input given as a duty or voltage also carries the back-EMF (eq. 4), which is not flipped with
// the input: fv1 then moves by twice the back-EMF damping, in the same direction as the others.
#include "furuta/identification/physical.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <utility>

namespace furuta::identification {

namespace {

// A pendulum of 1 m has sqrt(g/l) ~ 3 rad/s with l its equivalent length (mu4 / (m l)); one of
// 1 cm, ~31. The band is wide on purpose: this is to catch factors of 57 or 1000, not to judge.
constexpr double kLowestPendulumRadS = 1.0;
constexpr double kHighestPendulumRadS = 40.0;
// The pendulum's inertia about its pivot against the arm's: within a factor 1000 on any rig made
// to swing one with the other (about 1 on the paper's and on Quanser's).
constexpr double kInertiaRatio = 1e3;
// Inertias this many times off CAD are no rig's tolerance (CAD and Table I agree within 15 %).
constexpr double kCadFactor = 10.0;

PhysicalViolation grade(PhysicalCondition c, double margin, double margin_sd, bool strict) {
  PhysicalViolation v{c, margin, margin_sd, 0, false};
  if (margin_sd > 0) {
    v.sigmas = -margin / margin_sd;
  } else {
    v.sigmas = margin < 0 || (strict && margin == 0) ? std::numeric_limits<double>::infinity() : 0;
  }
  v.within_noise = v.sigmas < kNoiseSigmas;
  return v;
}

// The parameter is below zero by more than the noise.
bool clearly_negative(double value, double sd) {
  return value < 0 && -value >= kNoiseSigmas * sd;
}
bool clearly_positive(double value, double sd) {
  return value > 0 && value >= kNoiseSigmas * sd;
}

std::string number(double v, int digits = 3) {
  std::ostringstream s;
  s << std::setprecision(digits) << v;
  return s.str();
}

// The setting that holds each mistake, in the recording's own terms.
std::string where_to_look(LikelyCause cause, RecordingSource source) {
  const bool csv = source == RecordingSource::csv;
  switch (cause) {
    case LikelyCause::pendulum_sign:
      return csv ? "Check the import spec's pendulum_angle_scale (-1 flips the column)"
                 : "Check [encoders.pendulum] sign (the sessions must then be recorded again)";
    case LikelyCause::pendulum_zero:
      return csv ? "Check the import spec's pendulum_zero (up | down)"
                 : "Check [encoders.pendulum] zero_offset_deg (keep 0) and that the pendulum hung "
                   "still when the session started";
    case LikelyCause::pendulum_zero_and_sign:
      return csv ? "Check the import spec's pendulum_zero (up | down) and pendulum_angle_scale"
                 : "Check [encoders.pendulum] zero_offset_deg and sign";
    case LikelyCause::arm_sign:
      return csv ? "Check the import spec's arm_angle_scale (-1 flips the column)"
                 : "Check [encoders.arm] sign";
    case LikelyCause::input_sign:
      return csv ? "Check the input's sign: the import spec's input_scale (or the motor's wiring)"
                 : "Check the motor's wiring: a positive duty must turn q1 positive "
                   "([encoders.arm] "
                   "sign)";
    case LikelyCause::angle_unit:
      return csv ? "Check the import spec's angle_unit (and counts_per_rev)"
                 : "Check [encoders.*] counts_per_rev and [motor]'s gear ratios";
    case LikelyCause::time_unit:
      return csv ? "Check the import spec's time_unit" : "Check the log's time stamps";
    case LikelyCause::input_gain:
      return csv ? "Check the import spec's input_scale, input_kind and [motor]"
                 : "Check [motor] (eq. 4's motor data) and the supply";
    case LikelyCause::too_short:
      return csv ? "Record longer" : "Run longer sessions (--duration, [excitation] duration_s)";
    case LikelyCause::spike:
      return csv ? "Check the CSV's angle columns for readings that jump and come back"
                 : "Check the encoders' cables and the log (furuta log info)";
    case LikelyCause::closed_loop:
      return "The output-error fit, which simulates the model with the applied duty, is the "
             "estimate to use (Table I's output-error column; `furuta controller design "
             "--parameters output-error`); or identify open-loop sessions (an excitation "
             "--profile)";
    case LikelyCause::none:
    case LikelyCause::unknown:
      break;
  }
  return "Check the angles' signs and zeros, their units and the input's sign and scale";
}

std::string cause_text(LikelyCause cause) {
  switch (cause) {
    case LikelyCause::pendulum_sign:
      return "the pendulum angle counted the other way (q2 -> -q2 makes mu3 < 0 and nothing else)";
    case LikelyCause::pendulum_zero:
      return "the pendulum's zero upright instead of hanging (q2 off by pi makes mug < 0 and "
             "mu3 < 0)";
    case LikelyCause::pendulum_zero_and_sign:
      return "the pendulum's zero upright and its angle counted the other way (mug < 0, mu3 > 0)";
    case LikelyCause::arm_sign:
      return "the arm angle counted the other way (q1 -> -q1 makes every parameter < 0 but mu3)";
    case LikelyCause::input_sign:
      return "the input's sign (a negative input gain makes every parameter < 0)";
    case LikelyCause::angle_unit:
      return "the angles' unit (degrees read as radians shrinks the inertias about 57 times and "
             "garbles the rest)";
    case LikelyCause::time_unit:
      return "the time unit (inertias scale with its square, frictions with it)";
    case LikelyCause::input_gain:
      return "the input's gain (every parameter off by one factor)";
    case LikelyCause::too_short:
      return "a recording shorter than " + number(kShortRecordingS) +
             " s (too few swings to tell the parameters apart)";
    case LikelyCause::spike:
      return "samples that jump faster than " + number(kFastestJointRadS) +
             " rad/s, which no joint can (spikes in the angles)";
    case LikelyCause::closed_loop:
      return "closed-loop data: the duty came from the balance controller acting on the measured "
             "angles, so it is correlated with their noise and least squares on it is biased "
             "(its signs point at no recording mistake)";
    case LikelyCause::none:
    case LikelyCause::unknown:
      break;
  }
  return "unknown (no sign pattern fits, and no check on the recordings found spikes, angles "
         "beyond radians or too short a recording)";
}

// What a condition bounds.
const char* quantity(PhysicalCondition c) {
  switch (c) {
    case PhysicalCondition::mu1_positive:
      return model::kParameterNames[0];
    case PhysicalCondition::mu2_positive:
      return model::kParameterNames[1];
    case PhysicalCondition::mu3_positive:
      return model::kParameterNames[2];
    case PhysicalCondition::mu4_positive:
      return model::kParameterNames[3];
    case PhysicalCondition::mug_positive:
      return model::kParameterNames[4];
    case PhysicalCondition::mass_matrix_positive_definite:
      return "mu1 mu4 - mu3^2";
    case PhysicalCondition::fv1_nonnegative:
      return model::kParameterNames[5];
    case PhysicalCondition::fv2_nonnegative:
      return model::kParameterNames[6];
  }
  return "?";
}

}  // namespace

bool PhysicalCheck::clear() const {
  for (const PhysicalViolation& v : violations) {
    if (!v.within_noise) return true;
  }
  return false;
}

const char* condition_text(PhysicalCondition condition) {
  switch (condition) {
    case PhysicalCondition::mu1_positive:
      return "mu1 > 0";
    case PhysicalCondition::mu2_positive:
      return "mu2 > 0";
    case PhysicalCondition::mu3_positive:
      return "mu3 > 0";
    case PhysicalCondition::mu4_positive:
      return "mu4 > 0";
    case PhysicalCondition::mug_positive:
      return "mug > 0";
    case PhysicalCondition::mass_matrix_positive_definite:
      return "mu1 mu4 > mu3^2";
    case PhysicalCondition::fv1_nonnegative:
      return "fv1 >= 0";
    case PhysicalCondition::fv2_nonnegative:
      return "fv2 >= 0";
  }
  return "?";
}

const char* cause_name(LikelyCause cause) {
  switch (cause) {
    case LikelyCause::none:
      return "none";
    case LikelyCause::pendulum_sign:
      return "pendulum sign";
    case LikelyCause::pendulum_zero:
      return "pendulum zero";
    case LikelyCause::pendulum_zero_and_sign:
      return "pendulum zero and sign";
    case LikelyCause::arm_sign:
      return "arm sign";
    case LikelyCause::input_sign:
      return "input sign";
    case LikelyCause::angle_unit:
      return "angle unit";
    case LikelyCause::time_unit:
      return "time unit";
    case LikelyCause::input_gain:
      return "input gain";
    case LikelyCause::too_short:
      return "too short";
    case LikelyCause::spike:
      return "spike";
    case LikelyCause::closed_loop:
      return "closed loop";
    case LikelyCause::unknown:
      return "unknown";
  }
  return "?";
}

bool RecordingEvidence::short_recording() const {
  return shortest_s < kShortRecordingS;
}

bool RecordingEvidence::spikes() const {
  return fast_steps > 0 &&
         static_cast<double>(fast_steps) <= kSpikeShare * static_cast<double>(steps);
}

bool RecordingEvidence::closed_loop() const {
  return closed_loop_share > 0.5;
}

bool RecordingEvidence::angles_not_radians() const {
  return (fast_steps > 0 && !spikes()) || largest_arm_travel_rad > kLargestArmTravelRad;
}

RecordingEvidence recording_evidence(const std::vector<RawExperiment>& experiments) {
  RecordingEvidence out;
  for (const RawExperiment& e : experiments) {
    if (e.t_s.size() < 2) {
      out.shortest_s = std::min(out.shortest_s, 0.0);
      continue;
    }
    out.shortest_s = std::min(out.shortest_s, e.t_s.back() - e.t_s.front());
    for (std::size_t i = 1; i < e.t_s.size() && i < e.q1.size() && i < e.q2.size(); ++i) {
      const double dt = e.t_s[i] - e.t_s[i - 1];
      if (!(dt > 0)) continue;
      const double fastest = kFastestJointRadS * dt;
      const bool fast = !(std::fabs(e.q1[i] - e.q1[i - 1]) <= fastest) ||
                        !(std::fabs(e.q2[i] - e.q2[i - 1]) <= fastest);
      ++out.steps;
      if (fast) {
        ++out.fast_steps;
        continue;
      }
      out.largest_arm_travel_rad =
          std::max(out.largest_arm_travel_rad, std::fabs(e.q1[i] - e.q1.front()));
    }
  }
  return out;
}

PhysicalCheck check_physical(const model::Parameters<double>& p,
                             const std::optional<model::Parameters<double>>& std_dev,
                             const std::optional<model::Parameters<double>>& nominal,
                             const RecordingEvidence* evidence) {
  const model::Parameters<double> sd = std_dev.value_or(model::Parameters<double>{});
  PhysicalCheck out;
  const auto add = [&](PhysicalCondition c, double margin, double margin_sd, bool strict) {
    if (margin < 0 || (strict && margin == 0)) {
      out.violations.push_back(grade(c, margin, margin_sd, strict));
    }
  };
  add(PhysicalCondition::mu1_positive, p.mu1, sd.mu1, true);
  add(PhysicalCondition::mu2_positive, p.mu2, sd.mu2, true);
  add(PhysicalCondition::mu3_positive, p.mu3, sd.mu3, true);
  add(PhysicalCondition::mu4_positive, p.mu4, sd.mu4, true);
  add(PhysicalCondition::mug_positive, p.mug, sd.mug, true);
  // Only meaningful with both inertias positive (else mu1 > 0 or mu4 > 0 already failed).
  if (p.mu1 > 0 && p.mu4 > 0) {
    const double det = p.mu1 * p.mu4 - p.mu3 * p.mu3;
    const double det_sd = std::hypot(p.mu4 * sd.mu1, p.mu1 * sd.mu4, 2 * p.mu3 * sd.mu3);
    add(PhysicalCondition::mass_matrix_positive_definite, det, det_sd, true);
  }
  add(PhysicalCondition::fv1_nonnegative, p.fv1, sd.fv1, false);
  add(PhysicalCondition::fv2_nonnegative, p.fv2, sd.fv2, false);

  if (nominal && nominal->mu1 > 0 && nominal->mu4 > 0) {
    out.reference = MagnitudeReference::cad;
    out.inertia_ratio_to_cad = std::sqrt(std::fabs(p.mu1 * p.mu4) / (nominal->mu1 * nominal->mu4));
  }
  if (p.mu4 != 0 && p.mug != 0) out.pendulum_frequency_rad_s = std::sqrt(std::fabs(p.mug / p.mu4));
  if (p.mu1 != 0) out.pendulum_to_arm_inertia = std::fabs(p.mu4 / p.mu1);

  // Signs first: each sign mistake gives an exact pattern (see the top of this file).
  const bool arm_inertia_negative = clearly_negative(p.mu1, sd.mu1);
  const bool pendulum_inertia_negative = clearly_negative(p.mu4, sd.mu4);
  const bool mu3_negative = clearly_negative(p.mu3, sd.mu3);
  const bool mu3_positive = clearly_positive(p.mu3, sd.mu3);
  const bool mug_negative = clearly_negative(p.mug, sd.mug);
  if (arm_inertia_negative && pendulum_inertia_negative) {
    if (mu3_negative) {
      out.candidates = {LikelyCause::input_sign};
    } else if (mu3_positive) {
      out.candidates = {LikelyCause::arm_sign};
    } else {
      out.candidates = {LikelyCause::input_sign, LikelyCause::arm_sign};
    }
  } else if (mug_negative && !arm_inertia_negative && !pendulum_inertia_negative) {
    if (mu3_negative) {
      out.candidates = {LikelyCause::pendulum_zero};
    } else if (mu3_positive) {
      out.candidates = {LikelyCause::pendulum_zero_and_sign};
    } else {
      out.candidates = {LikelyCause::pendulum_zero, LikelyCause::pendulum_zero_and_sign};
    }
  } else if (mu3_negative && !arm_inertia_negative && !pendulum_inertia_negative) {
    out.candidates = {LikelyCause::pendulum_sign};
  }

  // Then magnitudes, when the signs name nothing: units and gains keep the signs. A gain scales
  // every parameter alike, a time factor k the inertias by k^2 and mug not at all: each a pattern
  // of the parameters. What scales nothing alike (an angle unit: sin and cos of 57 times the
  // angle are noise; a spike; too few swings) is named only when the recordings show it.
  const auto from_the_data = [&]() -> std::vector<LikelyCause> {
    if (evidence == nullptr) return {};
    if (evidence->spikes()) return {LikelyCause::spike};
    if (evidence->angles_not_radians()) return {LikelyCause::angle_unit};
    if (evidence->short_recording()) return {LikelyCause::too_short};
    return {};
  };
  if (out.candidates.empty()) {
    const auto off = [](double ratio) { return ratio > kCadFactor || ratio < 1 / kCadFactor; };
    const auto alike = [](double a, double b) { return a < 3 * b && b < 3 * a; };
    if (out.inertia_ratio_to_cad) {
      const double r1 = std::fabs(p.mu1 / nominal->mu1), r4 = std::fabs(p.mu4 / nominal->mu4);
      const double rg = nominal->mug > 0 ? std::fabs(p.mug / nominal->mug) : 1.0;
      if (off(r1) || off(r4) || off(rg)) {
        out.candidates = from_the_data();
        if (!out.candidates.empty()) {
          // The data's own finding comes first.
        } else if (alike(r1, r4) && alike(r4, rg)) {
          out.candidates = {LikelyCause::input_gain};
        } else if (alike(r1, r4) && alike(rg, 1.0)) {
          out.candidates = {LikelyCause::time_unit};
        } else {
          out.candidates = {LikelyCause::unknown};
        }
      }
    }
    const bool implausible_frequency =
        out.pendulum_frequency_rad_s && (*out.pendulum_frequency_rad_s < kLowestPendulumRadS ||
                                         *out.pendulum_frequency_rad_s > kHighestPendulumRadS);
    const bool implausible_inertias =
        out.pendulum_to_arm_inertia && (*out.pendulum_to_arm_inertia < 1 / kInertiaRatio ||
                                        *out.pendulum_to_arm_inertia > kInertiaRatio);
    if (out.candidates.empty() && (implausible_frequency || implausible_inertias)) {
      out.candidates = from_the_data();
      if (out.candidates.empty()) out.candidates = {LikelyCause::unknown};
    }
    if (out.candidates.empty() && out.clear()) {
      out.candidates = from_the_data();
      if (out.candidates.empty()) out.candidates = {LikelyCause::unknown};
    }
  }
  // Spikes and too short a recording garble any pattern of signs: when the data show either, it
  // is named first, before the pattern the garbled estimate happens to show.
  if (!out.candidates.empty() && evidence != nullptr) {
    for (const auto& [shown, cause] :
         {std::pair{evidence->short_recording(), LikelyCause::too_short},
          std::pair{evidence->spikes(), LikelyCause::spike}}) {
      if (shown &&
          std::find(out.candidates.begin(), out.candidates.end(), cause) == out.candidates.end()) {
        out.candidates.insert(out.candidates.begin(), cause);
      }
    }
    std::erase(out.candidates, LikelyCause::unknown);
    if (out.candidates.empty()) out.candidates = {LikelyCause::unknown};
  }
  // On closed-loop data the patterns of signs and magnitudes are the loop's bias, not a recording
  // mistake: the controller's duty follows the measured angles, noise included. Only what the
  // recordings themselves show stays beside it.
  if (!out.candidates.empty() && evidence != nullptr && evidence->closed_loop()) {
    std::vector<LikelyCause> kept = {LikelyCause::closed_loop};
    for (const auto& [shown, cause] :
         {std::pair{evidence->short_recording(), LikelyCause::too_short},
          std::pair{evidence->spikes(), LikelyCause::spike},
          std::pair{evidence->angles_not_radians(), LikelyCause::angle_unit}}) {
      if (shown) kept.push_back(cause);
    }
    out.candidates = std::move(kept);
  }
  out.cause = out.candidates.empty() ? LikelyCause::none : out.candidates.front();
  return out;
}

std::string physical_warning(const PhysicalCheck& check, RecordingSource source,
                             const std::string& what) {
  if (check.consistent() && check.cause == LikelyCause::none) return "";
  std::ostringstream w;
  w << kPhysicalWarningPrefix << what;
  if (check.consistent()) {
    w << " lies inside the physical region, but its magnitudes are no rig's";
  } else {
    w << " violates";
    for (std::size_t i = 0; i < check.violations.size(); ++i) {
      const PhysicalViolation& v = check.violations[i];
      w << (i == 0 ? " " : "; ") << condition_text(v.condition) << " (";
      w << quantity(v.condition) << " = " << number(v.margin);
      if (v.margin_sd > 0) {
        w << ", " << number(v.sigmas, 2) << " sd past the boundary"
          << (v.within_noise ? ": within noise" : "");
      }
      w << ")";
    }
  }
  if (check.inertia_ratio_to_cad) {
    w << "; inertias " << number(*check.inertia_ratio_to_cad, 2) << " times CAD's";
  } else if (check.pendulum_frequency_rad_s && check.pendulum_to_arm_inertia) {
    w << "; no CAD values, so magnitudes judged from the parameters' own ratios: sqrt(mug/mu4) = "
      << number(*check.pendulum_frequency_rad_s, 2)
      << " rad/s, mu4/mu1 = " << number(*check.pendulum_to_arm_inertia, 2);
  }
  if (check.cause == LikelyCause::none) {
    w << ". Every violation is within noise of the boundary: the data do not exclude a physical "
         "rig, but a longer or richer excitation would settle it";
    return w.str();
  }
  w << ". Likely cause: " << cause_text(check.cause);
  for (std::size_t i = 1; i < check.candidates.size(); ++i) {
    w << (i == 1 ? "; or " : ", or ") << cause_text(check.candidates[i]);
  }
  w << ". " << where_to_look(check.cause, source);
  for (std::size_t i = 1; i < check.candidates.size(); ++i) {
    w << ". " << where_to_look(check.candidates[i], source);
  }
  // The refits undo recording mistakes; the loop's bias is none.
  if (check.cause != LikelyCause::closed_loop) {
    w << " (`furuta identify --diagnose` refits each candidate mistake: "
      << (source == RecordingSource::csv ? "docs/csv-import.md" : "docs/model.md") << ")";
  }
  return w.str();
}

}  // namespace furuta::identification
