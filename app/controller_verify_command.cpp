// `furuta controller verify`: the balancing loop of a controller file proven to keep the pendulum
// upright over a parameter box (verification/, docs/control.md), with the sampled check and the
// report (report/'s verification_page.hpp). Numbers come from the libraries; the text is made here.
#include <cmath>
#include <numbers>
#include <ostream>
#include <sstream>
#include <string>

#include "commands.hpp"
#include "furuta/config/config_error.hpp"
#include "furuta/config/controller_file.hpp"
#include "furuta/config/parameter_box.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/firmware_bridge/encoder_geometry.hpp"
#include "furuta/report/json.hpp"
#include "furuta/report/run_directory.hpp"
#include "furuta/report/verification_page.hpp"
#include "furuta/verification/balance_certificate.hpp"
#include "furuta/verification/sampled_loop.hpp"

namespace furuta::app {

namespace {

using interval::Interval;

constexpr double kDeg = std::numbers::pi / 180.0;
// Trajectories of the sampled check drawn in the report's figure.
constexpr std::size_t kDrawn = 6;

std::string failure_text(const verification::Failure& f) {
  std::ostringstream text;
  const auto deg = [](const Interval& v) {
    std::ostringstream s;
    s << "[" << v.lo() / kDeg << ", " << v.hi() / kDeg << "] deg";
    return s.str();
  };
  switch (f.kind) {
    case verification::FailureKind::pendulum_limit:
      text << "the pendulum may reach " << f.limit / kDeg << " deg from upright (enclosure "
           << deg(f.value) << ")";
      break;
    case verification::FailureKind::arm_limit:
      text << "the arm may reach its limit " << f.limit / kDeg << " deg (enclosure " << deg(f.value)
           << ")";
      break;
    case verification::FailureKind::duty_limit:
      text << "the law's duty may reach its limit " << f.limit << " (enclosure [" << f.value.lo()
           << ", " << f.value.hi() << "]), which the proof assumes it does not";
      break;
    case verification::FailureKind::law_mode:
      text << "a pendulum reading may leave the law's balance region " << f.limit / kDeg
           << " deg (enclosure " << deg(f.value) << ")";
      break;
    case verification::FailureKind::no_enclosure:
      text << "the enclosure of a period's motion did not close: the tube grew faster than the "
              "loop contracts it";
      break;
  }
  text << " at t = " << f.t_s << " s";
  return text.str();
}

}  // namespace

int run_controller_verify_command(const ControllerVerifyOptions& options, std::ostream& out,
                                  std::ostream& err) {
  const auto refuse = [&](const std::string& what) {
    err << "furuta controller verify: " << what << "\n";
    return kExitNotDone;
  };
  if (options.output_dir.empty()) return refuse("-o is empty: give the report's directory");
  config::ControllerFile controller;
  config::RigConfig rig;
  try {
    controller = config::load_controller_file(options.controller);
    rig = config::load_rig_config(options.config_path);
  } catch (const config::ConfigError& e) {
    return refuse(e.what());
  }
  const control::BalanceControllerSpec& law = controller.spec;

  verification::LoopModel loop;
  std::string source;
  if (options.parameters.extension() == ".toml") {
    try {
      const config::ParameterBox box = config::load_parameter_box(options.parameters);
      for (std::size_t k = 0; k < model::kParameterCount; ++k) {
        loop.parameters[k] = Interval(box.lo[k], box.hi[k]);
      }
    } catch (const config::ConfigError& e) {
      return refuse(e.what());
    }
    source = "box file " + options.parameters.string();
  } else {
    report::ResultsFile results;
    try {
      results = report::read_results(options.parameters);
    } catch (const report::ResultsFileError& e) {
      return refuse(options.parameters.string() + ": " + e.what());
    }
    if (!results.output_error || !results.output_error_sd) {
      return refuse(options.parameters.string() +
                    " has no converged output-error estimate with standard deviations "
                    "(output_error.estimate, output_error.std_dev): give a box file instead");
    }
    for (std::size_t k = 0; k < model::kParameterCount; ++k) {
      const double centre = (*results.output_error)[k];
      const double spread = options.sd * (*results.output_error_sd)[k];
      // A friction's box stops at 0: negative friction is not physical, and the model's
      // remainder assumes it.
      const double lo = k >= 5 ? std::max(0.0, centre - spread) : centre - spread;
      if (!(lo > 0 || (k >= 5 && lo >= 0))) {
        return refuse(std::string("the box's ") + model::kParameterNames[k] + " reaches " +
                      std::to_string(lo) + " (estimate - " + std::to_string(options.sd) +
                      " sd): give fewer standard deviations or a box file");
      }
      loop.parameters[k] = Interval(lo, centre + spread);
    }
    std::ostringstream s;
    s << "output-error estimate of " << options.parameters.string() << " +- " << options.sd
      << " sd";
    source = s.str();
  }
  loop.duty_torque_nm = Interval(law.duty_torque_nm);
  loop.back_emf_nm_s = Interval(law.back_emf_nm_s);
  loop.lag_s = options.lag_ms ? Interval((*options.lag_ms)[0] * 1e-3, (*options.lag_ms)[1] * 1e-3)
                              : Interval(law.duty_path.lag_s);
  // The board ramps as the rig's configuration sets it (the law follows the ramp it was designed
  // with).
  loop.ramp_duty_per_s = rig.excitation.board_acceleration_pct_per_s / 100.0;
  loop.reading_age_s =
      options.reading_age_ms ? *options.reading_age_ms * 1e-3 : controller.reading_age_s;
  loop.arm_count_rad = bridge::resolution_rad(rig.arm_encoder);
  loop.pendulum_count_rad = bridge::resolution_rad(rig.pendulum_encoder);

  verification::LoopStart start;
  const double angle = options.start_deg * kDeg;
  const double rate = options.start_deg_s * kDeg;
  const double rate_error = options.estimate_error_deg_s * kDeg;
  start.state = {Interval(0.0), Interval(-angle, angle), Interval(0.0), Interval(-rate, rate)};
  start.estimate_error = {Interval(-loop.arm_count_rad, loop.arm_count_rad),
                          Interval(-loop.pendulum_count_rad, loop.pendulum_count_rad),
                          Interval(-rate_error, rate_error), Interval(-rate_error, rate_error)};
  const verification::LoopLimits limits{
      options.upright_deg ? *options.upright_deg * kDeg : law.region.fall_rad,
      rig.safety.arm_limit_rad};
  verification::VerifyOptions verify;
  verify.horizon_s = options.horizon_s;
  verify.max_symbols = options.max_symbols;
  const verification::SplitOptions split{options.max_pieces, options.handover_s};

  report::VerificationReportInput input;
  input.software_version = daemon::kSoftwareVersion;
  input.controller = options.controller.string();
  input.parameters_source = source;
  input.loop = loop;
  input.start = start;
  input.limits = limits;
  input.options = verify;
  input.split = split;
  try {
    input.certificate = verification::verify_balance_split(law, loop, start, limits, verify, split);
    if (options.start_region && input.certificate.certified()) {
      // The whole start is the region: the bisection would begin by proving it again.
      verification::StartRegion whole;
      whole.scale = 1.0;
      whole.start = start;
      whole.certificate = input.certificate;
      input.start_region = whole;
    } else if (options.start_region) {
      input.start_region =
          verification::largest_start(law, loop, start, limits, verify, split, 1.0, 6);
    }
  } catch (const std::invalid_argument& e) {
    return refuse(e.what());
  }
  // The check runs against a certified tube when there is one: the start box's, else the
  // largest certified start's; none when neither is (a failed run's boxes are one piece's).
  const bool on_region =
      !input.certificate.certified() && input.start_region && input.start_region->scale > 0;
  const bool any_certified = input.certificate.certified() || on_region;
  const verification::SampledCheck sampled =
      verification::sampled_check(law, loop, on_region ? input.start_region->start : start,
                                  on_region ? input.start_region->certificate : input.certificate,
                                  any_certified ? options.sampled : 0, kDrawn, 1);
  input.sampled.on_start_region = on_region;
  input.sampled.trajectories = sampled.trajectories;
  input.sampled.checks = sampled.check.checks;
  input.sampled.outside = sampled.check.outside;
  if (!std::isnan(sampled.check.first_outside_s)) {
    input.sampled.first_outside_s = sampled.check.first_outside_s;
  }
  input.sampled.drawn = sampled.drawn;

  try {
    report::RunDirectory dir(options.output_dir);
    report::write_verification_report(dir.staging(), input);
    dir.commit();
  } catch (const report::OutputDirectoryError& e) {
    return refuse("-o " + options.output_dir.string() + ": " + e.what());
  }

  const verification::BalanceCertificate& c = input.certificate;
  out << "parameters: " << source << "; start: pendulum within " << options.start_deg << " deg and "
      << options.start_deg_s << " deg/s of upright, arm at its centre\n";
  if (c.certified()) {
    out << "certified for " << c.horizon_s << " s: the pendulum within "
        << limits.upright_rad / kDeg << " deg of upright, the arm within " << limits.arm_rad / kDeg
        << " deg, the duty within its limit, for every parameter and start in the boxes ("
        << c.pieces << " piece" << (c.pieces == 1 ? "" : "s");
    if (c.handover_s > 0) out << " to " << c.handover_s << " s, then one run from their states";
    out << ", " << c.seconds << " s)\n";
  } else {
    out << "not certified: " << failure_text(*c.failure) << " (" << c.pieces << " piece"
        << (c.pieces == 1 ? "" : "s") << ", " << c.seconds << " s)\n";
  }
  if (input.start_region) {
    const verification::StartRegion& r = *input.start_region;
    if (r.scale > 0) {
      out << "largest start certified: the pendulum within " << r.scale * options.start_deg
          << " deg and " << r.scale * options.start_deg_s << " deg/s (";
      if (r.verifications == 0) {
        out << "the start itself)\n";
      } else {
        out << r.verifications << " verifications)\n";
      }
    } else {
      out << "no start certified down to " << options.start_deg / 64 << " deg\n";
    }
  }
  if (any_certified) {
    out << "sampled check" << (on_region ? " (the largest certified start)" : "") << ": "
        << input.sampled.trajectories << " trajectories, " << input.sampled.checks << " checks, "
        << input.sampled.outside << " outside the tube\n";
  } else {
    out << "sampled check: none, no tube was certified\n";
  }
  out << "wrote " << (options.output_dir / "report.html").string() << ", verification.json and "
      << "verification.svg\n";
  if (input.sampled.outside > 0) {
    err << "furuta controller verify: a sampled trajectory left the tube at "
        << *input.sampled.first_outside_s << " s: the proof's model does not hold\n";
    return kExitPartOrRefused;
  }
  return c.certified() ? kExitDone : kExitPartOrRefused;
}

}  // namespace furuta::app
