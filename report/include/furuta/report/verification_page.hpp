#pragma once
// The balance controller's verification as a person and a program read it: what was proven
// (certified to the horizon, or which bound the enclosure reached and when), under which
// assumptions (the parameter box, the drive, the lag, the readings, the start box, the limits),
// the independent sampled check, and one figure of the tube over time. The numbers are
// verification::verify_balance_split's (and largest_start's, check_inside's); nothing is
// recomputed.
//
//   report::VerificationReportInput input{version, controller, source, loop, start, limits,
//                                         options, split, certificate, region, sampled};
//   report::write_verification_report(dir, input);  // report.html, verification.json, .svg

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "furuta/report/json.hpp"
#include "furuta/verification/balance_certificate.hpp"
#include "furuta/verification/sampled_loop.hpp"

namespace furuta::report {

struct VerificationSampled {  // the independent sampled check
  std::size_t trajectories = 0;
  std::size_t checks = 0;
  std::size_t outside = 0;
  std::optional<double> first_outside_s;
  std::vector<verification::LoopTrajectory> drawn;  // a few, drawn inside the tube
  // Against the largest certified start's tube (the start box not certified, a region found):
  // the figure then draws that tube.
  bool on_start_region = false;
};

struct VerificationReportInput {
  std::string software_version;
  std::string controller;         // the controller file as given
  std::string parameters_source;  // e.g. "output-error estimate of results.json +- 3 sd", or
                                  // "box file x.toml"
  verification::LoopModel loop;
  verification::LoopStart start;
  verification::LoopLimits limits;
  verification::VerifyOptions options;
  verification::SplitOptions split;
  verification::BalanceCertificate certificate;
  std::optional<verification::StartRegion> start_region;  // when asked for
  VerificationSampled sampled;
};

// verification.json (docs/outputs.md, "The verification report"): the verdict, the failure, the
// assumptions, every step's boxes on a line of its own, the start region, the sampled check.
// Angles in rad, rates in rad/s, times in s; an interval [lo, hi], a bound that is not finite
// null (unbounded), an empty interval null in place of [lo, hi].
Json verification_json(const VerificationReportInput& input);

// The tube over time: panels sharing t [s], each a <g class="panel" id="...">: "upright" (q2 - pi
// in degrees: each step's `over` box as a shaded band, the drawn trajectories' q2 - pi as
// lines), "arm" (q1 in degrees, the same), "duty" (each step's `duty`, sent at its end, as a
// band, the drawn trajectories' duties at their samples as lines). The stated bound
// (limits.upright_rad in degrees) dashed at +-bound in the upright panel and, when not certified,
// a vertical line at failure->t_s in every panel. Long runs are thinned: a band is one polygon
// hulling the steps within a few pixels, a trajectory keeps each pixel column's first, lowest,
// highest and last value.
std::string svg_verification(const VerificationReportInput& input);

// report.html: what was proven (certified to T, or not: the failure in words, which bound, when,
// the enclosure against the limit, with units), the assumptions (the parameter box per parameter,
// the drive's constants, the lag in ms, the ramp, the reading age in ms, the counts, the start
// box and the estimate error in deg and deg/s, the limits), the pieces and the seconds, the start
// region when given, the sampled check's counts ("N trajectories, M checks, K outside"), then the
// figure.
std::string render_verification_html(const VerificationReportInput& input);

// report.html, verification.json and verification.svg into `dir` (created). std::runtime_error
// when a file cannot be written.
void write_verification_report(const std::filesystem::path& dir,
                               const VerificationReportInput& input);

}  // namespace furuta::report
