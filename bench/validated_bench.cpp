// Validated simulation (issue 6): the DynIbex pendulum benchmark and the paper's four Furuta
// scenarios over 4 s, with point parameters and with interval parameters, against the spread of
// sampled solutions (long double RK4, tests/validated/reference.hpp). Each benchmark runs once
// (a run is seconds to minutes); the figures are counters:
//
//   build/hB/bench/validated_bench --benchmark_counters_tabular=true
//
// Environment: FURUTA_SPLIT_PIECES (cap on pieces, default 16), FURUTA_FV1_REL / FURUTA_FV2_REL /
// FURUTA_MU_REL (the interval parameters' relative half-widths, default 0.1 / 0.5 / 0.02);
// FURUTA_TM_ORDER (the Taylor-model benchmarks' order in z, default 3), FURUTA_WRAP_AT_BASE_POINT
// (the Furuta Taylor-model benchmarks' wrap_at_base_point, default 1).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "furuta/model/model.hpp"
#include "furuta/validated/integrator.hpp"
#include "furuta/validated/research/benchmark_systems.hpp"
#include "furuta/validated/split.hpp"
#include "furuta/validated/taylor_model_flow.hpp"
#include "furuta/validated/taylor_model_split.hpp"
#include "reference.hpp"

namespace {

using furuta::interval::Box;
using furuta::interval::Interval;
namespace v = furuta::validated;
namespace ref = furuta::validated::testing;

double env_or(const char* name, double fallback) {
  const char* s = std::getenv(name);
  return s != nullptr ? std::atof(s) : fallback;
}

// ---- (1) The DynIbex pendulum ------------------------------------------------------------------

void BM_Pendulum(benchmark::State& state) {
  const v::research::SimplePendulum pendulum;
  const Box x0{Interval(-1.755, -1.735), Interval(-0.01, 0.01)};
  v::IntegratorOptions options;
  options.t_end = 4.0;
  v::IntegrationResult r;
  for (auto _ : state) {
    r = v::integrate(pendulum, x0, options);
    benchmark::DoNotOptimize(r);
  }
  state.counters["ok"] = r.ok() ? 1 : 0;
  state.counters["wall_s"] = r.seconds;
  state.counters["steps"] = static_cast<double>(r.steps);
  // The true range of x1 from 1,000 points on the box's boundary (where the extremes are).
  std::vector<ref::Point<2>> points;
  for (int i = 0; i < 250; ++i) {
    const long double s = -1.0L + 2.0L * i / 250;
    points.push_back({-1.745L + 0.01L * s, -0.01L});
    points.push_back({-1.735L, 0.01L * s});
    points.push_back({-1.745L - 0.01L * s, 0.01L});
    points.push_back({-1.755L, -0.01L * s});
  }
  for (int second = 1; second <= 4; ++second) {
    long double lo = 1e9L;
    long double hi = -1e9L;
    for (ref::Point<2>& x : points) {
      x = ref::simulate(pendulum, x, second - 1.0, second, 1e-3);
      lo = std::min(lo, x[0]);
      hi = std::max(hi, x[0]);
    }
    const double width = r.tube.enclosure_at(second)[0].width();
    const std::string t = std::to_string(second);
    state.counters["x1_w_" + t + "s"] = width;
    state.counters["ratio_" + t + "s"] = width / static_cast<double>(hi - lo);
  }
}
BENCHMARK(BM_Pendulum)->Iterations(3)->Unit(benchmark::kMillisecond);

// ---- (2), (3) The paper's Furuta scenarios ----------------------------------------------------

struct Scenario {
  double q2_deg;
  double tau_nm;
};
constexpr Scenario kScenarios[] = {{-100.0, 0.0}, {50.0, 0.0}, {-90.0, 0.17}, {-45.0, -0.1}};

Box initial_state(const Scenario& s) {
  const double q2 = s.q2_deg * std::numbers::pi / 180.0;
  return Box{Interval(-1e-3, 1e-3), Interval(-1e-3, 1e-3), Interval(q2 - 1.6e-3, q2 + 1.6e-3),
             Interval(-1e-3, 1e-3)};
}

// The spread of q2 at `times` (increasing, from 0) over `count` sampled initial states (corners
// included) and, when `params` is not null, parameters drawn in their intervals (one draw per 50
// points).
std::vector<double> sampled_q2_spread(
    const Scenario& s, const Box& x0,
    const furuta::model::Parameters<furuta::interval::Interval>* params, std::size_t count,
    const std::vector<double>& times = {1.0, 2.0, 3.0, 4.0}) {
  const furuta::model::Parameters<double> truth = furuta::model::paper_run1();
  std::mt19937_64 rng(2024);
  const std::vector<ref::Point<4>> points = ref::sample_box<4>(x0, count, rng);
  const std::size_t m = times.size();
  std::vector<long double> lo(m, 1e9L);
  std::vector<long double> hi(m, -1e9L);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto draw = [&](const Interval& x) { return x.lo() + u(rng) * (x.hi() - x.lo()); };
  furuta::model::Parameters<furuta::interval::Interval> p = v::interval_parameters(truth);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (params != nullptr && i % 50 == 0) {
      p = furuta::model::Parameters<furuta::interval::Interval>{
          draw(params->mu1), draw(params->mu2), draw(params->mu3), draw(params->mu4),
          draw(params->mug), draw(params->fv1), draw(params->fv2)};
    }
    const v::FurutaStateDynamics system(p, Interval(s.tau_nm));
    ref::Point<4> x = points[i];
    double t = 0.0;
    for (std::size_t k = 0; k < m; ++k) {
      x = ref::simulate(system, x, t, times[k], 1e-3);
      t = times[k];
      lo[k] = std::min(lo[k], x[2]);
      hi[k] = std::max(hi[k], x[2]);
    }
  }
  std::vector<double> spread(m);
  for (std::size_t k = 0; k < m; ++k) spread[k] = static_cast<double>(hi[k] - lo[k]);
  return spread;
}

