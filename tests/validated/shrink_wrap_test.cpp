// Shrink wrapping (validated/src/shrink_wrap.hpp, internal to the library: a white-box test) when
// the start variables' columns have become dependent, as the Furuta arm's are once its velocity
// has relaxed: four start columns in three slow directions. The wrap must leave out the dependent
// slot (whatever its length), and what it returns must hold p(z) + e for every z and e.
#include "shrink_wrap.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <random>
#include <vector>

namespace furuta::validated::detail {
namespace {

using interval::Interval;

constexpr std::size_t kSlots = 4;      // q1, dq1, q2, dq2
constexpr std::size_t kVariables = 5;  // the four start variables and one parameter

// p_i(z) = c_i + sum_j L_ij z_j + a parameter term + small quadratic terms, with L's dq1 column
// 0.5 (q2 column) + 0.7 (dq2 column) + `off` (dq1 unit vector): dependent for off = 0; the q2 row
// curved in the slots by `curvature` z_q2 z_dq2.
struct Case {
  std::shared_ptr<const MonomialSpace> space = std::make_shared<const MonomialSpace>(kVariables, 3);
  Eigen::Matrix4d l;
  std::vector<TaylorModel> p;

  explicit Case(double off, double curvature = 2e-6) {
    const Eigen::Vector4d q1(1e-3, 0.0, 0.0, 0.0);
    const Eigen::Vector4d q2(0.0, 3e-4, 1e-3, 5e-4);
    const Eigen::Vector4d dq2(0.0, -2e-4, 1e-4, 1e-3);
    l.col(0) = q1;
    l.col(2) = q2;
    l.col(3) = dq2;
    l.col(1) = 0.5 * q2 + 0.7 * dq2 + Eigen::Vector4d(0.0, off, 0.0, 0.0);
    const std::array<double, kSlots> centre{0.1, -0.2, -1.7, 0.3};
    auto z = [&](std::size_t v) { return TaylorModel::variable(space, v, Interval(-1.0, 1.0)); };
    for (std::size_t i = 0; i < kSlots; ++i) {
      TaylorModel row(space, Interval(centre[i]));
      for (std::size_t j = 0; j < kSlots; ++j) row += z(j) * Interval(l(i, j));
      if (i > 0)
        row += z(4) * Interval(2e-3 * static_cast<double>(i)) + z(2) * z(4) * Interval(1e-5);
      if (i == 2) row += z(2) * z(3) * Interval(curvature);
      p.push_back(row.polynomial());
    }
  }
};

const std::vector<std::size_t> kRows{0, 1, 2, 3};
const std::vector<Interval> kError{Interval(-2e-6, 2e-6), Interval(-5e-6, 4e-6),
                                   Interval(-3e-6, 3e-6), Interval(-1e-6, 2e-6)};

// Newton in double on the slots that were widened and on the left-out row's part c: p_new(w with
// z's other variables) + rest_mid + c e_kept = p(z) + e. w: the point's variables after the wrap.
struct Representation {
  std::vector<double> w;
  double c = 0.0;
};
Representation represent(const std::vector<TaylorModel>& p, const std::vector<TaylorModel>& wrapped,
                         const ShrinkWrap& wrap, const std::vector<double>& z,
                         const std::vector<double>& e) {
  std::vector<double> target(kSlots);
  for (std::size_t i = 0; i < kSlots; ++i) target[i] = p[i].evaluate(z).mid() + e[i];
  std::vector<double> w = z;
  double c = 0.0;
  for (int iteration = 0; iteration < 20; ++iteration) {
    Eigen::Vector4d residual;
    Eigen::Matrix4d jacobian;
    for (std::size_t i = 0; i < kSlots; ++i) {
      const auto ei = static_cast<Eigen::Index>(i);
      residual(ei) = wrapped[i].evaluate(w).mid() + wrap.rest[i].mid() - target[i];
      if (i == wrap.kept) residual(ei) += c;
      for (std::size_t j = 0; j < kSlots; ++j) {
        const auto ej = static_cast<Eigen::Index>(j);
        jacobian(ei, ej) =
            j == wrap.kept ? (i == j ? 1.0 : 0.0) : wrapped[i].derivative(j).evaluate(w).mid();
      }
    }
    const Eigen::Vector4d step = jacobian.fullPivLu().solve(residual);
    for (std::size_t j = 0; j < kSlots; ++j) {
      if (j == wrap.kept) {
        c -= step(static_cast<Eigen::Index>(j));
      } else {
        w[j] -= step(static_cast<Eigen::Index>(j));
      }
    }
  }
  return {w, c};
}

// The worst excess of |w| over 1 and of c outside the rest on the kept row (relative), both <= ~0
// when sound.
double worst_excess(const std::vector<TaylorModel>& p, const std::vector<TaylorModel>& wrapped,
                    const ShrinkWrap& wrap, const std::vector<double>& z,
                    const std::vector<double>& e) {
  const auto [w, c] = represent(p, wrapped, wrap, z, e);
  double excess = -1.0;
  for (std::size_t j = 0; j < kSlots; ++j) {
    if (j != wrap.kept) excess = std::max(excess, std::abs(w[j]) - 1.0);
  }
  if (wrap.kept < kSlots) {
    const Interval& kept = wrap.rest[wrap.kept];
    const double half = 0.5 * kept.width();
    excess = std::max(excess, (std::abs(c) - half) / half);
  }
  return excess;
}

// 200 sampled z, each with a corner of e: f(z, e).
template <class F>
void for_each_sample(std::uint64_t seed, F&& f) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int sample = 0; sample < 200; ++sample) {
    std::vector<double> z(kVariables);
    for (double& v : z) v = u(rng);
    std::vector<double> e(kSlots);
    for (std::size_t i = 0; i < kSlots; ++i) {
      e[i] = (sample >> i) & 1 ? kError[i].hi() : kError[i].lo();
    }
    f(z, e);
  }
}

