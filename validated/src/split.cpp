// The splitting integrator (see split.hpp and validated/README.md, "Splitting").

#include "furuta/validated/split.hpp"

#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <utility>

#include "lohner_frame.hpp"
#include "parallel_runs.hpp"

namespace furuta::validated {
namespace {

// A piece to integrate: its initial box, the failed run it continues (null: from t_start) and
// that run's step to restart from, its depth and its path in the bisection tree ('0' lower half).
struct Job {
  Box box;
  std::shared_ptr<const IntegrationResult> parent;
  std::size_t step = 0;
  int depth = 0;
  std::string path;
};

// The widths of C r0 + P(r0) and B r (the exactly carried and the error part of the doubleton)
// at a step's t0.
void part_widths(const TubeStep& s, std::size_t n, std::vector<double>& exact,
                 std::vector<double>& error) {
  exact.assign(n, 0.0);
  error.assign(n, 0.0);
  const std::size_t pairs = n * (n + 1) / 2;
  for (std::size_t v = 0; v < n; ++v) {
    for (std::size_t j = 0; j < n; ++j) {
      exact[v] += std::abs(s.c[v * n + j]) * s.r0[j].width();
      error[v] += std::abs(s.b[v * n + j]) * s.r[j].width();
    }
    if (s.quad.size() != n * pairs) continue;
    // The quadratic part's width, bounded above by its coefficients times the ranges: the
    // criterion only needs its size.
    std::size_t k = 0;
    for (std::size_t a = 0; a < n; ++a) {
      for (std::size_t b = a; b < n; ++b, ++k) {
        exact[v] += std::abs(s.quad[v * pairs + k]) * s.r0[a].mag() * s.r0[b].mag() * 2.0;
      }
    }
  }
}

// The last step whose set at t0 was still tight (excess_ratio at most `excess`), or 0.
std::size_t restart_step(const Tube& tube, double excess) {
  std::vector<double> exact;
  std::vector<double> error;
  for (std::size_t j = tube.steps.size(); j-- > 1;) {
    part_widths(tube.steps[j], tube.dimension, exact, error);
    if (excess > 0.0 && excess_ratio(exact, error) <= excess) return j;
  }
  return 0;
}

// The component of the piece to bisect: the widest relative to x0 among those that can bend the
// flow (read by the field: the moving state and the parameters carried as state), so that the
// pieces shrink in turn in every such direction. (Choosing by the share of each direction in the
// set's extent at the failure kept cutting the same one: on the Furuta model the pendulum angle,
// while the speeds' widths fed the growth as much.)
std::size_t split_component(const Box& piece, const Box& x0, const std::vector<bool>& read) {
  std::vector<double> scale(x0.size(), 0.0);
  for (std::size_t v = 0; v < x0.size(); ++v) {
    if (read[v] && x0[v].width() > 0.0) scale[v] = x0[v].width();
  }
  return piece.widest_relative_index(scale);
}

// The component to bisect at a planned split, from the tube's last step: the start
// direction (state or parameter) with the largest share of the moving components' spread, each
// moving component weighed by its own spread (its row of C times the piece's widths: the
// polynomial's first-order coefficients). It keeps q2's tube closer to the sampled spread than
// halving every direction in turn (docs/measurements/taylor-model-flow.md, "Splitting where the
// spread comes from"). The widest relative direction when the tube has no step or no spread.
std::size_t spread_component(const Box& piece, const Box& x0, const std::vector<bool>& read,
                             const std::vector<bool>& moving, const Tube& tube) {
  if (tube.steps.empty()) return split_component(piece, x0, read);
  const std::size_t n = piece.size();
  const std::vector<double>& c = tube.steps.back().c;
  std::vector<double> share(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    if (!moving[i]) continue;
    double total = 0.0;
    for (std::size_t v = 0; v < n; ++v) total += std::abs(c[i * n + v]) * piece[v].width();
    if (!(total > 0.0)) continue;
    for (std::size_t v = 0; v < n; ++v) {
      if (read[v]) share[v] += std::abs(c[i * n + v]) * piece[v].width() / total;
    }
  }
  const auto best = std::max_element(share.begin(), share.end());
  if (!(*best > 0.0)) return split_component(piece, x0, read);
  return static_cast<std::size_t>(best - share.begin());
}

// The component to bisect after a run that failed with `tube`: at the tube's last step,
// the moving component whose error part has outgrown its exactly carried part the most (where
// the set is being lost), and in its row of C the start direction (state or parameter) with the
// largest term times the piece's width (the polynomial's first-order coefficients). Cycling
// through the directions the field reads never cut fv1, whose spread alone ends a Furuta tube
// early on the bench box (docs/measurements/validated.md, "Limits, in full"). The widest relative
// direction (split_component) when the tube has no step or no spread.
std::size_t failure_component(const Box& piece, const Box& x0, const std::vector<bool>& read,
                              const std::vector<bool>& moving, const Tube& tube) {
  if (tube.steps.empty()) return split_component(piece, x0, read);
  const std::size_t n = piece.size();
  const TubeStep& step = tube.steps.back();
  std::size_t worst = n;
  double worst_ratio = -1.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!moving[i]) continue;
    double exact = 0.0;
    double error = 0.0;
    for (std::size_t v = 0; v < n; ++v) {
      exact += std::abs(step.c[i * n + v]) * piece[v].width();
      error += std::abs(step.b[i * n + v]) * step.r[v].width();
    }
    const double ratio = exact > 0.0 ? error / exact : 0.0;
    if (exact > 0.0 && ratio > worst_ratio) {
      worst_ratio = ratio;
      worst = i;
    }
  }
  if (worst == n) return split_component(piece, x0, read);
  std::size_t best = n;
  double best_term = 0.0;
  for (std::size_t v = 0; v < n; ++v) {
    const double term = std::abs(step.c[worst * n + v]) * piece[v].width();
    if (read[v] && term > best_term) {
      best_term = term;
      best = v;
    }
  }
  return best == n ? split_component(piece, x0, read) : best;
}

}  // namespace