// q2's width in `set` (a Tube or a SplitResult) at each of `times`, and its ratio to the spread
// of sampled solutions with the parameters `p` drawn in their intervals.
struct Q2Width {
  double width;
  double ratio;
};
template <class Set>
std::vector<Q2Width> q2_against_spread(
    const Set& set, const Scenario& s, const Box& state_box,
    const furuta::model::Parameters<furuta::interval::Interval>& p,
    const std::vector<double>& times) {
  const std::vector<double> spread = sampled_q2_spread(s, state_box, &p, 1000, times);
  std::vector<Q2Width> out;
  for (std::size_t k = 0; k < times.size(); ++k) {
    const double width = set.enclosure_at(times[k])[v::FurutaDynamics::q2].width();
    out.push_back({width, width / spread[k]});
  }
  return out;
}

void report(benchmark::State& state, const v::SplitResult& r, std::size_t q2_component,
            const std::vector<double>& spread) {
  state.counters["ok"] = r.ok() ? 1 : 0;
  state.counters["t_reached"] = r.t_reached;
  state.counters["wall_s"] = r.seconds;
  state.counters["pieces"] = static_cast<double>(r.pieces.size());
  state.counters["runs"] = static_cast<double>(r.runs);
  state.counters["steps"] = static_cast<double>(r.steps);
  for (int second = 1; second <= 4; ++second) {
    const Box e = r.enclosure_at(second);
    const double width = e.is_empty() ? 0.0 : e[q2_component].width();
    const std::string t = std::to_string(second);
    state.counters["q2_w_" + t + "s"] = width;
    state.counters["spread_" + t + "s"] = spread[static_cast<std::size_t>(second - 1)];
    state.counters["ratio_" + t + "s"] = width / spread[static_cast<std::size_t>(second - 1)];
  }
}

v::IntegratorOptions furuta_options() {
  v::IntegratorOptions options;
  options.t_end = 4.0;
  options.tolerance = 1e-11;    // as scenario_integrator_options(): see validated/README.md
  options.max_inflation = 1.0;  // QR frame: the arm's damping (150 /s) ruins the parallelepiped
  return options;
}

v::SplitOptions split_options(int planned_depth = 0) {
  v::SplitOptions split;
  split.max_pieces = static_cast<std::size_t>(env_or("FURUTA_SPLIT_PIECES", 16));
  split.planned_depth = planned_depth;
  split.planned_split_s = env_or("FURUTA_PLANNED_SPLIT_S", 0.5);
  split.max_pieces = std::max(split.max_pieces, std::size_t{1} << planned_depth);
  return split;
}

