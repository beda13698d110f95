// The SIVIA stage: the guaranteed set of the paper's method, from the combined LSMI estimate and
// the data's bounds ([sivia]).
#include "stages.hpp"

namespace furuta::pipeline {

namespace {

identification::InnerTest inner_test(config::SiviaInnerTest test) {
  using identification::InnerTest;
  switch (test) {
    case config::SiviaInnerTest::witness:
      return InnerTest::witness;
    case config::SiviaInnerTest::intermediate_value:
      return InnerTest::intermediate_value;
    case config::SiviaInnerTest::for_all_data:
      return InnerTest::for_all_data;
    case config::SiviaInnerTest::none:
      break;
  }
  return InnerTest::none;
}

// SIVIA over the fitted sessions: the mu's around the combined LSMI estimate (Table II style), the
// frictions' priors, the data bounds and the paver settings from [sivia].
Guaranteed run_guaranteed(const SiviaSettings& settings, const identification::Identification& id,
                          const identification::IdentifyOptions& identify, Progress* progress) {
  using namespace identification;
  const config::SiviaConfig& cfg = settings.config;
  GuaranteedOptions g;
  g.prior = sivia_prior(cfg, id.combined.estimate);
  g.unknown.fill(false);
  for (const std::string& name : cfg.unknowns) {
    for (std::size_t k = 0; k < model::kParameterCount; ++k) {
      if (name == model::kParameterNames[k]) g.unknown[k] = true;
    }
  }
  g.epsilon = cfg.epsilon;
  g.epsilon_relative = cfg.epsilon_relative;
  g.contract = cfg.contract;
  g.inner = inner_test(cfg.inner_test);
  g.q = cfg.q;
  g.threads = settings.threads;
  if (progress != nullptr) {
    g.progress = [progress](std::size_t tested, std::size_t pending) {
      progress->sivia(tested, pending);
    };
  }
  Guaranteed out;
  out.bounds = data_error_bounds(cfg);
  std::vector<const JointSeries*> series;
  for (const JointSeries& s : id.processed) series.push_back(&s);
  const std::size_t trim = identify.lsmi.trim_samples != 0 ? identify.lsmi.trim_samples
                                                           : edge_samples(identify.preprocess);
  out.samples = interval_samples(series, out.bounds, trim);
  const SampleConstraints constraints(out.samples, g.prior, g.unknown);
  out.result = guaranteed_identification(constraints, g);
  if (progress != nullptr) progress->sivia_done();
  return out;
}

}  // namespace

identification::DataErrorBounds data_error_bounds(const config::SiviaConfig& cfg) {
  const auto bound = [](const std::array<double, 2>& b) {
    return identification::ChannelErrorBound{b[0], b[1]};
  };
  identification::DataErrorBounds bounds;
  bounds.q2 = bound(cfg.q2_bound);
  bounds.dq1 = bound(cfg.dq1_bound);
  bounds.dq2 = bound(cfg.dq2_bound);
  bounds.ddq1 = bound(cfg.ddq1_bound);
  bounds.ddq2 = bound(cfg.ddq2_bound);
  bounds.tau = bound(cfg.tau_bound);
  return bounds;
}

interval::Box sivia_prior(const config::SiviaConfig& sivia, const model::Parameters<double>& lsmi) {
  interval::Box prior = identification::paper_prior(lsmi, sivia.mu_uncertainty_pct, 1.0);
  prior[5] = interval::Interval(sivia.fv1_prior[0], sivia.fv1_prior[1]);
  prior[6] = interval::Interval(sivia.fv2_prior[0], sivia.fv2_prior[1]);
  return prior;
}

bool has_data_error_bounds(const config::SiviaConfig& cfg) {
  for (const auto* b : {&cfg.q2_bound, &cfg.dq1_bound, &cfg.dq2_bound, &cfg.ddq1_bound,
                        &cfg.ddq2_bound, &cfg.tau_bound}) {
    if ((*b)[0] > 0 || (*b)[1] > 0) return true;
  }
  return false;
}

namespace detail {

void run_sivia(const Batch& /*batch*/, const Settings& settings, Run& run, Progress* progress) {
  if (!run.identification.lsmi_ran()) {
    run.warnings.push_back(
        {Warning::Stage::sivia, Warning::Kind::skipped,
         "SIVIA skipped: it starts from LSMI's estimate and bounds the derivatives LSMI's filters "
         "form, and LSMI did not run"});
    return;
  }
  run.sivia = run_guaranteed(settings.sivia, run.identification, settings.identify, progress);
  const identification::GuaranteedResult& r = run.sivia->result;
  if (r.empty) {
    run.warnings.push_back(
        {Warning::Stage::sivia, Warning::Kind::failed, "empty set: " + r.finding});
  }
  if (r.paving.truncated) {
    run.warnings.push_back({Warning::Stage::sivia, Warning::Kind::note, "paving truncated"});
  }
  if (!r.empty && run.output_error && run.output_error->result.converged) {
    run.sivia_excludes_output_error = estimates_outside(
        r.paving.outer_hull(), run.output_error->result.estimate, run.output_error->result.std_dev);
  }
}

}  // namespace detail
}  // namespace furuta::pipeline
