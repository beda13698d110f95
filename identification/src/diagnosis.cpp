#include "furuta/identification/diagnosis.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace furuta::identification {

namespace {

constexpr double kPi = std::numbers::pi;

// The scales the pendulum's angle is read with by mistake: counts per revolution off by a power of
// two (an encoder's x1/x2/x4 decoding), and the sign. The arm's scale is no such search: the model
// is exactly invariant under q1 -> q1 / s with mu1, mu2 -> s mu1, s mu2 and mu4, mug, fv2 -> mu4 /
// s, ...; the residuals cannot tell it, only CAD's magnitudes.
constexpr double kPendulumScales[] = {-1.0, 0.25, 0.5, 2.0, 4.0};
// The input's scale moves every parameter by one factor but not the duty's back-EMF (or the
// voltage's), which the arm's friction then has to take, below its bound 0 when the input reads
// low: so the residuals tell a large scale, CAD's magnitudes its value. The scales tried; the
// named one is then moved to where the inertias meet CAD's.
constexpr double kInputScales[] = {0.2, 0.5, 2.0, 5.0};
// A candidate that is the answer converges from CAD's values in a few tens of iterations; the
// others need not be followed to the end.
constexpr int kCandidateIterations = 30;
// A named correction must describe the data this much better than the recording as it is.
constexpr double kBetterBy = 2.0;
// Two corrections whose residual sigmas lie within this factor fit alike.
constexpr double kAlike = 1.1;
// The fitted value of a scale: the best candidate refitted at value * and / this, and the
// parabola through the three residual sigmas in log(value).
constexpr double kProbe = 1.03;

// |mu1 mu4|^(1/2) against CAD's, the measure of the inertias' magnitude check_physical uses.
std::optional<double> inertia_ratio(const model::Parameters<double>& p,
                                    const std::optional<model::Parameters<double>>& cad) {
  if (!cad || !(cad->mu1 * cad->mu4 > 0)) return std::nullopt;
  return std::sqrt(std::abs(p.mu1 * p.mu4) / (cad->mu1 * cad->mu4));
}

// The largest factor by which mu1, mu2, mu3, mu4 or mug lies off CAD's (>= 1); nothing without CAD.
std::optional<double> furthest_from_cad(const model::Parameters<double>& p,
                                        const std::optional<model::Parameters<double>>& cad) {
  if (!cad) return std::nullopt;
  double worst = 1.0;
  for (std::size_t k = 0; k < 5; ++k) {
    if (!((*cad)[k] != 0) || !(p[k] != 0)) return std::nullopt;
    const double r = std::abs(p[k] / (*cad)[k]);
    worst = std::max({worst, r, 1.0 / r});
  }
  return worst;
}

MistakeFit fit_with(const std::vector<OeExperiment>& experiments, Mistake mistake, double value,
                    const model::Parameters<double>& start, const model::MotorData& motor,
                    const OutputErrorOptions& options,
                    const std::optional<model::Parameters<double>>& cad) {
  OutputErrorResult fit;
  OutputErrorOptions candidate = options;
  candidate.max_iterations = std::min(options.max_iterations, kCandidateIterations);
  try {
    fit = refine_output_error(corrected(experiments, mistake, value), start, motor, candidate);
  } catch (const std::invalid_argument&) {
    MistakeFit failed;
    failed.mistake = mistake;
    failed.value = value;
    return failed;
  }
  MistakeFit out = judge_fit(fit, options, cad);
  out.mistake = mistake;
  out.value = value;
  return out;
}

// The input and arm scales that would bring an estimate's mu1 and mu4 to CAD's: mu1 goes as
// input / arm, mu4 as input x arm.
struct CadFactors {
  double input = 1, arm = 1;
};
std::optional<CadFactors> cad_factors(const model::Parameters<double>& p,
                                      const std::optional<model::Parameters<double>>& cad) {
  if (!cad || !(cad->mu1 > 0) || !(cad->mu4 > 0) || !(p.mu1 > 0) || !(p.mu4 > 0)) {
    return std::nullopt;
  }
  const double r1 = p.mu1 / cad->mu1, r4 = p.mu4 / cad->mu4;
  return CadFactors{std::sqrt(r1 * r4), std::sqrt(r4 / r1)};
}

// Nearer CAD's magnitudes; without CAD, neither.
bool nearer_cad(const MistakeFit& a, const MistakeFit& b) {
  return a.off_cad && b.off_cad && *a.off_cad < *b.off_cad;
}

}  // namespace