// (2) Point parameters (the truth), state box +-1e-3 (q2 +-1.6e-3), the 4-dimensional system;
// second argument: the planned split's depth (2^depth pieces from FURUTA_PLANNED_SPLIT_S, 0.5 s).
void BM_FurutaPointParameters(benchmark::State& state) {
  const Scenario& s = kScenarios[state.range(0)];
  const Box x0 = initial_state(s);
  const v::FurutaStateDynamics system(v::interval_parameters(furuta::model::paper_run1()),
                                      Interval(s.tau_nm));
  v::SplitResult r;
  for (auto _ : state) {
    r = v::integrate_split(system, x0, furuta_options(),
                           split_options(static_cast<int>(state.range(1))));
    benchmark::DoNotOptimize(r);
  }
  report(state, r, v::FurutaStateDynamics::q2, sampled_q2_spread(s, x0, nullptr, 1000));
}
BENCHMARK(BM_FurutaPointParameters)
    ->ArgsProduct({{0, 1, 2, 3}, {0, 2, 3}})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

// (3) Interval parameters: fv1 +-10 %, fv2 +-50 % (a stand-in for SIVIA's box), the mu's +-2 %,
// carried as state (the 11-dimensional system) so that their correlation with the motion is kept;
// second argument: the planned split's depth, as in (2).
void BM_FurutaIntervalParameters(benchmark::State& state) {
  const Scenario& s = kScenarios[state.range(0)];
  const furuta::model::Parameters<double> truth = furuta::model::paper_run1();
  furuta::model::Parameters<furuta::interval::Interval> p =
      v::parameters_around(truth, env_or("FURUTA_MU_REL", 0.02));
  const double fv1 = env_or("FURUTA_FV1_REL", 0.1);
  const double fv2 = env_or("FURUTA_FV2_REL", 0.5);
  p.fv1 = Interval(truth.fv1) * (Interval(1.0) + Interval(-fv1, fv1));
  p.fv2 = Interval(truth.fv2) * (Interval(1.0) + Interval(-fv2, fv2));
  const Box state_box = initial_state(s);
  const Box x0 = v::FurutaDynamics::initial_box(state_box, p);
  const v::FurutaDynamics system(Interval(s.tau_nm));
  v::SplitResult r;
  for (auto _ : state) {
    r = v::integrate_split(system, x0, furuta_options(),
                           split_options(static_cast<int>(state.range(1))));
    benchmark::DoNotOptimize(r);
  }
  report(state, r, v::FurutaDynamics::q2, sampled_q2_spread(s, state_box, &p, 1000));
  // A run that ends early still says how tight it was: q2's width against the spread at half and
  // at nine tenths of the time it reached.
  if (r.t_reached < 4.0 && r.t_reached > 0.0) {
    const std::vector<Q2Width> late =
        q2_against_spread(r, s, state_box, p, {0.5 * r.t_reached, 0.9 * r.t_reached});
    const char* names[] = {"half", "late"};
    for (std::size_t k = 0; k < late.size(); ++k) {
      state.counters[std::string("q2_w_") + names[k]] = late[k].width;
      state.counters[std::string("ratio_") + names[k]] = late[k].ratio;
    }
  }
}
BENCHMARK(BM_FurutaIntervalParameters)
    ->ArgsProduct({{0, 1, 2, 3}, {0, 2, 3}})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

// (3b) Where the interval-parameter tubes end: one tube of the 50 deg scenario with a single
// parameter an interval (the others the truth as points), at the bench-(3) width for that
// parameter (mu's 2 %, fv1 10 %, fv2 50 %) divided by 10^decades. First argument: the parameter
// (0..6 = mu1, mu2, mu3, mu4, mug, fv1, fv2), second: decades (0..3).
void BM_FurutaOneIntervalParameter(benchmark::State& state) {
  const Scenario& s = kScenarios[1];
  const furuta::model::Parameters<double> truth = furuta::model::paper_run1();
  furuta::model::Parameters<furuta::interval::Interval> p = v::interval_parameters(truth);
  const auto parameter = static_cast<std::size_t>(state.range(0));
  const double bench_width[] = {0.02, 0.02, 0.02, 0.02, 0.02, 0.1, 0.5};
  const double relative = bench_width[parameter] * std::pow(10.0, -state.range(1));
  Interval* fields[] = {&p.mu1, &p.mu2, &p.mu3, &p.mu4, &p.mug, &p.fv1, &p.fv2};
  *fields[parameter] = *fields[parameter] * (Interval(1.0) + Interval(-relative, relative));
  const Box state_box = initial_state(s);
  const Box x0 = v::FurutaDynamics::initial_box(state_box, p);
  const v::FurutaDynamics system(Interval(s.tau_nm));
  v::IntegrationResult r;
  for (auto _ : state) {
    r = v::integrate(system, x0, furuta_options());
    benchmark::DoNotOptimize(r);
  }
  const double reached = r.tube.t_end();  // t_failed when the run ended early
  state.counters["relative"] = relative;
  state.counters["t_reached"] = reached;
  state.counters["steps"] = static_cast<double>(r.steps);
  state.counters["wall_s"] = r.seconds;
  // q2's width against the sampled spread at half the time reached: the tube is tight until the
  // error part takes over.
  state.counters["ratio_half"] =
      q2_against_spread(r.tube, s, state_box, p, {0.5 * reached})[0].ratio;
}
BENCHMARK(BM_FurutaOneIntervalParameter)
    ->ArgsProduct({{0, 1, 2, 3, 4, 5, 6}, {0, 1, 2, 3}})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

