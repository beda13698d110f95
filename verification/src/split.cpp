#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <optional>
#include <utility>
#include <vector>

#include "furuta/verification/balance_certificate.hpp"
#include "loop_run.hpp"

namespace furuta::verification {

namespace {

// How much a relative change of each parameter moves the plant (see SplitOptions): the mass
// matrix's inverse at upright for mu1, mu3, mu4, the arm's damping for fv1; the rest enter
// through small angles or the pendulum's light damping.
std::array<double, model::kParameterCount> influence(const LoopModel& loop) {
  const model::Parameters<double> c =
      loop.parameters.map([](const Interval& v) { return v.mid(); });
  const double det = c.mu1 * c.mu4 - c.mu3 * c.mu3;
  const double damping = loop.back_emf_nm_s.mid() + c.fv1;
  std::array<double, model::kParameterCount> out{};
  out.fill(0.05);
  out[0] = std::fabs(c.mu1 * c.mu4 / det);
  out[2] = std::fabs(2 * c.mu3 * c.mu3 / det);
  out[3] = std::fabs(c.mu1 * c.mu4 / det);
  if (damping > 0) out[5] = std::fabs(c.fv1 / damping);
  return out;
}

// The halves of `p` along its most influential parameter for its relative width.
std::pair<model::Parameters<Interval>, model::Parameters<Interval>> halves(
    const model::Parameters<Interval>& p, const std::array<double, model::kParameterCount>& w) {
  std::size_t widest = 0;
  double largest = -1;
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const double mid = std::fabs(p[k].mid());
    const double size = w[k] * p[k].width() / (mid > 0 ? mid : 1.0);
    if (size > largest) {
      largest = size;
      widest = k;
    }
  }
  const auto [lo, hi] = p[widest].bisect();
  model::Parameters<Interval> a = p;
  model::Parameters<Interval> b = p;
  a[widest] = lo;
  b[widest] = hi;
  return {a, b};
}

// The halves of the start's plant box along the pendulum's angle or rate, whichever is the
// wider for its width in `whole` (nothing when both are points).
std::optional<std::pair<LoopStart, LoopStart>> start_halves(const LoopStart& start,
                                                            const LoopStart& whole) {
  std::optional<std::size_t> widest;
  double largest = 0;
  for (const std::size_t k : {std::size_t{1}, std::size_t{3}}) {
    const double full = whole.state[k].width();
    if (!(full > 0)) continue;
    const double size = start.state[k].width() / full;
    if (size > largest) {
      largest = size;
      widest = k;
    }
  }
  if (!widest) return std::nullopt;
  const auto [lo, hi] = start.state[*widest].bisect();
  LoopStart a = start;
  LoopStart b = start;
  a.state[*widest] = lo;
  b.state[*widest] = hi;
  return std::make_pair(a, b);
}

// The largest of the start's pendulum angle and rate widths for those of `whole`.
double share_of(const LoopStart& start, const LoopStart& whole) {
  double share = 0;
  for (const std::size_t k : {std::size_t{1}, std::size_t{3}}) {
    const double full = whole.state[k].width();
    if (full > 0) share = std::max(share, start.state[k].width() / full);
  }
  return share;
}

// The start is halved before the parameters down to this share of it.
constexpr double kStartShare = 1.0 / 8;

bool is_point(const model::Parameters<Interval>& p) {
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    if (p[k].width() > 0) return false;
  }
  return true;
}

// Handovers tried: at 1, 2 and 3 times SplitOptions::handover_s.
constexpr std::size_t kHandoverTries = 3;

struct Piece {
  model::Parameters<Interval> parameters;
  LoopStart start;
  int splits = 0;
};

// The pieces of the start and parameter boxes, each run to options' horizon, halved where they
// fail (SplitOptions) until certified or max_pieces: the certificate over their hull, and the hull
// of their states at the horizon.
struct PiecesRun {
  BalanceCertificate certificate;
  std::vector<detail::LoopStateBox> at_checkpoints;  // hulls over the pieces
};