const char* mistake_name(Mistake mistake) {
  switch (mistake) {
    case Mistake::none:
      return "none";
    case Mistake::arm_scale:
      return "arm_scale";
    case Mistake::pendulum_scale:
      return "pendulum_scale";
    case Mistake::pendulum_zero:
      return "pendulum_zero";
    case Mistake::pendulum_zero_and_sign:
      return "pendulum_zero_and_sign";
    case Mistake::angle_unit:
      return "angle_unit";
    case Mistake::input_scale:
      return "input_scale";
  }
  return "unknown";
}

namespace {

// A mistake undone, as what it does to each quantity: an arm angle, a pendulum angle, an input
// value; the angles' noise scales with their angle.
struct Correction {
  std::function<double(double)> arm = [](double q) { return q; };
  std::function<double(double)> pendulum = [](double q) { return q; };
  double input_divisor = 1;
  std::array<double, 2> noise_divisor = {1, 1};
};

Correction correction(Mistake mistake, double value) {
  Correction c;
  const auto scaled = [value](double q) { return q / value; };
  switch (mistake) {
    case Mistake::none:
      break;
    case Mistake::arm_scale:
      c.arm = scaled;
      c.noise_divisor[0] = std::abs(value);
      break;
    case Mistake::pendulum_scale:
      c.pendulum = scaled;
      c.noise_divisor[1] = std::abs(value);
      break;
    case Mistake::angle_unit:
      c.arm = c.pendulum = scaled;
      c.noise_divisor = {std::abs(value), std::abs(value)};
      break;
    case Mistake::pendulum_zero:
      c.pendulum = [value](double q) { return q - value; };
      break;
    case Mistake::pendulum_zero_and_sign:
      c.pendulum = [value](double q) { return value - q; };
      break;
    case Mistake::input_scale:
      c.input_divisor = value;
      break;
  }
  return c;
}

void map_each(const std::function<double(double)>& f, std::vector<double>& values) {
  for (double& v : values) v = f(v);
}

}  // namespace

std::vector<OeExperiment> corrected(const std::vector<OeExperiment>& experiments, Mistake mistake,
                                    double value) {
  const Correction c = correction(mistake, value);
  std::vector<OeExperiment> out = experiments;
  for (OeExperiment& e : out) {
    for (OeObservation& o : e.observations)
      o.angle_rad = (o.joint == 0 ? c.arm : c.pendulum)(o.angle_rad);
    for (std::size_t j = 0; j < 2; ++j) e.angle_sigma_rad[j] /= c.noise_divisor[j];
    for (double& u : e.input) u /= c.input_divisor;
    for (double& s : e.input_slope) s /= c.input_divisor;
  }
  return out;
}

RawExperiment corrected_raw(const RawExperiment& experiment, Mistake mistake, double value) {
  const Correction c = correction(mistake, value);
  RawExperiment e = experiment;
  map_each(c.arm, e.q1);
  map_each(c.pendulum, e.q2);
  for (double& u : e.input) u /= c.input_divisor;
  map_each(c.arm, e.recorded.q1_rad);
  map_each(c.pendulum, e.recorded.q2_rad);
  for (double& u : e.recorded.input) u /= c.input_divisor;
  if (e.recorded.input_at_start) *e.recorded.input_at_start /= c.input_divisor;
  return e;
}