// worst_excess over 200 sampled z, each with a corner of e.
double worst_over_samples(const std::vector<TaylorModel>& p,
                          const std::vector<TaylorModel>& wrapped, const ShrinkWrap& wrap,
                          std::uint64_t seed) {
  double worst = -1.0;
  for_each_sample(seed, [&](const std::vector<double>& z, const std::vector<double>& e) {
    worst = std::max(worst, worst_excess(p, wrapped, wrap, z, e));
  });
  return worst;
}

TEST(ShrinkWrap, DependentColumnsAreWrappedWithTheDependentSlotLeftOut) {
  const Case k(0.0);
  const std::vector<std::size_t> slots{0, 1, 2, 3};
  // The whole error part cannot go into four columns that span three directions.
  std::vector<TaylorModel> unwrapped = k.p;
  EXPECT_FALSE(shrink_wrap(unwrapped, kError, kRows, slots, 1.0, false).done);
  // Left out, the dq1 slot: its column is not short (0.5 and 0.7 of the others), only dependent.
  EXPECT_GT(k.l.col(1).norm(), 0.5 * k.l.col(2).norm());
  std::vector<TaylorModel> wrapped = k.p;
  const ShrinkWrap wrap = shrink_wrap(wrapped, kError, kRows, slots, 1.0, true);
  ASSERT_TRUE(wrap.done);
  EXPECT_EQ(wrap.kept, 1U);
  // Sound: every sampled z and every corner of e is reached by widened slots in [-1, 1] and the
  // kept row's part inside its rest.
  EXPECT_LE(worst_over_samples(k.p, wrapped, wrap, 11), 1e-9);
}

TEST(ShrinkWrap, IndependentColumnsAreWrappedWhole) {
  const Case k(4e-4);
  const std::vector<std::size_t> slots{0, 1, 2, 3};
  std::vector<TaylorModel> wrapped = k.p;
  const ShrinkWrap wrap = shrink_wrap(wrapped, kError, kRows, slots, 1.0, true);
  ASSERT_TRUE(wrap.done);
  EXPECT_EQ(wrap.kept, static_cast<std::size_t>(-1));
  EXPECT_LE(worst_over_samples(k.p, wrapped, wrap, 12), 1e-9);
}

