// Taylor models (issue 22): every operation's model holds the exact result at every point of its
// variables' box, checked against MPFR at 200 bits; the models are tight where they should be
// (dependency cancelled, remainders shrinking with the order); they run as TaylorRunner's scalar.
#include "furuta/validated/taylor_model.hpp"

#include <gtest/gtest.h>
#include <mpfr.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "furuta/model/model.hpp"
#include "furuta/validated/integrator.hpp"
#include "furuta/validated/ode.hpp"
#include "furuta/validated/research/benchmark_systems.hpp"
#include "furuta/validated/taylor.hpp"
#include "mpfr_oracle.hpp"

namespace furuta::validated {
namespace {

using furuta::testing::d_str;
using furuta::testing::Mp;
using furuta::testing::mp_str;
using research::SimplePendulum;

std::size_t binomial(std::size_t n, std::size_t k) {
  std::size_t r = 1;
  for (std::size_t i = 1; i <= k; ++i) r = r * (n - k + i) / i;
  return r;
}

TEST(MonomialSpace, GradedMonomialsAndTheirProducts) {
  for (std::size_t n : {1u, 2u, 4u, 11u}) {
    for (int k : {0, 1, 3, n < 11 ? 5 : 4}) {
      const MonomialSpace s(n, k);
      ASSERT_EQ(s.size(), binomial(n + static_cast<std::size_t>(k), static_cast<std::size_t>(k)));
      for (std::size_t m = 1; m < s.size(); ++m) EXPECT_LE(s.degree(m - 1), s.degree(m));
      for (std::size_t a = 0; a < s.size(); ++a) {
        for (std::size_t b = 0; b < s.size(); ++b) {
          const std::size_t p = s.product(a, b);
          if (s.degree(a) + s.degree(b) > k) {
            EXPECT_EQ(p, MonomialSpace::npos);
            continue;
          }
          ASSERT_NE(p, MonomialSpace::npos);
          for (std::size_t v = 0; v < n; ++v) {
            EXPECT_EQ(s.exponent(p, v), s.exponent(a, v) + s.exponent(b, v));
          }
        }
      }
    }
  }
  const MonomialSpace s(2, 2);
  EXPECT_EQ(s.range(0), Interval(1.0));
  EXPECT_EQ(s.range(s.variable(0)), Interval(-1.0, 1.0));
  EXPECT_EQ(s.range(s.product(s.variable(1), s.variable(1))), Interval(0.0, 1.0));
  EXPECT_THROW(MonomialSpace(0, 2), std::invalid_argument);
  EXPECT_THROW(MonomialSpace(3, 13), std::invalid_argument);
  EXPECT_THROW(MonomialSpace(11, 5), std::invalid_argument);  // 4,368 monomials
}

// A function of three variables, once on Taylor models and once in MPFR (at the real point
// x = mid + rad z that the variable models take at z).
struct Function {
  std::string name;
  std::function<TaylorModel(const std::array<TaylorModel, 3>&)> on_models;
  std::function<void(mpfr_ptr, const std::array<Mp, 3>&)> in_mpfr;
};

std::vector<Function> functions() {
  auto set = [](mpfr_ptr r, double v) { mpfr_set_d(r, v, MPFR_RNDN); };
  std::vector<Function> f;
  f.push_back({"x0 x1 - x0^2 + 0.5",
               [](const auto& x) { return x[0] * x[1] - sqr(x[0]) + TaylorModel(0.5); },
               [](mpfr_ptr r, const auto& x) {
                 Mp t;
                 mpfr_mul(r, x[0], x[1], MPFR_RNDN);
                 mpfr_sqr(t, x[0], MPFR_RNDN);
                 mpfr_sub(r, r, t, MPFR_RNDN);
                 mpfr_add_d(r, r, 0.5, MPFR_RNDN);
               }});
  f.push_back({"sin(x0 + 0.3 x1) x1",
               [](const auto& x) { return sin(x[0] + x[1] * Interval(0.3)) * x[1]; },
               [set](mpfr_ptr r, const auto& x) {
                 Mp t, k;
                 set(k, 0.3);
                 mpfr_mul(t, x[1], k, MPFR_RNDN);
                 mpfr_add(t, t, x[0], MPFR_RNDN);
                 mpfr_sin(t, t, MPFR_RNDN);
                 mpfr_mul(r, t, x[1], MPFR_RNDN);
               }});
  f.push_back({"cos(x0 x1) - 1 / (2 + x0)",
               [](const auto& x) {
                 return cos(x[0] * x[1]) - TaylorModel(1.0) / (x[0] + TaylorModel(2.0));
               },
               [](mpfr_ptr r, const auto& x) {
                 Mp t;
                 mpfr_mul(r, x[0], x[1], MPFR_RNDN);
                 mpfr_cos(r, r, MPFR_RNDN);
                 mpfr_add_d(t, x[0], 2.0, MPFR_RNDN);
                 mpfr_d_div(t, 1.0, t, MPFR_RNDN);
                 mpfr_sub(r, r, t, MPFR_RNDN);
               }});
  f.push_back({"(x0 x1 + sin x2) / (3 + cos x1), squared",
               [](const auto& x) {
                 return sqr((x[0] * x[1] + sin(x[2])) / (cos(x[1]) + TaylorModel(3.0)));
               },
               [](mpfr_ptr r, const auto& x) {
                 Mp t;
                 mpfr_mul(r, x[0], x[1], MPFR_RNDN);
                 mpfr_sin(t, x[2], MPFR_RNDN);
                 mpfr_add(r, r, t, MPFR_RNDN);
                 mpfr_cos(t, x[1], MPFR_RNDN);
                 mpfr_add_d(t, t, 3.0, MPFR_RNDN);
                 mpfr_div(r, r, t, MPFR_RNDN);
                 mpfr_sqr(r, r, MPFR_RNDN);
               }});
  // A denominator from 0.6 to 3.2 about 1.95 on the wide box: the reciprocal's tail far from c.
  f.push_back(
      {"x1 / (2 + x0 + 0.2 x1 x2)",
       [](const auto& x) { return x[1] / (x[0] + x[1] * x[2] * Interval(0.2) + TaylorModel(2.0)); },
       [set](mpfr_ptr r, const auto& x) {
         Mp t, k;
         set(k, 0.2);
         mpfr_mul(t, x[1], x[2], MPFR_RNDN);
         mpfr_mul(t, t, k, MPFR_RNDN);
         mpfr_add(t, t, x[0], MPFR_RNDN);
         mpfr_add_d(t, t, 2.0, MPFR_RNDN);
         mpfr_div(r, x[1], t, MPFR_RNDN);
       }});
  return f;
}

// Every function, orders 1..6, a narrow and a wide box: at 300 random points z (corners
// included), the MPFR value lies in the model's polynomial at z plus its remainder, and in its
// bound().
TEST(TaylorModel, EveryOperationHoldsTheExactValueAtEveryPoint) {
  const std::vector<std::array<Interval, 3>> boxes = {
      {Interval(0.38, 0.42), Interval(-0.22, -0.18), Interval(1.18, 1.22)},
      {Interval(-0.9, 0.9), Interval(-1.0, 0.6), Interval(0.0, 2.5)}};
  std::mt19937_64 rng(2211);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::size_t checks = 0;
  for (const Function& f : functions()) {
    for (int order = 1; order <= 6; ++order) {
      for (const auto& box : boxes) {
        const auto space = std::make_shared<const MonomialSpace>(3, order);
        const std::array<TaylorModel, 3> x = {TaylorModel::variable(space, 0, box[0]),
                                              TaylorModel::variable(space, 1, box[1]),
                                              TaylorModel::variable(space, 2, box[2])};
        const TaylorModel y = f.on_models(x);
        ASSERT_TRUE(y.remainder().is_bounded()) << f.name << " order " << order;
        const Interval range = y.bound();
        for (int p = 0; p < 300; ++p) {
          std::vector<double> z(3);
          for (std::size_t v = 0; v < 3; ++v) {
            z[v] = p < 8 ? ((p >> v) & 1 ? 1.0 : -1.0) : unit(rng);
          }
          std::array<Mp, 3> xs;
          for (std::size_t v = 0; v < 3; ++v) {
            // The variable model's real value at z: mid + rad z (exact in MPFR).
            mpfr_set_d(xs[v], box[v].rad(), MPFR_RNDN);
            mpfr_mul_d(xs[v], xs[v], z[v], MPFR_RNDN);
            mpfr_add_d(xs[v], xs[v], box[v].mid(), MPFR_RNDN);
          }
          Mp exact;
          f.in_mpfr(exact, xs);
          const Interval at = y.evaluate(z);
          ++checks;
          ASSERT_TRUE(mpfr_cmp_d(exact, at.lo()) >= 0 && mpfr_cmp_d(exact, at.hi()) <= 0)
              << f.name << ", order " << order << ", z = (" << z[0] << ", " << z[1] << ", " << z[2]
              << "): exact " << mp_str(exact, 30) << " not in [" << d_str(at.lo()) << ", "
              << d_str(at.hi()) << "]";
          ASSERT_TRUE(mpfr_cmp_d(exact, range.lo()) >= 0 && mpfr_cmp_d(exact, range.hi()) <= 0)
              << f.name << ": bound() misses " << mp_str(exact, 30);
        }
      }
    }
  }
  std::printf("[ measured ] Taylor models: %zu MPFR checks, 0 violations\n", checks);
}

// 1/x over [0.45, 1.55] in one variable: the series about 1 is exact up to order k, so the
// remainder is the geometric series' tail, largest at x = 0.45: 0.55^(k+1) / 0.45. The Lagrange
// form of the tail (0.55^(k+1) / 0.45^(k+2)) is 4.9x-120x wider at orders 1-5.
TEST(TaylorModel, TheReciprocalsRemainderIsTheSeriesTail) {
  for (int order : {1, 3, 5}) {
    const auto space = std::make_shared<const MonomialSpace>(1, order);
    const TaylorModel x = TaylorModel::variable(space, 0, Interval(0.45, 1.55));
    const TaylorModel y = reciprocal(x);
    const double tail = std::pow(0.55, order + 1) / 0.45;
    EXPECT_LE(y.remainder().mag(), tail * 1.001) << "order " << order;
    // It holds 1/x near the ends (at z = -1 the exact value is the bound's edge itself).
    EXPECT_TRUE(y.evaluate({-0.99}).contains(1.0 / (1.0 - 0.55 * 0.99))) << "order " << order;
    EXPECT_TRUE(y.evaluate({0.99}).contains(1.0 / (1.0 + 0.55 * 0.99))) << "order " << order;
  }
}

TEST(TaylorModel, TheRemainderShrinksWithTheOrderAndTheDependencyCancels) {
  const std::array<Interval, 2> box = {Interval(0.35, 0.45), Interval(-0.25, -0.15)};
  double previous = 1.0;
  for (int order : {1, 2, 3, 5, 7}) {
    const auto space = std::make_shared<const MonomialSpace>(2, order);
    const TaylorModel x0 = TaylorModel::variable(space, 0, box[0]);
    const TaylorModel x1 = TaylorModel::variable(space, 1, box[1]);
    const TaylorModel y = sin(x0 + x1 * Interval(0.3)) * x1 / (cos(x0) + TaylorModel(1.0));
    const double width = y.remainder().width();
    std::printf(
        "[ measured ] sin(x0 + 0.3 x1) x1 / (1 + cos x0) over +-0.05: order %d, remainder width "
        "%.3g\n",
        order, width);
    EXPECT_LT(width, previous * 0.2) << "order " << order;
    previous = width;
  }
  // x - x is 0 (a plain interval evaluation gives twice the width), and x^2 - 2x + 1 = (x - 1)^2
  // over [0, 2] is bounded by [0, 1], not [-4, 5].
  const auto space = std::make_shared<const MonomialSpace>(1, 3);
  const TaylorModel x = TaylorModel::variable(space, 0, Interval(0.0, 2.0));
  EXPECT_LE((x - x).bound().mag(), 1e-15);
  const Interval q = (sqr(x) - x * Interval(2.0) + TaylorModel(1.0)).bound();
  EXPECT_GE(q.lo(), -1e-15);
  EXPECT_LE(q.hi(), 1.0 + 1e-15);
}

// Where the linear part dominates, the linear-dominated bounder finds the corners: z0 + z1 +
// 0.1 z0 z1 over [-1, 1]^2 ranges over [-1.9, 2.1]; term by term gives [-2.1, 2.1].
TEST(TaylorModel, TheLinearDominatedBoundFindsTheCorners) {
  const auto space = std::make_shared<const MonomialSpace>(2, 3);
  const TaylorModel z0 = TaylorModel::variable(space, 0, Interval(-1.0, 1.0));
  const TaylorModel z1 = TaylorModel::variable(space, 1, Interval(-1.0, 1.0));
  const TaylorModel p = z0 + z1 + z0 * z1 * Interval(0.1);
  EXPECT_LE(p.polynomial_bound().lo(), -2.1 + 1e-12);
  const Interval b = p.bound();
  EXPECT_LE(b.lo(), -1.9);
  EXPECT_GT(b.lo(), -1.95);
  EXPECT_GE(b.hi(), 2.1);
  EXPECT_LT(b.hi(), 2.1 + 1e-9);
}

TEST(TaylorModel, ConstantsMixInAndDivisionByZeroIsEntire) {
  const auto space = std::make_shared<const MonomialSpace>(2, 3);
  const TaylorModel x = TaylorModel::variable(space, 0, Interval(-1.0, 1.0));
  const TaylorModel c(Interval(2.0, 3.0));
  EXPECT_TRUE((x + c).bound().is_subset(Interval(1.0 - 1e-12, 4.0 + 1e-12)));
  EXPECT_TRUE((c * x).bound().is_subset(Interval(-3.0 - 1e-12, 3.0 + 1e-12)));
  EXPECT_TRUE((TaylorModel(1.0) / x).remainder().is_entire());
  EXPECT_EQ((c + TaylorModel(1.0)).bound(), Interval(3.0, 4.0));
  const auto other = std::make_shared<const MonomialSpace>(2, 3);
  EXPECT_THROW(x + TaylorModel::variable(other, 1, Interval(0.0, 1.0)), std::invalid_argument);
}

// TaylorRunner with Taylor models as its scalar: the pendulum's Taylor coefficients as models in
// the start's deviations. At sampled starts they agree with the interval runner at that start.
TEST(TaylorModel, RunsAsTheTaylorRunnersScalar) {
  const std::vector<Tape> tapes = record_system(SimplePendulum{});
  const std::array<Interval, 2> box = {Interval(-1.76, -1.74), Interval(-0.01, 0.01)};
  const auto space = std::make_shared<const MonomialSpace>(2, 4);
  const std::vector<TaylorModel> x0 = {TaylorModel::variable(space, 0, box[0]),
                                       TaylorModel::variable(space, 1, box[1])};
  TaylorRunner<TaylorModel> models;
  models.run(tapes.front(), x0, 8);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int p = 0; p < 100; ++p) {
    const std::vector<double> z = {unit(rng), unit(rng)};
    const std::vector<Interval> start = {
        Interval(box[0].mid()) + Interval(box[0].rad()) * Interval(z[0]),
        Interval(box[1].mid()) + Interval(box[1].rad()) * Interval(z[1])};
    TaylorRunner<Interval> at_point;
    at_point.run(tapes.front(), start, 8);
    for (std::size_t v = 0; v < 2; ++v) {
      for (int i = 0; i <= 8; ++i) {
        const Interval m = models.coefficient(v, i).evaluate(z);
        EXPECT_TRUE(m.intersects(at_point.coefficient(v, i)))
            << "component " << v << " order " << i;
      }
    }
  }
}

// A model reduced to a lower order keeps every value: at sampled points the reduced model's set
// holds the original's value; its remainder is the dropped terms' bound.
TEST(TaylorModel, ReducedToALowerOrderHoldsEveryValue) {
  const auto space = std::make_shared<const MonomialSpace>(3, 4);
  const TaylorModel x = TaylorModel::variable(space, 0, Interval(0.2, 0.6));
  const TaylorModel y = TaylorModel::variable(space, 1, Interval(-1.0, 0.5));
  const TaylorModel z = TaylorModel::variable(space, 2, Interval(1.0, 1.5));
  const TaylorModel f = sin(x * y) * z + sqr(y) * x / z;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int order = 0; order <= 4; ++order) {
    const auto lower = std::make_shared<const MonomialSpace>(3, order);
    const TaylorModel g = f.reduced_to(lower);
    EXPECT_EQ(g.space(), lower);
    EXPECT_EQ(g.coefficients().size(), lower->size());
    for (int p = 0; p < 300; ++p) {
      const std::vector<double> at = {unit(rng), unit(rng), unit(rng)};
      EXPECT_TRUE(f.evaluate(at).is_subset(g.evaluate(at))) << "order " << order;
    }
    if (order < 4) {
      EXPECT_GT(g.remainder().width(), f.remainder().width()) << "order " << order;
    }
  }
  EXPECT_THROW(f.reduced_to(std::make_shared<const MonomialSpace>(2, 1)), std::invalid_argument);
  EXPECT_THROW(f.reduced_to(std::make_shared<const MonomialSpace>(3, 5)), std::invalid_argument);
}