MistakeFit judge_fit(const OutputErrorResult& fit, const OutputErrorOptions& options,
                     const std::optional<model::Parameters<double>>& cad) {
  MistakeFit out;
  out.converged = fit.converged;
  out.residual_sigma = fit.residual_sigma;
  out.estimate = fit.estimate;
  out.std_dev = fit.std_dev;
  out.physical = check_physical(fit.estimate, fit.std_dev, cad);
  // The magnitudes are judged here whatever check_physical found: a refinement keeps its
  // estimate inside the physical region, so only they can tell a scale mistake.
  out.physical.inertia_ratio_to_cad = inertia_ratio(fit.estimate, cad);
  out.off_cad = furthest_from_cad(fit.estimate, cad);
  const bool rig_magnitudes = !out.off_cad || *out.off_cad < kCadFactor;
  const auto frequency = out.physical.pendulum_frequency_rad_s;
  const bool a_pendulum = !frequency || (*frequency > 1.0 && *frequency < 40.0);
  out.plausible = fit.converged && std::isfinite(fit.residual_sigma) &&
                  fit.residual_sigma <= options.misfit_sigma && out.physical.consistent() &&
                  rig_magnitudes && a_pendulum;
  return out;
}

bool needs_diagnosis(const MistakeFit& fit) {
  return !fit.plausible;
}

Diagnosis diagnose_recording(const std::vector<OeExperiment>& experiments,
                             const OutputErrorResult& as_recorded, const model::MotorData& motor,
                             const OutputErrorOptions& options,
                             const std::optional<model::Parameters<double>>& cad,
                             const CorrectedStart& start_for) {
  Diagnosis d;
  d.as_recorded = judge_fit(as_recorded, options, cad);
  model::Parameters<double> start = cad.value_or(as_recorded.estimate);
  for (double& v : start) v = std::abs(v);

  // The corrections in the order recordings get them wrong: signs, then zeros, then scales.
  std::vector<std::pair<Mistake, double>> tries = {
      {Mistake::pendulum_scale, -1.0},        {Mistake::arm_scale, -1.0},
      {Mistake::input_scale, -1.0},           {Mistake::pendulum_zero, kPi},
      {Mistake::pendulum_zero_and_sign, kPi}, {Mistake::angle_unit, 180.0 / kPi},
      {Mistake::angle_unit, kPi / 180.0}};
  for (const double s : kPendulumScales) {
    if (s != -1.0) tries.emplace_back(Mistake::pendulum_scale, s);
  }
  for (const double s : kInputScales) tries.emplace_back(Mistake::input_scale, s);
  // The arm's scale moves mu1 and mu4 apart (above), which only CAD's magnitudes tell: the factor
  // that brings the recorded fit's mu1 and mu4 to CAD's (mu1 goes as input / arm, mu4 as input x
  // arm).
  if (const auto arm = cad_factors(as_recorded.estimate, cad)) {
    // CAD's own error moves the factor by some tens of percent; a counts mistake is a power of two.
    const double two = std::exp2(std::round(std::log2(arm->arm)));
    const double value = std::abs(std::log(arm->arm / two)) < std::log(1.25) ? two : arm->arm;
    if (std::abs(std::log(value)) > std::log(1.5)) tries.emplace_back(Mistake::arm_scale, value);
  }
  for (const auto& [mistake, value] : tries) {
    model::Parameters<double> from = start;
    if (!cad && start_for) {
      if (const auto lsmi = start_for(mistake, value)) {
        from = *lsmi;
        for (double& v : from) v = std::abs(v);
      }
    }
    d.candidates.push_back(fit_with(experiments, mistake, value, from, motor, options, cad));
    // A recording that is no rig's answer, and a correction that is one and fits at least as
    // well: the rest need not be tried (a diagnosis asked of a good fit tries them all).
    const MistakeFit& c = d.candidates.back();
    if (!d.as_recorded.plausible && c.plausible &&
        c.residual_sigma <= kAlike * d.as_recorded.residual_sigma) {
      break;
    }
  }

  const auto better = [](const MistakeFit& a, const MistakeFit& b) {
    if (a.plausible != b.plausible) return a.plausible;
    if (a.converged != b.converged) return a.converged;
    return a.residual_sigma < b.residual_sigma;
  };
  std::stable_sort(d.candidates.begin(), d.candidates.end(), better);
  if (d.candidates.empty() || !d.candidates.front().plausible) return d;

  // Among the plausible fits alike to the best, the one nearest CAD's magnitudes.
  MistakeFit best = d.candidates.front();
  for (const MistakeFit& c : d.candidates) {
    if (!c.plausible || c.residual_sigma > kAlike * d.candidates.front().residual_sigma) break;
    if (nearer_cad(c, best)) best = c;
  }
  const bool supported =
      !d.as_recorded.plausible || best.residual_sigma * kBetterBy < d.as_recorded.residual_sigma;
  if (!supported) return d;

  // The input's value from CAD's magnitudes: the residuals hardly tell it once the friction is
  // free.
  if (best.mistake == Mistake::input_scale && best.value != -1.0) {
    if (const auto f = cad_factors(best.estimate, cad)) {
      const MistakeFit moved = fit_with(experiments, best.mistake, best.value * f->input,
                                        best.estimate, motor, options, cad);
      if (moved.plausible && moved.residual_sigma <= kAlike * best.residual_sigma) best = moved;
    }
  }
  // A scale's fitted value: the parabola through the residual sigmas at value / kProbe, value and
  // value * kProbe, in log(value).
  const bool scale = best.mistake == Mistake::arm_scale ||
                     best.mistake == Mistake::pendulum_scale || best.mistake == Mistake::angle_unit;
  if (scale && std::abs(best.value) != 1.0) {
    const MistakeFit lo = fit_with(experiments, best.mistake, best.value / kProbe, best.estimate,
                                   motor, options, cad);
    const MistakeFit hi = fit_with(experiments, best.mistake, best.value * kProbe, best.estimate,
                                   motor, options, cad);
    const double a = lo.residual_sigma, b = best.residual_sigma, c = hi.residual_sigma;
    const double curvature = a - 2 * b + c;
    if (lo.converged && hi.converged && curvature > 0) {
      const double step = 0.5 * (a - c) / curvature;  // in units of log(kProbe), from the middle
      if (std::abs(step) <= 1.0) {
        const double value = best.value * std::pow(kProbe, step);
        const MistakeFit refined =
            fit_with(experiments, best.mistake, value, best.estimate, motor, options, cad);
        if (refined.plausible && refined.residual_sigma <= best.residual_sigma) best = refined;
      }
    }
  }
  d.named = best;
  return d;
}

}  // namespace furuta::identification

