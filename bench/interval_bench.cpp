// Interval arithmetic per operation: `*` in each sign case, by a point, `+`, `-`, `sqr`, and a
// small Taylor-style kernel (the Cauchy product of two series, as the validated integrator's
// recurrences do it). Each benchmark runs over kCount operand pairs drawn once (fixed seed); the
// time per iteration divided by kCount is the cost of one operation (the `op` counter, seconds per
// operation: 12.3n is 12.3 ns).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

#include "furuta/interval/interval.hpp"

namespace {

using furuta::interval::Interval;

constexpr std::size_t kCount = 1024;

enum class Shape { kPositive, kNegative, kMixed, kPoint, kAny };

// Moderate magnitudes (as the integrator's jets), narrow-ish widths.
std::vector<Interval> operands(Shape shape, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> mag(-6.0, 6.0);
  std::uniform_real_distribution<double> rel(1e-12, 1e-3);
  std::uniform_int_distribution<int> pick(0, 2);
  std::vector<Interval> v;
  v.reserve(kCount);
  for (std::size_t i = 0; i < kCount; ++i) {
    const double m = std::exp(mag(rng));
    Shape s = shape;
    if (s == Shape::kAny) s = static_cast<Shape>(pick(rng));
    switch (s) {
      case Shape::kPositive:
        v.emplace_back(m, m * (1 + rel(rng)));
        break;
      case Shape::kNegative:
        v.emplace_back(-m * (1 + rel(rng)), -m);
        break;
      case Shape::kMixed:
        v.emplace_back(-m * rel(rng), m);
        break;
      default:
        v.emplace_back(m);
        break;
    }
  }
  return v;
}

// Total time / (iterations * kCount) = time per operation.
void per_op(benchmark::State& state) {
  state.counters["op"] =
      benchmark::Counter(static_cast<double>(state.iterations() * kCount),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

template <class Op>
void binary(benchmark::State& state, Shape sx, Shape sy, Op op) {
  const std::vector<Interval> x = operands(sx, 1);
  const std::vector<Interval> y = operands(sy, 2);
  std::vector<Interval> r(kCount);
  for (auto _ : state) {
    for (std::size_t i = 0; i < kCount; ++i) r[i] = op(x[i], y[i]);
    benchmark::DoNotOptimize(r.data());
    benchmark::ClobberMemory();
  }
  per_op(state);
}

const auto mul = [](const Interval& a, const Interval& b) { return a * b; };
const auto add = [](const Interval& a, const Interval& b) { return a + b; };
const auto sub = [](const Interval& a, const Interval& b) { return a - b; };

void BM_MulPositive(benchmark::State& s) {
  binary(s, Shape::kPositive, Shape::kPositive, mul);
}
void BM_MulNegPos(benchmark::State& s) {
  binary(s, Shape::kNegative, Shape::kPositive, mul);
}
void BM_MulMixedPos(benchmark::State& s) {
  binary(s, Shape::kMixed, Shape::kPositive, mul);
}
void BM_MulMixedMixed(benchmark::State& s) {
  binary(s, Shape::kMixed, Shape::kMixed, mul);
}
void BM_MulAnyAny(benchmark::State& s) {  // sign cases in random order: branch mispredictions
  binary(s, Shape::kAny, Shape::kAny, mul);
}
void BM_MulByPoint(benchmark::State& s) {
  binary(s, Shape::kAny, Shape::kPoint, mul);
}
void BM_Add(benchmark::State& s) {
  binary(s, Shape::kAny, Shape::kAny, add);
}
void BM_Sub(benchmark::State& s) {
  binary(s, Shape::kAny, Shape::kAny, sub);
}

void BM_Sqr(benchmark::State& state) {
  const std::vector<Interval> x = operands(Shape::kAny, 3);
  std::vector<Interval> r(kCount);
  for (auto _ : state) {
    for (std::size_t i = 0; i < kCount; ++i) r[i] = sqr(x[i]);
    benchmark::DoNotOptimize(r.data());
    benchmark::ClobberMemory();
  }
  per_op(state);
}

// The Cauchy product c_k = sum_{j <= k} a_j b_{k-j} of two order-31 series: 528 products and
// 528 sums per iteration (the `op` counter is per product-and-sum pair).
void BM_CauchyProduct(benchmark::State& state) {
  constexpr std::size_t kOrder = 32;
  const std::vector<Interval> x = operands(Shape::kAny, 4);
  const std::vector<Interval> y = operands(Shape::kAny, 5);
  std::vector<Interval> c(kOrder);
  for (auto _ : state) {
    for (std::size_t k = 0; k < kOrder; ++k) {
      Interval s(0.0);
      for (std::size_t j = 0; j <= k; ++j) s += x[j] * y[k - j];
      c[k] = s;
    }
    benchmark::DoNotOptimize(c.data());
    benchmark::ClobberMemory();
  }
  state.counters["op"] =
      benchmark::Counter(static_cast<double>(state.iterations() * kOrder * (kOrder + 1) / 2),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

}  // namespace

BENCHMARK(BM_MulPositive);
BENCHMARK(BM_MulNegPos);
BENCHMARK(BM_MulMixedPos);
BENCHMARK(BM_MulMixedMixed);
BENCHMARK(BM_MulAnyAny);
BENCHMARK(BM_MulByPoint);
BENCHMARK(BM_Add);
BENCHMARK(BM_Sub);
BENCHMARK(BM_Sqr);
BENCHMARK(BM_CauchyProduct);