// rescaled(s) is p(s z): at sampled z its set holds p's value at s z; partial_over(v, box) holds
// the derivative at every point of a box that reaches beyond [-1, 1] (central differences).
TEST(TaylorModel, RescaledAndPartialDerivativesHoldTheirValues) {
  const auto space = std::make_shared<const MonomialSpace>(2, 3);
  const TaylorModel x = TaylorModel::variable(space, 0, Interval(0.1, 0.5));
  const TaylorModel y = TaylorModel::variable(space, 1, Interval(-1.0, 0.2));
  const TaylorModel p = (sin(x * y) + sqr(y) * x).polynomial();
  const std::vector<double> s = {0.7, 1.3};
  const TaylorModel q = p.rescaled(s);
  const std::vector<Interval> box = {Interval(-1.25, 1.25), Interval(-1.0, 1.0)};
  const Interval d0 = p.partial_over(0, box);
  const Interval d1 = p.partial_over(1, box);
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int k = 0; k < 300; ++k) {
    const std::vector<double> z = {unit(rng), unit(rng)};
    const Interval exact = p.evaluate({s[0] * z[0], s[1] * z[1]});
    EXPECT_TRUE(exact.intersects(q.evaluate(z))) << z[0] << " " << z[1];
    const std::vector<double> w = {1.25 * z[0], z[1]};
    const double eps = 1e-6;
    const double f0 = (p.evaluate({w[0] + eps, w[1]}).mid() - p.evaluate({w[0] - eps, w[1]}).mid());
    const double f1 = (p.evaluate({w[0], w[1] + eps}).mid() - p.evaluate({w[0], w[1] - eps}).mid());
    EXPECT_TRUE(Interval(f0 / (2 * eps)).is_subset(d0 + Interval(-1e-6, 1e-6)));
    EXPECT_TRUE(Interval(f1 / (2 * eps)).is_subset(d1 + Interval(-1e-6, 1e-6)));
  }
  EXPECT_THROW(p.rescaled({1.0}), std::invalid_argument);
  EXPECT_THROW(p.partial_over(2, box), std::invalid_argument);
}