namespace furuta::identification {

namespace {

std::string g3(double v) {
  std::ostringstream s;
  s << std::setprecision(3) << v;
  return s.str();
}

// Counts per revolution: whole numbers.
std::string whole(double counts) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(0) << counts;
  return s.str();
}

// "the pendulum's angles recorded -1 x true (its sign flipped)", what a correction says.
std::string what_was_wrong(const MistakeFit& m) {
  const std::string v = g3(m.value);
  const auto scaled = [&](const std::string& what) {
    if (m.value == -1.0) return what + " counted the other way (its sign flipped)";
    return what + " recorded " + v + " times the true angle" +
           (m.value < 0 ? " and counted the other way" : "");
  };
  switch (m.mistake) {
    case Mistake::arm_scale:
      return scaled("the arm's angle");
    case Mistake::pendulum_scale:
      return scaled("the pendulum's angle");
    case Mistake::angle_unit:
      return std::abs(m.value * kPi / 180.0 - 1.0) < 0.01 ? "both angles in degrees read as radians"
             : std::abs(m.value * 180.0 / kPi - 1.0) < 0.01
                 ? "both angles in radians read as degrees"
                 : "both angles recorded " + v + " times the true angle";
    case Mistake::pendulum_zero:
      return "the pendulum's angle counted from upright, not from hanging down";
    case Mistake::pendulum_zero_and_sign:
      return "the pendulum's angle counted from upright and the other way";
    case Mistake::input_scale:
      return m.value == -1.0 ? "the input's sign flipped (positive input turns the arm negative)"
                             : "the input recorded " + v + " times what the rig received";
    case Mistake::none:
      break;
  }
  return "nothing";
}

// The setting that makes the correction, in the recording's own terms.
std::string what_to_change(const MistakeFit& m, RecordingSource source,
                           std::array<double, 2> counts_per_rev) {
  const bool csv = source == RecordingSource::csv;
  const auto angle = [&](int joint) {
    const char* name = joint == 0 ? "arm" : "pendulum";
    const double counts = counts_per_rev[static_cast<std::size_t>(joint)];
    std::string out;
    if (std::abs(m.value) != 1.0 && counts > 0) {
      out = std::string("its counts per revolution are likely ") +
            whole(counts * std::abs(m.value)) + ", not " + whole(counts) + " (" +
            (csv ? std::string(name) + "_counts_per_rev in the import spec"
                 : std::string("[encoders.") + name + "] counts_per_rev") +
            ")";
      if (m.value < 0) out += ", and its sign the other way";
      return out;
    }
    const std::string setting = csv ? std::string(name) + "_angle_scale in the import spec"
                                    : std::string("[encoders.") + name + "] sign" +
                                          (std::abs(m.value) != 1.0 ? " and counts_per_rev" : "");
    return "multiply it by " + g3(1.0 / m.value) + " (" + setting + ")";
  };
  switch (m.mistake) {
    case Mistake::arm_scale:
      return angle(0);
    case Mistake::pendulum_scale:
      return angle(1);
    case Mistake::angle_unit:
      return csv ? "check angle_unit in the import spec" : "check both encoders' counts_per_rev";
    case Mistake::pendulum_zero:
    case Mistake::pendulum_zero_and_sign:
      return csv ? std::string("pendulum_zero = \"up\" in the import spec") +
                       (m.mistake == Mistake::pendulum_zero_and_sign
                            ? " and pendulum_angle_scale = -1"
                            : "")
                 : std::string("[encoders.pendulum] zero_offset_rad") +
                       (m.mistake == Mistake::pendulum_zero_and_sign ? " and sign" : "");
    case Mistake::input_scale:
      return m.value == -1.0
                 ? (csv ? "input_scale = -1 in the import spec (or the arm's sign, if "
                          "the arm is the one reversed)"
                        : "check the motor's wiring or [encoders.arm] sign")
                 : std::string("divide the input by ") + g3(m.value) +
                       (csv ? " (input_scale in the import spec, or the motor's data)"
                            : " (the motor's data in [motor]: its magnitudes are CAD's only "
                              "then)");
    case Mistake::none:
      break;
  }
  return "";
}

}  // namespace

