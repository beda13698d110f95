// Taylor-mode AD: the series recurrences against known expansions, the tape recorder, the ODE
// coefficients against closed forms, and the gradients against hand derivatives.
#include "furuta/validated/taylor.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <span>
#include <vector>

#include "furuta/validated/ode.hpp"
#include "furuta/validated/research/benchmark_systems.hpp"

namespace furuta::validated {
namespace {

using research::HarmonicOscillator;
using research::SimplePendulum;

double factorial(int n) {
  double f = 1.0;
  for (int i = 2; i <= n; ++i) f *= i;
  return f;
}

TEST(TaylorSeries, SinCosOfTheTimeVariable) {
  // sin(x0 + t) = sum sin^(i)(x0) t^i / i!.
  const double x0 = 0.7;
  const auto t = Taylor<double>::variable(x0, 12);
  const auto [s, c] = sin_cos(t);
  for (int i = 0; i <= 12; ++i) {
    const double ds = std::sin(x0 + i * M_PI / 2) / factorial(i);
    const double dc = std::cos(x0 + i * M_PI / 2) / factorial(i);
    EXPECT_NEAR(s[i], ds, 1e-15) << i;
    EXPECT_NEAR(c[i], dc, 1e-15) << i;
  }
  EXPECT_NEAR(sin(t)[5], s[5], 0.0);
  EXPECT_NEAR(cos(t)[5], c[5], 0.0);
}

TEST(TaylorSeries, ArithmeticAgainstKnownExpansions) {
  const int k = 10;
  const auto t = Taylor<double>::variable(0.0, k);
  const Taylor<double> one(k, 1.0);
  const Taylor<double> geometric = one / (one - t);  // 1 / (1 - t) = sum t^i
  const Taylor<double> square = sqr(one + t);        // 1 + 2t + t^2
  const Taylor<double> product = (one + t) * (one - t);
  for (int i = 0; i <= k; ++i) {
    EXPECT_DOUBLE_EQ(geometric[i], 1.0) << i;
    EXPECT_DOUBLE_EQ(square[i], i == 0 ? 1.0 : i == 1 ? 2.0 : i == 2 ? 1.0 : 0.0) << i;
    EXPECT_DOUBLE_EQ(product[i], i == 0 ? 1.0 : i == 2 ? -1.0 : 0.0) << i;
    EXPECT_DOUBLE_EQ((-t)[i], i == 1 ? -1.0 : 0.0);
  }
  EXPECT_DOUBLE_EQ(geometric.eval(0.5), (1.0 - std::pow(0.5, k + 1)) / 0.5);
}

TEST(TaylorSeries, IntervalSeriesEncloseThePointSeries) {
  const int k = 15;
  const auto ti = Taylor<Interval>::variable(Interval(0.3), k);
  const auto td = Taylor<double>::variable(0.3, k);
  const Taylor<Interval> fi = sin(ti) * cos(ti) / (Taylor<Interval>(k, Interval(2.0)) + sqr(ti));
  const Taylor<double> fd = sin(td) * cos(td) / (Taylor<double>(k, 2.0) + sqr(td));
  for (int i = 0; i <= k; ++i) {
    EXPECT_TRUE(fi[i].contains(fd[i])) << i << " " << fi[i] << " " << fd[i];
    EXPECT_LT(fi[i].width(), 1e-14) << i;
  }
}

TEST(Tape, RecordsFoldsConstantsAndPairsSinCos) {
  const Tape tape = record(
      [](std::span<const Recorder> x, std::span<Recorder> dx) {
        dx[0] = x[1];
        dx[1] = (Recorder(2.0) * Recorder(3.0)) * sin(x[0]) + cos(x[0]);
      },
      2);
  ASSERT_EQ(tape.outputs.size(), 2U);
  EXPECT_EQ(tape.outputs[0], 1);
  int sins = 0;
  int coss = 0;
  bool folded = false;
  for (const TapeNode& n : tape.nodes) {
    sins += n.op == Op::sin;
    coss += n.op == Op::cos;
    folded = folded || (n.op == Op::constant && n.value == Interval(6.0));
  }
  EXPECT_EQ(sins, 1);  // sin and cos of x0 share one pair
  EXPECT_EQ(coss, 1);
  EXPECT_TRUE(folded);
}

TEST(Tape, ParametersAsStateAreTimeConstant) {
  const Tape tape = record(
      [](std::span<const Recorder> x, std::span<Recorder> dx) {
        dx[0] = -(x[1] * x[0]);
        dx[1] = Recorder(0.0);
      },
      2);
  EXPECT_FALSE(tape.nodes[0].time_constant);
  EXPECT_TRUE(tape.nodes[1].time_constant);
  // x' = -p x: x_[i] = x0 (-p)^i / i!.
  TaylorRunner<double> run;
  const std::vector<double> x0{1.5, 0.8};
  run.run(tape, std::span<const double>(x0), 12);
  for (int i = 0; i <= 12; ++i) {
    EXPECT_NEAR(run.coefficient(0, i), 1.5 * std::pow(-0.8, i) / factorial(i), 1e-16) << i;
    EXPECT_EQ(run.coefficient(1, i), i == 0 ? 0.8 : 0.0);
  }
}

TEST(TaylorRunner, HarmonicOscillatorCoefficients) {
  // x'' = -w^2 x from (x0, v0): x_[i] = (w^i / i!) (x0 cos^(i)(0) + v0/w sin^(i)(0)).
  const HarmonicOscillator osc{2.0};
  const Tape tape =
      record([&](std::span<const Recorder> x, std::span<Recorder> dx) { osc(x, dx); }, 2);
  TaylorRunner<Interval> run;
  const std::vector<Interval> x0{Interval(0.5), Interval(-1.0)};
  const int k = 20;
  run.run(tape, std::span<const Interval>(x0), k);
  for (int i = 0; i <= k; ++i) {
    const double wi = std::pow(2.0, i) / factorial(i);
    const double exact =
        wi * (0.5 * std::cos(i * M_PI / 2) + (-1.0 / 2.0) * std::sin(i * M_PI / 2));
    EXPECT_NEAR(run.coefficient(0, i).mid(), exact, 1e-15 * std::max(1.0, wi)) << i;
    EXPECT_LT(run.coefficient(0, i).width(), 1e-15 * std::max(1.0, wi)) << i;
  }
}

TEST(TaylorRunner, GradientsAreTheDerivativesOfTheCoefficients) {
  // Pendulum x1' = x2, x2' = -a sin x1 - b x2: check d x_[i] / d x0 against central differences.
  const SimplePendulum p;
  const Tape tape =
      record([&](std::span<const Recorder> x, std::span<Recorder> dx) { p(x, dx); }, 2);
  const int k = 8;
  const std::vector<double> x0{-1.2, 0.4};
  std::vector<Grad<2>> g{Grad<2>::variable(Interval(x0[0]), 0),
                         Grad<2>::variable(Interval(x0[1]), 1)};
  TaylorRunner<Grad<2>> run;
  run.run(tape, std::span<const Grad<2>>(g), k);
  TaylorRunner<double> plus;
  TaylorRunner<double> minus;
  const double eps = 1e-6;
  for (std::size_t c = 0; c < 2; ++c) {
    std::vector<double> xp = x0;
    std::vector<double> xm = x0;
    xp[c] += eps;
    xm[c] -= eps;
    plus.run(tape, std::span<const double>(xp), k);
    minus.run(tape, std::span<const double>(xm), k);
    for (std::size_t v = 0; v < 2; ++v) {
      for (int i = 0; i <= k; ++i) {
        const double fd = (plus.coefficient(v, i) - minus.coefficient(v, i)) / (2 * eps);
        const Interval& d = run.coefficient(v, i).d[c];
        EXPECT_NEAR(d.mid(), fd, 1e-6 * std::max(1.0, std::abs(fd))) << v << " " << c << " " << i;
        EXPECT_LT(d.width(), 1e-9 * std::max(1.0, d.mag()));
      }
    }
  }
}

TEST(TaylorRunner, SecondOrderJetsAreHalfTheSecondDirectionalDerivatives) {
  // Along delta = C rho + e: with point rho and e = 0, d2 of x_[i] must be half the second
  // derivative of s -> x_[i](y + s delta) (central differences); with an interval rho, it must
  // contain that value for every rho inside.
  const SimplePendulum p;
  const Tape tape =
      record([&](std::span<const Recorder> x, std::span<Recorder> dx) { p(x, dx); }, 2);
  const int k = 6;
  const std::vector<double> y{-1.2, 0.4};
  const double c[2][2] = {{1.0, 0.3}, {-0.2, 2.0}};
  auto second_difference = [&](const std::vector<double>& delta, std::size_t v, int i) {
    TaylorRunner<double> run;
    const double eps = 1e-4;
    double values[3];
    for (int s = -1; s <= 1; ++s) {
      const std::vector<double> x{y[0] + s * eps * delta[0], y[1] + s * eps * delta[1]};
      run.run(tape, std::span<const double>(x), k);
      values[s + 1] = run.coefficient(v, i);
    }
    return (values[0] - 2 * values[1] + values[2]) / (eps * eps) / 2;
  };
  auto jets = [&](const std::vector<Interval>& rho) {
    std::vector<Jet2<2>> x0(2);
    for (std::size_t v = 0; v < 2; ++v) {
      x0[v] = Jet2<2>(Interval(y[v]));
      x0[v].g = {Interval(c[v][0]), Interval(c[v][1])};
      x0[v].rho = rho.data();
      x0[v].changed();
    }
    TaylorRunner<Jet2<2>> run;
    run.run(tape, std::span<const Jet2<2>>(x0), k);
    return run;
  };
  const std::vector<Interval> point_rho{Interval(0.7), Interval(-0.4)};
  const auto point = jets(point_rho);
  const std::vector<double> delta{c[0][0] * 0.7 - c[0][1] * 0.4, c[1][0] * 0.7 - c[1][1] * 0.4};
  for (std::size_t v = 0; v < 2; ++v) {
    for (int i = 0; i <= k; ++i) {
      const double fd = second_difference(delta, v, i);
      EXPECT_NEAR(point.coefficient(v, i).d2.mid(), fd, 1e-5 * std::max(1.0, std::abs(fd)))
          << v << " " << i;
    }
  }
  const std::vector<Interval> box_rho{Interval(-1.0, 1.0), Interval(-0.5, 0.5)};
  const auto box = jets(box_rho);
  for (double r0 : {-1.0, -0.3, 0.6, 1.0}) {
    for (double r1 : {-0.5, 0.1, 0.5}) {
      const std::vector<double> d{c[0][0] * r0 + c[0][1] * r1, c[1][0] * r0 + c[1][1] * r1};
      for (std::size_t v = 0; v < 2; ++v) {
        for (int i = 0; i <= k; ++i) {
          const double fd = second_difference(d, v, i);
          const Interval& d2 = box.coefficient(v, i).d2;
          EXPECT_TRUE(fd >= d2.lo() - 1e-5 * std::max(1.0, std::abs(fd)) &&
                      fd <= d2.hi() + 1e-5 * std::max(1.0, std::abs(fd)))
              << v << " " << i << " " << fd << " " << d2;
        }
      }
    }
  }
}

}  // namespace
}  // namespace furuta::validated
