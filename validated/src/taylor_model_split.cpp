// The splitting Taylor-model flow (see taylor_model_split.hpp).

#include "furuta/validated/taylor_model_split.hpp"

#include <tbb/task_arena.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <utility>

#include "parallel_runs.hpp"
#include "shrink_wrap.hpp"
#include "taylor_model_flow_core.hpp"

namespace furuta::validated {
namespace {

using detail::TaylorModelFlowState;

// A piece to run: the state it starts from and the steps before it (its ancestors').
struct TaylorModelJob {
  TaylorModelFlowState state;
  std::vector<TaylorModelFlowStep> steps;
  int depth = 0;
  std::string path;
};

// A cut restarts from a state whose error part (p's remainders and B r) is at most this share of
// p's spread in every weighed component: there p's halves are nearly the halves of the whole set.
// A larger share restarts too late, and restarting only from wholly wrapped states (whose r holds
// only rounding) carries the pendulum's wide box less far (docs/measurements/taylor-model-flow.md,
// "Taylor models III").
constexpr double kRestartErrorShare = 1e-3;

// The sum of |coefficient| over p's non-constant monomials: its range's radius about the constant
// term is within it.
double spread(const TaylorModel& p) {
  const std::vector<double>& c = p.coefficients();
  double sum = 0.0;
  for (std::size_t m = 1; m < c.size(); ++m) sum += std::abs(c[m]);
  return sum;
}

bool error_part_is_small(const TaylorModelFlowState& s, const std::vector<bool>& weigh) {
  for (std::size_t v = 0; v < s.p.size(); ++v) {
    if (!weigh[v]) continue;
    double error = s.p[v].remainder().mag();
    for (std::size_t j = 0; j < s.r.size(); ++j) {
      error +=
          std::abs(s.b(static_cast<Eigen::Index>(v), static_cast<Eigen::Index>(j))) * s.r[j].mag();
    }
    if (!(error <= kRestartErrorShare * spread(s.p[v]))) return false;
  }
  return true;
}

// A run of a job: its result (the job's steps and its own) and the states it passed that a cut
// may restart from (error_part_is_small), each with the number of steps before it.
struct Run {
  TaylorModelFlowResult result;
  std::vector<std::pair<std::size_t, TaylorModelFlowState>> restarts;
};

Run run_job(const detail::TaylorModelFlowSetup& setup, const Box& x0, const TaylorModelJob& job,
            const std::vector<bool>& weigh) {
  const auto started = std::chrono::steady_clock::now();
  Run run;
  run.result.initial = x0;
  run.result.t_start = setup.options.integrator.t_start;
  run.result.steps = job.steps;
  TaylorModelFlowState state = job.state;
  detail::TaylorModelFlowRunners runners;
  while (state.t < setup.options.integrator.t_end) {
    if (auto failure = detail::taylor_model_flow_step(setup, runners, state, run.result)) {
      run.result.status = failure->status;
      run.result.reason = std::move(failure->reason);
      run.result.width_stop = failure->width;
      break;
    }
    if (error_part_is_small(state, weigh))
      run.restarts.emplace_back(run.result.steps.size(), state);
  }
  run.result.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return run;
}

// The variable with the largest share of the weighed components' spread in p: each monomial's
// |coefficient| (its range over the box is within that) shared among its variables in
// proportion to their exponents, each component's shares divided by its spread (the sum over
// its non-constant monomials).
std::size_t widest_variable(const std::vector<TaylorModel>& p, const std::vector<bool>& weigh) {
  const MonomialSpace& space = *p.front().space();
  const std::size_t n = space.variables();
  std::vector<double> share(n, 0.0);
  for (std::size_t v = 0; v < p.size(); ++v) {
    if (!weigh[v]) continue;
    const std::vector<double>& c = p[v].coefficients();
    const double total = spread(p[v]);
    if (!(total > 0.0)) continue;
    for (std::size_t m = 1; m < space.size(); ++m) {
      if (c[m] == 0.0) continue;
      const double part = std::abs(c[m]) / (total * space.degree(m));
      for (std::size_t i = 0; i < n; ++i) share[i] += part * space.exponent(m, i);
    }
  }
  return static_cast<std::size_t>(std::max_element(share.begin(), share.end()) - share.begin());
}

// The variable that most keeps the error part from being wrapped into p. Shrink wrapping
// (shrink_wrap.hpp) holds while |I - A M| < 1, A the inverse of the rows' linear coefficients in
// the slots and M their derivatives in the slots over the box: so I - A M is A times the slots'
// derivatives' nonlinear terms. Each such term (a monomial of dp_row / dz_slot of degree >= 1,
// weighed by |A|'s column of its row) is shared among its variables by their exponents; halving
// a variable halves its share at least. The widest variable (widest_variable) when there are no
// slots or L is singular.
std::size_t cut_variable(const std::vector<TaylorModel>& p, const std::vector<bool>& weigh,
                         const std::vector<std::size_t>& rows,
                         const std::vector<std::size_t>& slots) {
  const std::size_t m = rows.size();
  if (m == 0 || slots.size() != m) return widest_variable(p, weigh);
  const MonomialSpace& space = *p.front().space();
  const std::size_t n = space.variables();
  // As in the wrap (shrink_wrap.cpp): a singular L has no useful inverse to weigh the rows by.
  const std::optional<Eigen::MatrixXd> l_inverse = detail::linear_part_inverse(p, rows, slots);
  if (!l_inverse) return widest_variable(p, weigh);
  const Eigen::MatrixXd a = l_inverse->cwiseAbs();
  std::vector<double> share(n, 0.0);
  for (std::size_t k = 0; k < m; ++k) {
    const double weight = a.col(static_cast<Eigen::Index>(k)).sum();
    const std::vector<double>& c = p[rows[k]].coefficients();
    for (std::size_t mono = 1 + n; mono < space.size(); ++mono) {
      if (c[mono] == 0.0) continue;
      for (std::size_t slot : slots) {
        const int e = space.exponent(mono, slot);
        if (e == 0) continue;
        // The term e c z^mono / z_slot of the derivative, degree deg - 1 >= 1.
        const double part =
            weight * std::abs(c[mono]) * e / static_cast<double>(space.degree(mono) - 1);
        for (std::size_t i = 0; i < n; ++i) {
          share[i] += part * (space.exponent(mono, i) - (i == slot ? 1 : 0));
        }
      }
    }
  }
  if (!(*std::max_element(share.begin(), share.end()) > 0.0)) return widest_variable(p, weigh);
  return static_cast<std::size_t>(std::max_element(share.begin(), share.end()) - share.begin());
}

TaylorModelFlowState restricted(const TaylorModelFlowState& state, std::size_t variable,
                                double centre) {
  TaylorModelFlowState half = state;
  for (TaylorModel& m : half.p) m = m.restricted(variable, centre, 0.5);
  return half;
}

}  // namespace

Box TaylorModelSplitResult::enclosure_at(double t) const {
  if (pieces.empty()) return {};
  Box hull = pieces.front().enclosure_at(t);
  for (std::size_t i = 1; i < pieces.size(); ++i) {
    const Box b = pieces[i].enclosure_at(t);
    for (std::size_t v = 0; v < hull.size(); ++v) hull[v] = interval::hull(hull[v], b[v]);
  }
  if (!(t >= pieces.front().t_start && t <= t_reached)) return Box(hull.size(), Interval::empty());
  return hull;
}

TaylorModelSplitResult integrate_taylor_models_split(const std::vector<Tape>& tapes,
                                                     const std::vector<double>& switches,
                                                     const Box& x0,
                                                     const TaylorModelFlowOptions& options,
                                                     const TaylorModelSplitOptions& split) {
  const detail::TaylorModelFlowSetup setup(tapes, switches, x0, options);
  if (split.max_pieces == 0) throw std::invalid_argument("split.max_pieces: at least 1");
  if (split.max_depth < 0) throw std::invalid_argument("split.max_depth: at least 0");
  if (!(split.restart_back >= 0.0 && split.restart_back <= 1.0)) {
    throw std::invalid_argument("split.restart_back: in [0, 1]");
  }
  const auto started = std::chrono::steady_clock::now();
  std::vector<bool> weigh = detail::read_components(tapes, setup.n);
  const detail::LiveSet live(tapes, setup.n);
  for (std::size_t v = 0; v < setup.n; ++v) weigh[v] = weigh[v] && live.is_live[v];
  tbb::task_arena arena(split.threads > 0 ? split.threads : tbb::task_arena::automatic);

  TaylorModelSplitResult out;
  out.cuts.assign(setup.n, 0);
  std::vector<std::pair<std::string, TaylorModelFlowResult>> done;
  std::vector<TaylorModelJob> jobs{
      TaylorModelJob{detail::initial_flow_state(setup, x0), {}, 0, ""}};
  std::size_t leaves = 1;
  while (!jobs.empty()) {
    std::vector<Run> runs(jobs.size());
    detail::parallel_runs(arena, jobs.size(),
                          [&](std::size_t i) { runs[i] = run_job(setup, x0, jobs[i], weigh); });
    double longest = 0.0;
    for (const Run& run : runs) longest = std::max(longest, run.result.seconds);
    out.critical_path_seconds += longest;
    std::vector<TaylorModelJob> next;
    for (std::size_t i = 0; i < jobs.size(); ++i) {
      Run& run = runs[i];
      TaylorModelJob& job = jobs[i];
      ++out.runs;
      out.steps += run.result.steps.size() - job.steps.size();
      if (run.result.ok() || job.depth >= split.max_depth || leaves + 1 > split.max_pieces) {
        done.emplace_back(job.path, std::move(run.result));
        continue;
      }
      // Cut at the last state early enough whose error part is small, else at the job's start.
      const double t_failed = run.result.t_reached();
      const double t_latest = t_failed - split.restart_back * (t_failed - job.state.t);
      const TaylorModelFlowState* from = &job.state;
      std::size_t steps_before = job.steps.size();
      for (auto it = run.restarts.rbegin(); it != run.restarts.rend(); ++it) {
        if (it->second.t <= t_latest) {
          from = &it->second;
          steps_before = it->first;
          break;
        }
      }
      const std::size_t variable = cut_variable(from->p, weigh, from->live.live, setup.wrap_slots);
      ++out.cuts[variable];
      ++out.splits;
      ++leaves;
      const std::vector<TaylorModelFlowStep> steps(
          run.result.steps.begin(), run.result.steps.begin() + static_cast<long>(steps_before));
      next.push_back(
          TaylorModelJob{restricted(*from, variable, -0.5), steps, job.depth + 1, job.path + "0"});
      next.push_back(
          TaylorModelJob{restricted(*from, variable, 0.5), steps, job.depth + 1, job.path + "1"});
    }
    jobs = std::move(next);
  }
  std::sort(done.begin(), done.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  out.t_reached = HUGE_VAL;
  for (auto& [path, result] : done) {
    out.t_reached = std::min(out.t_reached, result.t_reached());
    if (!result.ok() && out.ok()) {
      out.status = result.status;
      out.reason = result.reason;
      out.width_stop = result.width_stop;
    }
    out.paths.push_back(path);
    out.pieces.push_back(std::move(result));
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return out;
}

}  // namespace furuta::validated