std::string diagnosis_text(const Diagnosis& d, RecordingSource source,
                           std::array<double, 2> counts_per_rev) {
  std::ostringstream s;
  s << kDiagnosisPrefix;
  const std::string recorded =
      "residual sigma " + g3(d.as_recorded.residual_sigma) + " as recorded";
  if (d.named) {
    const MistakeFit& m = *d.named;
    const bool from_cad = m.mistake == Mistake::arm_scale && m.value != -1.0;
    s << "the data fit best with " << what_was_wrong(m)
      << (from_cad ? " (a factor the residuals cannot tell: from CAD's magnitudes)" : "")
      << " (the fit with it undone: residual "
      << "sigma " << g3(m.residual_sigma) << " against " << g3(d.as_recorded.residual_sigma)
      << " as recorded";
    if (m.physical.inertia_ratio_to_cad) {
      s << ", inertias " << g3(*m.physical.inertia_ratio_to_cad) << " times CAD's";
    }
    s << "): " << what_to_change(m, source, counts_per_rev);
    return s.str();
  }
  const MistakeFit* next = d.candidates.empty() ? nullptr : &d.candidates.front();
  if (d.as_recorded.plausible) {
    s << "signs, zero and units as recorded fit best (" << recorded;
    if (next != nullptr) {
      s << "; the best correction, " << what_was_wrong(*next) << ", " << g3(next->residual_sigma)
        << (next->plausible ? "" : " and no rig's answer");
    }
    s << ")";
    return s.str();
  }
  s << "no single recording mistake explains the fit (" << recorded;
  if (next != nullptr) {
    s << "; the best correction, " << what_was_wrong(*next) << ", " << g3(next->residual_sigma)
      << (next->plausible ? "" : " and no rig's answer either");
  }
  s << "): the model may lack dynamics this rig has, its time stamps may be wrong, or two "
       "mistakes at once";
  return s.str();
}

}  // namespace furuta::identification