std::vector<const Tube*> SplitResult::tubes() const {
  std::vector<const Tube*> out;
  out.reserve(pieces.size());
  for (const Tube& t : pieces) out.push_back(&t);
  return out;
}

Box SplitResult::enclosure_at(double t) const {
  if (pieces.empty()) return Box();
  const std::size_t n = pieces.front().dimension;
  if (!(t >= pieces.front().t_start && t <= t_reached)) return Box(n, Interval::empty());
  Box out(n, Interval::empty());
  for (const Tube& p : pieces) out = hull(out, p.enclosure_at(t));
  return out;
}

Box SplitResult::enclosure_over(double ta, double tb) const {
  if (pieces.empty()) return Box();
  const std::size_t n = pieces.front().dimension;
  tb = std::min(tb, t_reached);
  if (!(ta <= tb)) return Box(n, Interval::empty());
  Box out(n, Interval::empty());
  for (const Tube& p : pieces) out = hull(out, p.enclosure_over(ta, tb));
  return out;
}

SplitResult integrate_split_tapes(const std::vector<Tape>& tapes,
                                  const std::vector<double>& switches, const Box& x0,
                                  const IntegratorOptions& options, const SplitOptions& split) {
  if (split.max_pieces == 0 || split.max_depth < 0 || !(split.restart_excess >= 0.0)) {
    throw std::invalid_argument("split options: max_pieces >= 1, max_depth >= 0, excess >= 0");
  }
  if (split.planned_depth < 0 || split.planned_depth > split.max_depth ||
      split.planned_depth >= 63 || (std::size_t{1} << split.planned_depth) > split.max_pieces) {
    throw std::invalid_argument(
        "split options: planned_depth in [0, max_depth] with 2^planned_depth <= max_pieces");
  }
  if (split.planned_depth > 0 &&
      !(split.planned_split_s >= options.t_start && split.planned_split_s < options.t_end)) {
    throw std::invalid_argument("split options: planned_split_s in [t_start, t_end)");
  }
  const auto started = std::chrono::steady_clock::now();
  const std::vector<bool> read = detail::read_components(tapes, x0.size());
  std::vector<bool> moving(x0.size(), false);
  for (std::size_t v : detail::live_components(tapes, x0.size())) moving[v] = true;
  tbb::task_arena arena(split.threads > 0 ? split.threads : tbb::task_arena::automatic);

  SplitResult out;
  struct Done {
    std::string path;
    std::shared_ptr<const IntegrationResult> result;
  };
  std::vector<Done> done;
  std::vector<Job> jobs{Job{x0, nullptr, 0, 0, ""}};
  std::size_t leaves = 1;
  if (split.planned_depth > 0) {
    // One tube up to the planned time, then 2^depth pieces from its last step (which starts
    // before that time: the pieces redo it, re-centred on themselves).
    std::shared_ptr<const IntegrationResult> root;
    std::size_t step = 0;
    if (split.planned_split_s > options.t_start) {
      IntegratorOptions first = options;
      first.t_end = split.planned_split_s;
      root = std::make_shared<const IntegrationResult>(integrate_tapes(tapes, switches, x0, first));
      ++out.runs;
      out.steps += root->steps;
      if (root->tube.steps.empty()) {
        root = nullptr;
      } else {
        step = root->ok() ? root->tube.steps.size() - 1
                          : restart_step(root->tube, split.restart_excess);
      }
    }
    jobs.clear();
    std::vector<Box> boxes{x0};
    for (int level = 0; level < split.planned_depth; ++level) {
      std::vector<Box> halves;
      for (const Box& b : boxes) {
        const auto [lower, upper] =
            b.bisect(root ? spread_component(b, x0, read, moving, root->tube)
                          : split_component(b, x0, read));
        halves.push_back(lower);
        halves.push_back(upper);
      }
      boxes = std::move(halves);
    }
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      std::string path;
      for (int level = split.planned_depth; level-- > 0;) path += ((i >> level) & 1U) ? '1' : '0';
      jobs.push_back(Job{boxes[i], root, step, split.planned_depth, path});
    }
    leaves = boxes.size();
    out.splits = boxes.size() - 1;
  }
  while (!jobs.empty()) {
    // Each job's run depends only on the job: the generation's results do not depend on the
    // schedule.
    std::vector<std::shared_ptr<const IntegrationResult>> results(jobs.size());
    detail::parallel_runs(arena, jobs.size(), [&](std::size_t i) {
      const Job& job = jobs[i];
      results[i] = std::make_shared<const IntegrationResult>(
          job.parent == nullptr
              ? integrate_tapes(tapes, switches, job.box, options)
              : integrate_sub_box(tapes, switches, job.parent->tube, job.step, job.box, options));
    });
    std::vector<Job> next;
    for (std::size_t i = 0; i < jobs.size(); ++i) {
      const IntegrationResult& r = *results[i];
      ++out.runs;
      out.steps += r.steps;
      const Job& job = jobs[i];
      if (r.ok() || job.depth >= split.max_depth || leaves + 1 > split.max_pieces) {
        done.push_back(Done{job.path, results[i]});
        continue;
      }
      const std::size_t d = failure_component(job.box, x0, read, moving, r.tube);
      const auto [lower, upper] = job.box.bisect(d);
      const bool restart = !r.tube.steps.empty();
      const std::size_t step = restart ? restart_step(r.tube, split.restart_excess) : 0;
      const auto parent = restart ? results[i] : nullptr;
      next.push_back(Job{lower, parent, step, job.depth + 1, job.path + "0"});
      next.push_back(Job{upper, parent, step, job.depth + 1, job.path + "1"});
      ++leaves;
      ++out.splits;
    }
    jobs = std::move(next);
  }

  std::sort(done.begin(), done.end(), [](const Done& a, const Done& b) { return a.path < b.path; });
  out.t_reached = std::numeric_limits<double>::infinity();
  for (const Done& d : done) {
    out.t_reached = std::min(out.t_reached, d.result->tube.t_end());
    if (!d.result->ok() && out.ok()) {
      out.status = d.result->status;
      out.reason = d.result->reason;
      out.width_stop = d.result->width_stop;
    }
  }
  out.pieces.reserve(done.size());
  for (Done& d : done) out.pieces.push_back(d.result->tube);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return out;
}

}  // namespace furuta::validated
