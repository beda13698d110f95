// The LSMI stage: preprocessing and LSMI over the fitted recordings, the check on the held-out
// one, and the estimate against the physical region.
#include <set>

#include "furuta/identification/physical.hpp"
#include "stages.hpp"

namespace furuta::pipeline {

std::vector<Warning> identification_warnings(const identification::Identification& id) {
  std::set<std::string> lsmi;
  for (std::size_t i = 0; i < id.per_experiment.size() && i < id.processed.size(); ++i) {
    for (const auto& w : id.per_experiment[i].warnings)
      lsmi.insert(id.processed[i].name + ": " + w);
  }
  for (const auto& w : id.combined.warnings) lsmi.insert("all experiments: " + w);
  std::vector<Warning> out;
  for (const auto& w : id.warnings) {
    if (lsmi.contains(w)) {
      out.push_back({Warning::Stage::lsmi, Warning::Kind::suspect, w});
    } else if (id.lsmi_ran() || w != "LSMI did not run: " + id.lsmi_skipped) {
      out.push_back({Warning::Stage::data, Warning::Kind::data, w});
    } else {
      out.push_back({Warning::Stage::lsmi, Warning::Kind::skipped, w});
    }
  }
  return out;
}

namespace {

// The share of the recordings' samples whose input a controller computed (balance sessions),
// weighted by each recording's samples; `from` and `count` pick the recordings.
double closed_loop_share(const Batch& batch, std::size_t from, std::size_t count) {
  double closed = 0, all = 0;
  for (std::size_t i = from; i < from + count && i < batch.fit.size(); ++i) {
    const double n = static_cast<double>(batch.fit[i].experiment.t_s.size());
    all += n;
    if (batch.fit[i].closed_loop) closed += n;
  }
  return all > 0 ? closed / all : 0.0;
}

// LSMI is unconstrained (the paper's reference), so its answer may be no rig at all: the combined
// estimate is checked, and each experiment's when that one is clearly outside while the combined
// is not (one recording of several made differently). Returns the combined estimate's check.
// Mostly closed-loop recordings (balance sessions) bias least squares: the check then names that,
// not a recording mistake.
identification::PhysicalCheck check_physical(identification::Identification& id, const Batch& batch,
                                             std::vector<Warning>& warnings) {
  using namespace identification;
  const RecordingSource source =
      batch.kind == InputKind::csv_recordings ? RecordingSource::csv : RecordingSource::session_log;
  const auto add = [&](const std::string& text) {
    if (text.empty()) return;
    id.warnings.push_back(text);
    warnings.push_back({Warning::Stage::physical, Warning::Kind::suspect, text});
  };
  if (!id.lsmi_ran()) return {};
  // The recordings as read: a cause the magnitudes cannot tell apart is named from what they show.
  RecordingEvidence evidence = recording_evidence(id.raw);
  evidence.closed_loop_share = closed_loop_share(batch, 0, batch.fit.size());
  const PhysicalCheck combined = identification::check_physical(
      id.combined.estimate, id.combined.std_dev, id.nominal, &evidence);
  add(physical_warning(combined, source, "the LSMI estimate of all experiments"));
  if (combined.consistent() && combined.cause == LikelyCause::none) {
    for (std::size_t i = 0; i < id.per_experiment.size() && i < id.processed.size(); ++i) {
      const LsmiResult& r = id.per_experiment[i];
      RecordingEvidence own =
          i < id.raw.size() ? recording_evidence({id.raw[i]}) : RecordingEvidence{};
      own.closed_loop_share = closed_loop_share(batch, i, 1);
      const PhysicalCheck one =
          identification::check_physical(r.estimate, r.std_dev, id.nominal, &own);
      if (one.clear())
        add(physical_warning(one, source, "the LSMI estimate of " + id.processed[i].name));
    }
  }
  return combined;
}

}  // namespace

namespace detail {

void run_lsmi(const Batch& batch, const Settings& settings, Run& run, Progress* progress) {
  std::vector<identification::RawExperiment> experiments;
  for (const Recording& r : batch.fit) {
    experiments.push_back(r.experiment);
    if (r.session) run.sessions.push_back(*r.session);
  }
  std::optional<identification::RawExperiment> held_out;
  if (batch.held_out) {
    held_out = batch.held_out->experiment;
    if (batch.held_out->session) run.sessions.push_back(*batch.held_out->session);
  }
  // The refinement needs no derivatives: with the CAD values to start from, a recording too short
  // for LSMI's filters is fitted by it alone.
  identification::IdentifyOptions identify = settings.identify;
  identify.lsmi_optional = settings.output_error.run && batch.nominal.has_value();
  run.identification = identification::identify(experiments, held_out, identify, batch.rig.motor,
                                                batch.voltage_motor);
  if (batch.nominal) run.identification.nominal = *batch.nominal;
  if (batch.truth) run.identification.truth = *batch.truth;
  for (const auto& path : batch.files) {
    const std::filesystem::path listed =
        batch.files_listed_in.empty() ? path : batch.files_listed_in / path.filename();
    run.inputs.push_back({listed.string(), identification::sha256_file(path.string())});
  }
  run.warnings = identification_warnings(run.identification);
  run.physical = check_physical(run.identification, batch, run.warnings);
  if (progress != nullptr) progress->lsmi_done(run.identification);
}

}  // namespace detail
}  // namespace furuta::pipeline
