#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <optional>
#include <utility>
#include <vector>

#include "furuta/verification/balance_certificate.hpp"

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

bool is_point(const model::Parameters<Interval>& p) {
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    if (p[k].width() > 0) return false;
  }
  return true;
}

struct Piece {
  model::Parameters<Interval> parameters;
  LoopStart start;
  int splits = 0;
};

}  // namespace

BalanceCertificate verify_balance_split(const control::BalanceControllerSpec& law,
                                        const LoopModel& loop, const LoopStart& start,
                                        const LoopLimits& limits, const VerifyOptions& options,
                                        const SplitOptions& split) {
  const auto began = std::chrono::steady_clock::now();
  const std::array<double, model::kParameterCount> weights = influence(loop);
  std::vector<Piece> pending{Piece{loop.parameters, start, 0}};
  std::vector<BalanceCertificate> certified;
  std::optional<BalanceCertificate> failed;
  std::size_t pieces = 1;
  while (!pending.empty()) {
    std::vector<BalanceCertificate> results(pending.size());
    tbb::parallel_for(std::size_t{0}, pending.size(), [&](std::size_t i) {
      LoopModel piece = loop;
      piece.parameters = pending[i].parameters;
      results[i] = verify_balance(law, piece, pending[i].start, limits, options);
    });
    std::vector<Piece> next;
    for (std::size_t i = 0; i < pending.size(); ++i) {
      if (results[i].certified()) {
        certified.push_back(std::move(results[i]));
        continue;
      }
      if (pieces + 1 <= split.max_pieces && !failed) {
        // The start and the parameters in turn, the start first: its transient binds first.
        const Piece& p = pending[i];
        const auto by_start = start_halves(p.start, start);
        const bool parameters_split = !is_point(p.parameters);
        if (by_start && (p.splits % 2 == 0 || !parameters_split)) {
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
      if (!failed || results[i].failure->t_s < failed->failure->t_s) failed = std::move(results[i]);
    }
    if (failed) break;
    pending = std::move(next);
  }
  BalanceCertificate out;
  out.horizon_s = options.horizon_s;
  out.pieces = pieces;
  for (const BalanceCertificate& c : certified) {
    out.largest_symbol_count = std::max(out.largest_symbol_count, c.largest_symbol_count);
  }
  if (failed) {
    out.failure = failed->failure;
    out.steps = std::move(failed->steps);
    out.largest_symbol_count = std::max(out.largest_symbol_count, failed->largest_symbol_count);
  } else {
    out.steps = certified.front().steps;
    for (std::size_t c = 1; c < certified.size(); ++c) {
      for (std::size_t k = 0; k < out.steps.size(); ++k) {
        LoopStepBox& s = out.steps[k];
        const LoopStepBox& t = certified[c].steps[k];
        for (std::size_t i = 0; i < 4; ++i) {
          s.over[i] = hull(s.over[i], t.over[i]);
          s.at_end[i] = hull(s.at_end[i], t.at_end[i]);
          s.estimate[i] = hull(s.estimate[i], t.estimate[i]);
        }
        s.duty = hull(s.duty, t.duty);
      }
    }
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  return out;
}

}  // namespace furuta::verification