// What the wrap reports ties each point's variables before (z) and after (w) it: scale_j w_j - z_j
// within delta_j on the widened slots, the kept slot and the parameter unchanged. Set inversion
// over the flow relies on it to carry a start through the wraps of a window.
TEST(ShrinkWrap, TheWrapTiesEachPointsVariablesBeforeAndAfter) {
  for (const double off : {0.0, 4e-4}) {
    const Case k(off);
    const std::vector<std::size_t> slots{0, 1, 2, 3};
    std::vector<TaylorModel> wrapped = k.p;
    const ShrinkWrap wrap = shrink_wrap(wrapped, kError, kRows, slots, 1.0, true);
    ASSERT_TRUE(wrap.done) << "off " << off;
    ASSERT_EQ(wrap.scale.size(), kVariables);
    ASSERT_EQ(wrap.delta.size(), kVariables);
    EXPECT_EQ(wrap.scale[4], 1.0);
    EXPECT_EQ(wrap.delta[4], 0.0);
    for (std::size_t j = 0; j < kSlots; ++j) {
      if (j == wrap.kept) {
        EXPECT_EQ(wrap.scale[j], 1.0);
        EXPECT_EQ(wrap.delta[j], 0.0);
      } else {
        EXPECT_GT(wrap.delta[j], 0.0) << "slot " << j;
        EXPECT_GE(wrap.scale[j], 1.0 + wrap.delta[j]) << "slot " << j;
      }
    }
    double worst = -1.0;  // the largest |scale w - z| - delta, relative to delta
    for_each_sample(21, [&](const std::vector<double>& z, const std::vector<double>& e) {
      const Representation r = represent(k.p, wrapped, wrap, z, e);
      for (std::size_t j = 0; j < kSlots; ++j) {
        if (j == wrap.kept) {
          EXPECT_EQ(r.w[j], z[j]);
          continue;
        }
        const double gap = std::abs(wrap.scale[j] * r.w[j] - z[j]);
        worst = std::max(worst, (gap - wrap.delta[j]) / wrap.delta[j]);
      }
    });
    EXPECT_LE(worst, 1e-6) << "off " << off;
  }
}

// The widening of slot j, 1 + delta_j, read from the rescaled linear coefficient of a row.
double widening(const Case& k, const std::vector<TaylorModel>& wrapped, std::size_t j) {
  const std::size_t m = k.space->variable(j);
  return wrapped[2].coefficient(m) / k.p[2].coefficient(m);
}

// With the preconditioner at the base point (A(z) ~ the slots' derivatives at z, inverted) the
// wraps hold as well, and widen less than with A over the box: I - A M keeps only the
// derivatives' change within delta of z, and delta is not raised on rows that already pass.
TEST(ShrinkWrap, AtTheBasePointTheWrapHoldsAndWidensLess) {
  const std::vector<std::size_t> slots{0, 1, 2, 3};
  for (const double off : {0.0, 4e-4}) {
    for (const double curvature : {2e-6, 2e-4}) {
      const Case k(off, curvature);
      std::vector<TaylorModel> over_box = k.p;
      const ShrinkWrap a = shrink_wrap(over_box, kError, kRows, slots, 1.0, true, false);
      std::vector<TaylorModel> at_base = k.p;
      const ShrinkWrap b = shrink_wrap(at_base, kError, kRows, slots, 1.0, true, true);
      ASSERT_TRUE(b.done) << off << " " << curvature;
      EXPECT_LE(worst_over_samples(k.p, at_base, b, 13), 1e-9) << off << " " << curvature;
      if (!a.done) continue;
      EXPECT_EQ(a.kept, b.kept);
      for (std::size_t j = 2; j < 4; ++j) {
        const double wa = widening(k, over_box, j);
        const double wb = widening(k, at_base, j);
        std::printf(
            "[ measured ] off %g, curvature %g, slot %zu: widening %.6f over the box, "
            "%.6f at the base point\n",
            off, curvature, j, wa, wb);
        EXPECT_LT(wb, wa);
      }
    }
  }
}

}  // namespace
}  // namespace furuta::validated::detail