// (3c) The interval-parameter box of (3) (second argument: every half-width divided by
// 10^decades) carried as Taylor models (taylor_model_flow.hpp: order 3 in the 11 variables, the
// Jacobian as order-1 models, shrink wrapping, the arm's collapsed velocity left out when needed;
// FURUTA_SHRINK_WRAP=0 and FURUTA_WRAP_WITHOUT_COLLAPSED=0 turn them off), one tube, to 4 s or
// until it fails.
struct TaylorModelCase {
  furuta::model::Parameters<furuta::interval::Interval> p;
  Box state_box;
  Box x0;
  v::TaylorModelFlowOptions options;
};
TaylorModelCase taylor_model_case(const Scenario& s, std::int64_t decades) {
  const furuta::model::Parameters<double> truth = furuta::model::paper_run1();
  const double scale = std::pow(10.0, -static_cast<double>(decades));
  TaylorModelCase c;
  c.p = v::parameters_around(truth, 0.02 * scale);
  c.p.fv1 = Interval(truth.fv1) * (Interval(1.0) + Interval(-0.1 * scale, 0.1 * scale));
  c.p.fv2 = Interval(truth.fv2) * (Interval(1.0) + Interval(-0.5 * scale, 0.5 * scale));
  c.state_box = initial_state(s);
  c.x0 = v::FurutaDynamics::initial_box(c.state_box, c.p);
  c.options.integrator = furuta_options();
  c.options.integrator.order = 8;
  // The Lagrange remainder's target: the models' truncation is far above it (1e-9 to 1e-3 a
  // step), and 1e-10 or 1e-6 reach the same times.
  c.options.integrator.tolerance = 1e-8;
  c.options.space_order = static_cast<int>(env_or("FURUTA_TM_ORDER", c.options.space_order));
  c.options.integrator.max_width = 2.0 * std::numbers::pi;
  c.options.shrink_wrap_max_delta = env_or("FURUTA_SHRINK_WRAP", 1.0);
  c.options.wrap_without_collapsed = env_or("FURUTA_WRAP_WITHOUT_COLLAPSED", 1.0) != 0.0;
  c.options.wrap_at_base_point = env_or("FURUTA_WRAP_AT_BASE_POINT", 1.0) != 0.0;
  return c;
}

void BM_FurutaTaylorModels(benchmark::State& state) {
  const Scenario& s = kScenarios[state.range(0)];
  const TaylorModelCase c = taylor_model_case(s, state.range(1));
  const v::FurutaDynamics system(Interval(s.tau_nm));
  v::TaylorModelFlowResult r;
  for (auto _ : state) {
    r = v::integrate_taylor_models(system, c.x0, c.options);
    benchmark::DoNotOptimize(r);
  }
  const double reached = r.t_reached();
  state.counters["t_reached"] = reached;
  state.counters["steps"] = static_cast<double>(r.steps.size());
  state.counters["wrapped"] = static_cast<double>(r.shrink_wraps);
  state.counters["partial"] = static_cast<double>(r.partial_wraps);
  state.counters["wall_s"] = r.seconds;
  if (reached > 0.0) {
    const std::vector<Q2Width> w =
        q2_against_spread(r, s, c.state_box, c.p, {0.5 * reached, 0.9 * reached});
    state.counters["ratio_half"] = w[0].ratio;
    state.counters["ratio_late"] = w[1].ratio;
  }
}
BENCHMARK(BM_FurutaTaylorModels)
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1}})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