// restricted: the model over a part of one variable's range holds, at every z, the original's
// value at the mapped point, and its halves' ranges are inside the whole's and narrower.
TEST(TaylorModel, RestrictedHoldsItsValuesOverThePart) {
  const auto space = std::make_shared<const MonomialSpace>(3, 3);
  const TaylorModel x = TaylorModel::variable(space, 0, Interval(0.1, 0.5));
  const TaylorModel y = TaylorModel::variable(space, 1, Interval(-1.0, 0.2));
  const TaylorModel w = TaylorModel::variable(space, 2, Interval(2.0, 3.0));
  const TaylorModel p = sin(x * y) * w + sqr(y) * x - cos(w) * y;
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const std::vector<std::pair<double, double>> parts = {{-0.5, 0.5}, {0.5, 0.5}, {0.3, 0.6}};
  for (std::size_t v = 0; v < 3; ++v) {
    for (const auto& [centre, scale] : parts) {
      const TaylorModel q = p.restricted(v, centre, scale);
      EXPECT_TRUE(p.remainder().is_subset(q.remainder()));
      // Only the re-expansion's rounding is added.
      EXPECT_LT(q.remainder().width() - p.remainder().width(), 1e-13);
      EXPECT_LT(q.bound().width(), p.bound().width()) << v << " " << centre;
      for (int k = 0; k < 200; ++k) {
        std::vector<double> z = {unit(rng), unit(rng), unit(rng)};
        std::vector<double> mapped = z;
        mapped[v] = centre + scale * z[v];
        EXPECT_TRUE(q.evaluate(z).intersects(p.evaluate(mapped))) << v << " " << centre;
      }
    }
  }
  EXPECT_THROW(p.restricted(3, 0.5, 0.5), std::invalid_argument);
  EXPECT_THROW(p.restricted(0, 0.75, 0.5), std::invalid_argument);
}

