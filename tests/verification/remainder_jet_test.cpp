// The plant's distance from its linearisation with its derivatives (verification/src/
// remainder_jet.hpp): at a point, its value against the field computed apart in long double and
// each order of derivative against central differences of the one below; over a box, every point's
// value and derivatives inside the box's intervals.
#include "remainder_jet.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <utility>

#include "loop_maps.hpp"

namespace furuta::verification::remainder_jet_test {
namespace {

using detail::RemainderJet;
using interval::Interval;

Eigen::Matrix2d upright_mass(const model::Parameters<double>& p) {
  Eigen::Matrix2d m;
  m << p.mu1, -p.mu3, -p.mu3, p.mu4;
  return m;
}

struct Plant {
  model::Parameters<double> centre{1.04e-3, 2.56e-3, 8.2e-4, 1.32e-3, 7.4e-2, 8.1e-2, 6.4e-4};
  double kd = 0.6;
  double kw = 0.155;
  detail::MomentumPlant momentum =
      detail::momentum_plant(centre, kd, kw, upright_mass(centre).inverse());
  model::Parameters<Interval> point = centre.map([](double v) { return Interval(v); });
};

// n(e, w) from its definition (docs/control.md): the rates M(pi + e)^-1 p with p = mass w, the
// field's momentum rows, less the linearisation's, in long double.
std::array<long double, 4> field_less_linear(const Plant& plant, long double e, long double w1,
                                             long double w2) {
  const model::Parameters<double>& c = plant.centre;
  const auto& mass = plant.momentum.mass;
  const long double p1 = mass(0, 0) * w1 + mass(0, 1) * w2;
  const long double p2 = mass(1, 0) * w1 + mass(1, 1) * w2;
  const long double q2 = std::numbers::pi_v<long double> + e;
  const long double s = std::sin(q2);
  const long double co = std::cos(q2);
  const long double m11 = c.mu1 + c.mu2 * s * s;
  const long double m12 = c.mu3 * co;
  const long double m22 = c.mu4;
  const long double det = m11 * m22 - m12 * m12;
  const long double dq1 = (m22 * p1 - m12 * p2) / det;
  const long double dq2 = (m11 * p2 - m12 * p1) / det;
  const long double damping = plant.kw + c.fv1;
  return {dq1 - w1, dq2 - w2, damping * w1 - damping * dq1,
          c.mu2 * s * co * dq1 * dq1 - c.mu3 * s * dq1 * dq2 - c.mug * s - c.mug * e - c.fv2 * dq2 +
              c.fv2 * w2};
}

RemainderJet jet_at(const Plant& plant, const std::array<double, 3>& y) {
  return detail::remainder_jet(plant.momentum, plant.point, Interval(plant.kw),
                               {Interval(y[0]), Interval(y[1]), Interval(y[2])});
}

using detail::pair_index;

std::size_t triple_index(std::array<std::size_t, 3> t) {
  std::sort(t.begin(), t.end());
  const auto at = std::find(detail::kTriples.begin(), detail::kTriples.end(), t);
  return static_cast<std::size_t>(at - detail::kTriples.begin());
}

TEST(RemainderJet, ValueAndEachOrderAgreeWithTheFieldAndDifferences) {
  const Plant plant;
  const std::array<double, 3> y{0.03, -1.7, 0.6};  // 1.7 deg, the arm at 1.7 rad/s
  const RemainderJet at = jet_at(plant, y);
  const auto n = field_less_linear(plant, y[0], y[1], y[2]);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_NEAR(static_cast<double>(n[i]), at.value[i].mid(), 1e-12 + 1e-9 * std::fabs(n[i]))
        << "row " << i;
    EXPECT_LT(at.value[i].width(), 1e-12) << "a point's value is thin";
  }
  // Central differences, each of the order below: of the long-double field for the gradient, of
  // the jet's gradient for the Hessian and of its Hessian for the third derivatives.
  const std::array<double, 3> step{1e-6, 1e-5, 1e-5};
  for (std::size_t k = 0; k < 3; ++k) {
    std::array<double, 3> up = y;
    std::array<double, 3> down = y;
    up[k] += step[k];
    down[k] -= step[k];
    const auto n_up = field_less_linear(plant, up[0], up[1], up[2]);
    const auto n_down = field_less_linear(plant, down[0], down[1], down[2]);
    const RemainderJet j_up = jet_at(plant, up);
    const RemainderJet j_down = jet_at(plant, down);
    for (std::size_t i = 0; i < 4; ++i) {
      const double slope = static_cast<double>((n_up[i] - n_down[i]) / (2 * step[k]));
      EXPECT_NEAR(slope, at.gradient[i][k].mid(), 1e-6 * (1 + std::fabs(slope)))
          << "dn" << i << "/dy" << k;
      for (std::size_t l = 0; l < 3; ++l) {
        const double second =
            (j_up.gradient[i][l].mid() - j_down.gradient[i][l].mid()) / (2 * step[k]);
        EXPECT_NEAR(second, at.hessian[i][pair_index(k, l)].mid(), 1e-5 * (1 + std::fabs(second)))
            << "d2n" << i << "/dy" << k << "dy" << l;
        for (std::size_t m = 0; m < 3; ++m) {
          const double third = (j_up.hessian[i][pair_index(l, m)].mid() -
                                j_down.hessian[i][pair_index(l, m)].mid()) /
                               (2 * step[k]);
          EXPECT_NEAR(third, at.third[i][triple_index({k, l, m})].mid(),
                      1e-4 * (1 + std::fabs(third)))
              << "d3n" << i << "/dy" << k << "dy" << l << "dy" << m;
        }
      }
    }
  }
}

TEST(RemainderJet, BoxHoldsEveryPointsValueAndDerivatives) {
  const Plant plant;
  const std::array<Interval, 3> box{Interval(-0.01, 0.05), Interval(-2.5, 0.5),
                                    Interval(-1.0, 1.5)};
  const RemainderJet over =
      detail::remainder_jet(plant.momentum, plant.point, Interval(plant.kw), box);
  std::mt19937 random(7);
  for (int trial = 0; trial < 200; ++trial) {
    std::array<double, 3> y;
    for (std::size_t k = 0; k < 3; ++k) {
      y[k] = std::uniform_real_distribution<double>(box[k].lo(), box[k].hi())(random);
    }
    const RemainderJet at = jet_at(plant, y);
    for (std::size_t i = 0; i < 4; ++i) {
      EXPECT_TRUE(at.value[i].is_subset(over.value[i])) << "value " << i;
      for (std::size_t k = 0; k < 3; ++k)
        EXPECT_TRUE(at.gradient[i][k].is_subset(over.gradient[i][k]));
      for (std::size_t k = 0; k < 6; ++k)
        EXPECT_TRUE(at.hessian[i][k].is_subset(over.hessian[i][k]));
      for (std::size_t k = 0; k < 10; ++k) EXPECT_TRUE(at.third[i][k].is_subset(over.third[i][k]));
    }
  }
}

}  // namespace
}  // namespace furuta::verification::remainder_jet_test