void report_split(benchmark::State& state, const v::TaylorModelSplitResult& r) {
  state.counters["t_reached"] = r.t_reached;
  state.counters["pieces"] = static_cast<double>(r.pieces.size());
  state.counters["runs"] = static_cast<double>(r.runs);
  state.counters["steps"] = static_cast<double>(r.steps);
  state.counters["wall_s"] = r.seconds;
  state.counters["critical_s"] = r.critical_path_seconds;
}

// (3d) (3c) split where a tube fails (taylor_model_split.hpp), to at most the third argument's
// pieces, on every core (FURUTA_TM_THREADS to set). The counters name how often each variable was
// cut (cut_<component>, components of FurutaDynamics) and the q2 ratio at each half second.
void BM_FurutaTaylorModelsSplit(benchmark::State& state) {
  const Scenario& s = kScenarios[state.range(0)];
  TaylorModelCase c = taylor_model_case(s, state.range(1));
  c.options.integrator.t_end = env_or("FURUTA_TM_T_END", c.options.integrator.t_end);
  const v::FurutaDynamics system(Interval(s.tau_nm));
  v::TaylorModelSplitOptions split;
  split.max_pieces = static_cast<std::size_t>(state.range(2));
  split.max_depth = 16;
  split.restart_back = env_or("FURUTA_TM_RESTART_BACK", split.restart_back);
  split.threads = static_cast<int>(env_or("FURUTA_TM_THREADS", 0.0));
  v::TaylorModelSplitResult r;
  for (auto _ : state) {
    r = v::integrate_taylor_models_split(system, c.x0, c.options, split);
    benchmark::DoNotOptimize(r);
  }
  report_split(state, r);
  for (std::size_t i = 0; i < r.cuts.size(); ++i) {
    if (r.cuts[i] > 0) state.counters["cut_" + std::to_string(i)] = static_cast<double>(r.cuts[i]);
  }
  std::vector<double> times;
  for (double t = 0.5; t <= r.t_reached; t += 0.5) times.push_back(t);
  times.push_back(0.9 * r.t_reached);
  if (r.t_reached > 0.0) {
    const std::vector<Q2Width> w = q2_against_spread(r, s, c.state_box, c.p, times);
    for (std::size_t k = 0; k + 1 < w.size(); ++k) {
      state.counters["ratio_" + std::to_string(times[k]).substr(0, 3) + "s"] = w[k].ratio;
    }
    state.counters["ratio_late"] = w.back().ratio;
  }
}
BENCHMARK(BM_FurutaTaylorModelsSplit)
    ->ArgsProduct({{0, 1, 2, 3}, {0}, {16}})
    ->ArgsProduct({{0, 1, 2, 3}, {1}, {4, 16}})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

// (3e) The split Taylor-model flow on the pendulum from a box 30x the benchmark's (+-0.3 in both
// components, order 3, to 3 s), to at most the first argument's pieces on the second argument's
// threads: how far splitting carries a tube that fails for want of width, and what the second core
// gives. `critical_s` is the sum over the cutting tree's generations of their longest run: the wall
// time with a core per run.
void BM_PendulumTaylorModelsSplit(benchmark::State& state) {
  const v::research::SimplePendulum pendulum;
  const Box x0{Interval(-2.045, -1.445), Interval(-0.3, 0.3)};
  v::TaylorModelFlowOptions o;
  o.integrator.t_end = 3.0;
  o.integrator.order = 8;
  o.integrator.tolerance = 1e-10;
  o.integrator.max_inflation = 1.0;
  o.integrator.max_width = 2.0 * std::numbers::pi;
  v::TaylorModelSplitOptions split;
  split.max_pieces = static_cast<std::size_t>(state.range(0));
  split.threads = static_cast<int>(state.range(1));
  v::TaylorModelSplitResult r;
  for (auto _ : state) {
    r = v::integrate_taylor_models_split(pendulum, x0, o, split);
    benchmark::DoNotOptimize(r);
  }
  report_split(state, r);
}
BENCHMARK(BM_PendulumTaylorModelsSplit)
    ->ArgsProduct({{1, 8, 32}, {1, 2}})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

}  // namespace