// derivative: the polynomial's partial derivative holds its difference quotients' limit at
// sampled points; bounded_in: the model left in the other variables holds every value with the
// named variables anywhere in their ranges (here reaching beyond [-1, 1]).
TEST(TaylorModel, DerivativeAndBoundedInHoldTheirValues) {
  const auto space = std::make_shared<const MonomialSpace>(3, 3);
  const TaylorModel x = TaylorModel::variable(space, 0, Interval(0.1, 0.5));
  const TaylorModel y = TaylorModel::variable(space, 1, Interval(-1.0, 0.2));
  const TaylorModel w = TaylorModel::variable(space, 2, Interval(2.0, 3.0));
  const TaylorModel p = (sin(x * y) * w + sqr(y) * x * w - y).polynomial();
  const std::vector<Interval> ranges = {Interval(-1.3, 1.3), Interval(-1.0, 1.0),
                                        Interval(-0.5, 0.25)};
  const TaylorModel in_x1 = p.bounded_in({1}, ranges);
  const TaylorModel in_x02 = p.bounded_in({0, 2}, ranges);
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double eps = 1e-6;
  for (std::size_t v = 0; v < 3; ++v) {
    const TaylorModel d = p.derivative(v);
    for (int k = 0; k < 200; ++k) {
      const std::vector<double> z = {unit(rng), unit(rng), unit(rng)};
      std::vector<double> up = z;
      std::vector<double> down = z;
      up[v] += eps;
      down[v] -= eps;
      const double quotient = (p.evaluate(up).mid() - p.evaluate(down).mid()) / (2 * eps);
      EXPECT_TRUE(Interval(quotient).is_subset(d.evaluate(z) + Interval(-1e-6, 1e-6))) << v;
    }
  }
  for (int k = 0; k < 300; ++k) {
    const std::vector<double> z = {1.3 * unit(rng), unit(rng), 0.375 * unit(rng) - 0.125};
    const Interval value = p.evaluate(z);
    // The kept variables at z (within [-1, 1]), the bounded ones anywhere in their ranges (the
    // value given for them is not read: their terms are gone).
    if (std::abs(z[0]) <= 1.0) {
      EXPECT_TRUE(value.intersects(in_x1.evaluate({z[0], 0.7, z[2]})));
    }
    EXPECT_TRUE(value.intersects(in_x02.evaluate({-0.3, z[1], 0.9})));
  }
  // Nothing of the bounded variables is left in the polynomial.
  for (std::size_t m = 0; m < space->size(); ++m) {
    if (space->exponent(m, 1) > 0) {
      EXPECT_EQ(in_x1.coefficient(m), 0.0);
    }
    if (space->exponent(m, 0) > 0 || space->exponent(m, 2) > 0) {
      EXPECT_EQ(in_x02.coefficient(m), 0.0);
    }
  }
  EXPECT_THROW(p.derivative(3), std::invalid_argument);
  EXPECT_THROW(p.bounded_in({3}, ranges), std::invalid_argument);
  EXPECT_THROW(p.bounded_in({0}, {Interval(0.0)}), std::invalid_argument);
}

