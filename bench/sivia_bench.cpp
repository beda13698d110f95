// Guaranteed identification (SIVIA over the model's rows, identification/src/guaranteed.cpp) on two
// simulated 10 s sessions at 16 ms (1,094 samples after trimming): the paper's two-unknown problem
// (fv1, fv2; the mu's carried as Table II intervals) with and without the contractors, and all
// seven parameters unknown; some also on the first 625 or 312 samples, the IBEX reference's counts.
// Each with 1 thread and with all cores (threads:0). Counters: inner / boundary / outer boxes,
// boxes tested, truncated (1 when max_boxes stopped the paver), the outer hull's width per unknown
// (w_<name>), the inner and boundary boxes' measure over the unknowns, whether the truth is in the
// outer approximation, and the process's CPU seconds per run (all threads).
// Run: build/release/bench/sivia_bench (see bench/README.md).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <ctime>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "furuta/identification/guaranteed.hpp"
#include "furuta/identification/preprocessing.hpp"
#include "furuta/model/model.hpp"
#include "simulated_sessions.hpp"

namespace {

using namespace furuta;
using namespace furuta::identification;

using furuta::testing::bounds_covering;
using furuta::testing::simulate;
using furuta::testing::SimulatedSession;
using furuta::testing::trim;

struct Data {
  std::vector<SimulatedSession> sessions;
  std::vector<IntervalSample> samples;
  furuta::model::Parameters<double> truth{};
};
const Data& data() {
  static const Data d = [] {
    Data out;
    out.sessions = {simulate(1), simulate(2)};
    out.samples = interval_samples({&out.sessions[0].processed, &out.sessions[1].processed},
                                   bounds_covering(out.sessions), trim());
    out.truth = furuta::model::paper_run1();
    return out;
  }();
  return d;
}

GuaranteedOptions two_unknowns(double epsilon, bool contract) {
  GuaranteedOptions o;
  o.prior = paper_prior(data().truth);
  o.epsilon = epsilon;
  o.contract = contract;
  return o;
}

GuaranteedOptions seven_unknowns(double epsilon, bool relative) {
  GuaranteedOptions o;
  o.prior = paper_prior(data().truth, {12, 12, 10, 12, 15}, 0.2);
  o.unknown.fill(true);
  o.epsilon = epsilon;
  o.epsilon_relative = relative;
  o.max_boxes = 2'000'000;
  return o;
}

// The first n samples (0: all; the first session has 547 after trimming, the second as many).
std::vector<IntervalSample> first_samples(std::int64_t n) {
  const std::vector<IntervalSample>& all = data().samples;
  if (n <= 0 || static_cast<std::size_t>(n) >= all.size()) return all;
  return {all.begin(), all.begin() + n};
}

// state.range(0): log10 epsilon; range(1): threads (0 = all cores); range(2): samples (0 = all).
void run(benchmark::State& state, GuaranteedOptions o) {
  o.threads = static_cast<int>(state.range(1));
  const SampleConstraints constraints(first_samples(state.range(2)), o.prior, o.unknown);
  GuaranteedResult r;
  // The process's CPU time (every thread's; Google Benchmark's CPU column is the main thread's).
  const std::clock_t cpu_start = std::clock();
  for (auto _ : state) {
    r = guaranteed_identification(constraints, o);
    benchmark::DoNotOptimize(r.paving.boxes_tested);
  }
  state.counters["process_cpu_s"] = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC /
                                    static_cast<double>(state.iterations());
  const interval::SubPaving& p = r.paving;
  state.counters["samples"] = static_cast<double>(constraints.size());
  state.counters["inner"] = static_cast<double>(p.inner.size());
  state.counters["boundary"] = static_cast<double>(p.boundary.size());
  state.counters["outer"] = static_cast<double>(p.outer_count);
  state.counters["tested"] = static_cast<double>(p.boxes_tested);
  state.counters["probed_inner"] = static_cast<double>(p.probed_inner);
  state.counters["truncated"] = p.truncated ? 1 : 0;
  const Box hull = p.outer_hull();
  for (std::size_t k = 0; k < furuta::model::kParameterCount; ++k) {
    if (o.unknown[k])
      state.counters[std::string("w_") + furuta::model::kParameterNames[k]] = hull[k].width();
  }
  state.counters["inner_measure"] = unknowns_volume(p.inner, o.unknown);
  state.counters["boundary_measure"] = unknowns_volume(p.boundary, o.unknown);
  const std::vector<double> truth(data().truth.begin(), data().truth.end());
  const auto contains_truth = [&](const std::vector<Box>& boxes) {
    return std::any_of(boxes.begin(), boxes.end(), [&](const Box& b) { return b.contains(truth); });
  };
  state.counters["truth_inside"] = contains_truth(p.inner) || contains_truth(p.boundary) ? 1 : 0;
}

double epsilon(const benchmark::State& state) {
  return std::pow(10.0, static_cast<double>(state.range(0)));
}

// (a) The paper's problem with the contractors, on both sessions and on the first 625 samples (the
// IBEX reference's count).
void BM_TwoUnknowns(benchmark::State& state) {
  run(state, two_unknowns(epsilon(state), true));
}
BENCHMARK(BM_TwoUnknowns)
    ->ArgNames({"log10_eps", "threads", "samples"})
    ->ArgsProduct({{-2, -3, -4}, {1, 0}, {0}})
    ->ArgsProduct({{-2, -3}, {1, 0}, {625}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
// Finer: the inner approximation grows.
BENCHMARK(BM_TwoUnknowns)
    ->ArgNames({"log10_eps", "threads", "samples"})
    ->ArgsProduct({{-5}, {1, 0}, {0}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

// ... and without the inner probe (bisection alone decides inner boxes, as IBEX's paver does).
void BM_TwoUnknownsNoProbe(benchmark::State& state) {
  GuaranteedOptions o = two_unknowns(epsilon(state), true);
  o.probe_inner = false;
  run(state, o);
}
BENCHMARK(BM_TwoUnknownsNoProbe)
    ->ArgNames({"log10_eps", "threads", "samples"})
    ->ArgsProduct({{-2, -3}, {1}, {0, 625}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// (b) The same without the contractors (plain SIVIA: a box is outer when one sample's rows miss).
void BM_TwoUnknownsPlainSivia(benchmark::State& state) {
  run(state, two_unknowns(epsilon(state), false));
}
BENCHMARK(BM_TwoUnknownsPlainSivia)
    ->ArgNames({"log10_eps", "threads", "samples"})
    ->ArgsProduct({{-2, -3, -4}, {1, 0}, {0}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// (c) All seven parameters unknown, epsilon absolute 1e-3, on both sessions and on the first 312
// samples (the IBEX reference's count).
void BM_SevenUnknownsAbsolute(benchmark::State& state) {
  run(state, seven_unknowns(epsilon(state), false));
}
BENCHMARK(BM_SevenUnknownsAbsolute)
    ->ArgNames({"log10_eps_abs", "threads", "samples"})
    ->ArgsProduct({{-3}, {1, 0}, {0, 312}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// ... and epsilon relative 1e-3 (of each prior width): far more boxes than max_boxes (2,000,000)
// allows; the paving is truncated (the untested boxes stay boundary: sound, coarser).
void BM_SevenUnknownsRelative(benchmark::State& state) {
  run(state, seven_unknowns(epsilon(state), true));
}
BENCHMARK(BM_SevenUnknownsRelative)
    ->ArgNames({"log10_eps", "threads", "samples"})
    ->ArgsProduct({{-3}, {1, 0}, {0, 312}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

// Building the per-sample constraints (regressor enclosures, witness faces, the preconditioned
// system) is done once per problem, outside the timings above.
void BM_BuildConstraints(benchmark::State& state) {
  const GuaranteedOptions o =
      state.range(0) == 2 ? two_unknowns(0.01, true) : seven_unknowns(1e-3, false);
  for (auto _ : state) {
    const SampleConstraints c(data().samples, o.prior, o.unknown);
    benchmark::DoNotOptimize(c.size());
  }
}
BENCHMARK(BM_BuildConstraints)->ArgName("unknowns")->Arg(2)->Arg(7)->Unit(benchmark::kMillisecond);

}  // namespace