PiecesRun run_pieces(const control::BalanceControllerSpec& law, const LoopModel& loop,
                     const LoopStart& start, const LoopLimits& limits, const VerifyOptions& options,
                     const SplitOptions& split, const std::vector<std::size_t>& checkpoints) {
  const std::array<double, model::kParameterCount> weights = influence(loop);
  std::vector<Piece> pending{Piece{loop.parameters, start, 0}};
  std::vector<detail::LoopRun> certified;
  std::optional<BalanceCertificate> failed;
  std::size_t pieces = 1;
  while (!pending.empty()) {
    std::vector<detail::LoopRun> results(pending.size());
    tbb::parallel_for(std::size_t{0}, pending.size(), [&](std::size_t i) {
      LoopModel piece = loop;
      piece.parameters = pending[i].parameters;
      results[i] = detail::run_loop(law, piece, pending[i].start, limits, options, checkpoints);
    });
    std::vector<Piece> next;
    for (std::size_t i = 0; i < pending.size(); ++i) {
      if (results[i].certificate.certified()) {
        certified.push_back(std::move(results[i]));
        continue;
      }
      if (pieces + 1 <= split.max_pieces && !failed) {
        // The start while its pieces are wider than kStartShare of it in angle or rate (the
        // transient binds first; the parameters are carried in sensitivities), then the start
        // and the parameters in turn.
        const Piece& p = pending[i];
        const auto by_start = start_halves(p.start, start);
        const bool parameters_split = !is_point(p.parameters);
        const bool start_wide = by_start && share_of(p.start, start) > kStartShare;
        if (by_start && (start_wide || p.splits % 2 == 0 || !parameters_split)) {
          next.push_back(Piece{p.parameters, by_start->first, p.splits + 1});
          next.push_back(Piece{p.parameters, by_start->second, p.splits + 1});
          ++pieces;
          continue;
        }
        if (parameters_split) {
          const auto [a, b] = halves(p.parameters, weights);
          next.push_back(Piece{a, p.start, p.splits + 1});
          next.push_back(Piece{b, p.start, p.splits + 1});
          ++pieces;
          continue;
        }
      }
      const BalanceCertificate& c = results[i].certificate;
      if (!failed || c.failure->t_s < failed->failure->t_s) failed = c;
    }
    if (failed) break;
    pending = std::move(next);
  }
  PiecesRun run;
  BalanceCertificate& out = run.certificate;
  out.horizon_s = options.horizon_s;
  out.pieces = pieces;
  for (const detail::LoopRun& c : certified) {
    out.largest_symbol_count =
        std::max(out.largest_symbol_count, c.certificate.largest_symbol_count);
  }
  if (failed) {
    out.failure = failed->failure;
    out.steps = std::move(failed->steps);
    out.largest_symbol_count = std::max(out.largest_symbol_count, failed->largest_symbol_count);
    return run;
  }
  out.steps = certified.front().certificate.steps;
  run.at_checkpoints = certified.front().at_checkpoints;
  for (std::size_t c = 1; c < certified.size(); ++c) {
    for (std::size_t k = 0; k < out.steps.size(); ++k) {
      LoopStepBox& s = out.steps[k];
      const LoopStepBox& t = certified[c].certificate.steps[k];
      for (std::size_t i = 0; i < 4; ++i) {
        s.over[i] = hull(s.over[i], t.over[i]);
        s.at_end[i] = hull(s.at_end[i], t.at_end[i]);
        s.estimate[i] = hull(s.estimate[i], t.estimate[i]);
      }
      s.duty = hull(s.duty, t.duty);
    }
    for (std::size_t j = 0; j < run.at_checkpoints.size(); ++j) {
      for (std::size_t i = 0; i < run.at_checkpoints[j].size(); ++i) {
        run.at_checkpoints[j][i] =
            hull(run.at_checkpoints[j][i], certified[c].at_checkpoints[j][i]);
      }
    }
  }
  return run;
}

}  // namespace

BalanceCertificate verify_balance_split(const control::BalanceControllerSpec& law,
                                        const LoopModel& loop, const LoopStart& start,
                                        const LoopLimits& limits, const VerifyOptions& options,
                                        const SplitOptions& split) {
  const auto began = std::chrono::steady_clock::now();
  const auto finish = [&](BalanceCertificate c) {
    c.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
    return c;
  };
  // The pieces to the handover, then one run from the hull of their states (the loop is the same
  // at every sample, so a trajectory in that hull at the handover stays in that run's tube). The
  // pieces record their states at 1, 2 and 3 times the handover; the earliest from which the run
  // is certified is taken.
  const double period = law.period_s;
  const auto handover_periods =
      static_cast<std::size_t>(std::max(1.0, std::round(split.handover_s / period)));
  const auto horizon_periods =
      static_cast<std::size_t>(std::ceil(options.horizon_s / period - 1e-9));
  std::vector<std::size_t> checkpoints;
  for (std::size_t m = 1; m <= kHandoverTries && split.handover_s > 0; ++m) {
    if (m * handover_periods < horizon_periods) checkpoints.push_back(m * handover_periods);
  }
  if (!checkpoints.empty()) {
    VerifyOptions first = options;
    first.horizon_s = static_cast<double>(checkpoints.back()) * period;
    PiecesRun pieces = run_pieces(law, loop, start, limits, first, split, checkpoints);
    if (!pieces.certificate.certified()) {
      pieces.certificate.horizon_s = options.horizon_s;
      return finish(std::move(pieces.certificate));
    }
    for (std::size_t j = 0; j < checkpoints.size(); ++j) {
      const double handover_s = static_cast<double>(checkpoints[j]) * period;
      VerifyOptions rest = options;
      rest.horizon_s = options.horizon_s - handover_s;
      const detail::LoopRun after =
          detail::run_loop(law, loop, pieces.at_checkpoints[j], limits, rest);
      if (!after.certificate.certified()) continue;
      BalanceCertificate out = std::move(pieces.certificate);
      out.steps.resize(checkpoints[j]);
      out.horizon_s = options.horizon_s;
      out.handover_s = handover_s;
      out.largest_symbol_count =
          std::max(out.largest_symbol_count, after.certificate.largest_symbol_count);
      for (LoopStepBox step : after.certificate.steps) {
        step.t0_s += handover_s;
        step.t1_s += handover_s;
        out.steps.push_back(step);
      }
      return finish(std::move(out));
    }
  }
  return finish(run_pieces(law, loop, start, limits, options, split, {}).certificate);
}

}  // namespace furuta::verification