// Grad<N, TaylorModel>: the Taylor coefficients' gradients of the Furuta model with its seven
// parameters as state (the bench box: mu's +-2 %, fv1 +-10 %, fv2 +-50 %) as order-1 models in
// the box's deviations. At sampled points of the box they hold the point's gradients, and bounded
// over the box they are narrower than the interval gradients over the box (the dependency between
// the mass matrix's entries and the parameters is kept).
TEST(TaylorModel, GradientsAsModelsHoldEveryPointAndAreNarrower) {
  const model::Parameters<double> truth = model::paper_run1();
  model::Parameters<Interval> p = parameters_around(truth, 0.02);
  p.fv1 = Interval(truth.fv1) * Interval(0.9, 1.1);
  p.fv2 = Interval(truth.fv2) * Interval(0.5, 1.5);
  const Box state{Interval(-1e-3, 1e-3), Interval(2.0, 2.5), Interval(-1.8, -1.6),
                  Interval(-1.0, 1.0)};
  const Box box = FurutaDynamics::initial_box(state, p);
  const std::vector<Tape> tapes = record_system(FurutaDynamics(Interval(0.1)));
  constexpr std::size_t kN = FurutaDynamics::dimension;
  const std::size_t n = box.size();
  const int k = 6;
  const auto space = std::make_shared<const MonomialSpace>(n, 1);
  std::vector<Grad<kN, TaylorModel>> models(n);
  std::vector<Grad<kN>> intervals(n);
  for (std::size_t v = 0; v < n; ++v) {
    models[v] = Grad<kN, TaylorModel>::variable(TaylorModel::variable(space, v, box[v]), v);
    intervals[v] = Grad<kN>::variable(box[v], v);
  }
  TaylorRunner<Grad<kN, TaylorModel>> model_run;
  model_run.run(tapes.front(), models, k);
  TaylorRunner<Grad<kN>> interval_run;
  interval_run.run(tapes.front(), intervals, k);
  // The Jacobian of the Taylor map over a step of 2 ms (what the Taylor-model flow uses).
  const Interval h(2e-3);
  double model_width = 0.0;
  double interval_width = 0.0;
  for (std::size_t v = 0; v < n; ++v) {
    for (std::size_t w = 0; w < n; ++w) {
      TaylorModel jm = model_run.coefficient(v, k).d[w];
      Interval ji = interval_run.coefficient(v, k).d[w];
      for (int i = k - 1; i >= 0; --i) {
        jm = jm * h + model_run.coefficient(v, i).d[w];
        ji = ji * h + interval_run.coefficient(v, i).d[w];
      }
      ASSERT_TRUE(jm.bound().is_bounded()) << v << " " << w;
      model_width += jm.bound().width();
      interval_width += ji.width();
    }
  }
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::size_t checks = 0;
  for (int s = 0; s < 40; ++s) {
    std::vector<double> z(n);
    for (double& zi : z) zi = s % 2 == 0 ? unit(rng) : (unit(rng) < 0.0 ? -1.0 : 1.0);
    std::vector<Grad<kN>> at(n);
    for (std::size_t v = 0; v < n; ++v) {
      at[v] =
          Grad<kN>::variable(Interval(box[v].mid()) + Interval(box[v].rad()) * Interval(z[v]), v);
    }
    TaylorRunner<Grad<kN>> point_run;
    point_run.run(tapes.front(), at, k);
    for (std::size_t v = 0; v < n; ++v) {
      for (int i = 0; i <= k; ++i) {
        for (std::size_t w = 0; w < n; ++w) {
          ++checks;
          EXPECT_TRUE(model_run.coefficient(v, i).d[w].evaluate(z).intersects(
              point_run.coefficient(v, i).d[w]))
              << "component " << v << " order " << i << " variable " << w;
        }
      }
    }
  }
  std::printf(
      "[ measured ] Furuta: the order-%d Taylor map's Jacobian over 2 ms, summed widths "
      "%.3g as order-1 models, %.3g as intervals; %zu point checks\n",
      k, model_width, interval_width, checks);
  EXPECT_LT(model_width, 0.7 * interval_width);
}

}  // namespace
}  // namespace furuta::validated
