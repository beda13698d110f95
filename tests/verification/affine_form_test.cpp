// The verifier's affine forms (verification/src/affine_form.hpp): a linear combination with
// interval coefficients holds its value for every choice of the symbols and of the coefficients in
// their intervals (evaluated in long double); the reduction's forms hold every point of the old
// ones, in every direction (their support functions), in the coordinates given or the identity.
#include "affine_form.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace furuta::verification::affine_form_test {
namespace {

using detail::AffineForm;
using detail::LinearCombination;
using detail::Symbols;
using interval::Interval;

// The form's value at the symbols e, without its err.
long double value_at(const AffineForm& a, const std::vector<double>& e) {
  long double v = a.centre;
  for (Eigen::Index j = 0; j < a.coef.size(); ++j) {
    v += static_cast<long double>(a.coef(j)) * e[static_cast<std::size_t>(j)];
  }
  return v;
}

TEST(AffineForm, ACombinationHoldsItsValueForEverySymbolAndCoefficient) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    Symbols symbols;
    std::vector<AffineForm> inputs;
    for (int i = 0; i < 4; ++i) {
      const double lo = u(rng) * std::pow(10.0, 3 * u(rng));
      inputs.push_back(symbols.noise(Interval(lo, lo + std::fabs(u(rng)))));
    }
    std::vector<Interval> k;
    LinearCombination sum;
    for (int i = 0; i < 4; ++i) {
      const double mid = u(rng) * 1e3;
      k.push_back(Interval(mid, mid + std::fabs(u(rng)) * 1e-3));
      sum.add(k.back(), inputs[static_cast<std::size_t>(i)]);
    }
    const AffineForm out = sum.result();
    const Interval range = detail::range(out);
    for (int sample = 0; sample < 50; ++sample) {
      std::vector<double> e(symbols.count());
      for (double& x : e) x = sample == 0 ? 1.0 : sample == 1 ? -1.0 : u(rng);
      long double exact = 0;
      for (int i = 0; i < 4; ++i) {
        const Interval& ki = k[static_cast<std::size_t>(i)];
        const double kv = ki.lo() + (ki.hi() - ki.lo()) * (0.5 + 0.5 * u(rng));
        exact += static_cast<long double>(kv) * value_at(inputs[static_cast<std::size_t>(i)], e);
      }
      // The value lies in the form's range, and within err of its symbols' part.
      EXPECT_GE(exact, range.lo());
      EXPECT_LE(exact, range.hi());
      EXPECT_LE(std::fabs(static_cast<double>(exact - value_at(out, e))), out.err);
    }
  }
}

// The support function of the forms' zonotope in direction d: d . centre + sum over the symbols
// of |d . g_j| + sum |d_i| err_i.
double support(const std::vector<AffineForm>& forms, const std::vector<double>& d) {
  double value = 0;
  Eigen::Index m = 0;
  for (const AffineForm& f : forms) m = std::max(m, f.coef.size());
  for (std::size_t i = 0; i < forms.size(); ++i) value += d[i] * forms[i].centre;
  for (Eigen::Index j = 0; j < m; ++j) {
    double dot = 0;
    for (std::size_t i = 0; i < forms.size(); ++i) {
      if (j < forms[i].coef.size()) dot += d[i] * forms[i].coef(j);
    }
    value += std::fabs(dot);
  }
  for (std::size_t i = 0; i < forms.size(); ++i) value += std::fabs(d[i]) * forms[i].err;
  return value;
}

TEST(AffineForm, TheReductionHoldsTheOldSetInEveryDirection) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  // A shear as the coordinates (y = [z0, z1 - 3 z0, z2]), and the identity.
  const detail::CoordinateMap shear_to = [](const std::vector<Interval>& z) {
    return std::vector<Interval>{z[0], z[1] - Interval(3.0) * z[0], z[2]};
  };
  const detail::CoordinateMap shear_from = [](const std::vector<Interval>& y) {
    return std::vector<Interval>{y[0], y[1] + Interval(3.0) * y[0], y[2]};
  };
  const detail::CoordinateMap same = [](const std::vector<Interval>& z) { return z; };
  for (const bool sheared : {false, true}) {
    for (int trial = 0; trial < 20; ++trial) {
      Symbols symbols;
      std::vector<AffineForm> forms(3);
      for (int j = 0; j < 40; ++j) {
        const AffineForm e = symbols.noise(Interval(-1.0, 1.0));
        for (auto& f : forms) f = LinearCombination().add(f).add(Interval(u(rng)), e).result();
      }
      const std::vector<AffineForm> before = forms;
      detail::reduce(forms, symbols, 12, sheared ? shear_to : same, sheared ? shear_from : same);
      EXPECT_EQ(symbols.count(), 12u);
      for (int n = 0; n < 200; ++n) {
        const std::vector<double> d{u(rng), u(rng), u(rng)};
        EXPECT_GE(support(forms, d), support(before, d) * (1 - 1e-12)) << "direction " << n;
      }
    }
  }
}

TEST(AffineForm, AnUnboundedQuantitySpansTheWholeLine) {
  Symbols symbols;
  const AffineForm f = symbols.noise(Interval(0.0, std::numeric_limits<double>::infinity()));
  EXPECT_FALSE(detail::range(f).is_bounded());
  EXPECT_EQ(symbols.count(), 0u);
}

}  // namespace
}  // namespace furuta::verification::affine_form_test
