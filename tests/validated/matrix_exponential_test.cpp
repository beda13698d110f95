// exp_enclosure (furuta/validated/matrix_exponential.hpp) against e^(a t) computed with MPFR at 200
// bits: for a point t every entry holds the exact value and is narrow; for an interval of t it
// holds the exact value at every t sampled inside; an unbounded t gives empty entries.
#include "furuta/validated/matrix_exponential.hpp"

#include <gtest/gtest.h>
#include <mpfr.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstddef>
#include <limits>
#include <random>
#include <vector>

#include "mpfr_oracle.hpp"

namespace furuta::validated::matrix_exponential_test {
namespace {

using furuta::testing::Mp;
using interval::Interval;

// e^(a t) in MPFR: the Taylor series, summed until a term is below 2^-220 of the sum's size (the
// matrices here have |a t| <= 10, so about 200 terms suffice; the loop stops by itself).
std::vector<Mp> exact_exponential(const Eigen::MatrixXd& a, double t) {
  const auto n = static_cast<std::size_t>(a.rows());
  std::vector<Mp> at(n * n), sum(n * n), term(n * n), next(n * n);
  Mp product;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      mpfr_set_d(at[i * n + j], a(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)),
                 MPFR_RNDN);
      mpfr_mul_d(at[i * n + j], at[i * n + j], t, MPFR_RNDN);
      mpfr_set_d(sum[i * n + j], i == j ? 1.0 : 0.0, MPFR_RNDN);
      mpfr_set_d(term[i * n + j], i == j ? 1.0 : 0.0, MPFR_RNDN);
    }
  }
  for (unsigned long k = 1; k < 1000; ++k) {
    bool negligible = true;
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < n; ++j) {
        mpfr_set_zero(next[i * n + j], 1);
        for (std::size_t l = 0; l < n; ++l) {
          mpfr_mul(product, term[i * n + l], at[l * n + j], MPFR_RNDN);
          mpfr_add(next[i * n + j], next[i * n + j], product, MPFR_RNDN);
        }
        mpfr_div_ui(next[i * n + j], next[i * n + j], k, MPFR_RNDN);
      }
    }
    for (std::size_t e = 0; e < n * n; ++e) {
      mpfr_set(term[e], next[e], MPFR_RNDN);
      mpfr_add(sum[e], sum[e], term[e], MPFR_RNDN);
      if (!mpfr_zero_p(term[e]) && mpfr_get_exp(term[e]) > -220) negligible = false;
    }
    if (negligible) break;
  }
  return sum;
}

// Every entry of `enclosure` holds the exact value's entry.
void expect_contains(const std::vector<Interval>& enclosure, const std::vector<Mp>& exact,
                     const char* what) {
  for (std::size_t e = 0; e < exact.size(); ++e) {
    EXPECT_GE(mpfr_cmp_d(exact[e], enclosure[e].lo()), 0)
        << what << " entry " << e << ": " << furuta::testing::mp_str(exact[e], 25) << " below "
        << furuta::testing::d_str(enclosure[e].lo());
    EXPECT_LE(mpfr_cmp_d(exact[e], enclosure[e].hi()), 0)
        << what << " entry " << e << ": " << furuta::testing::mp_str(exact[e], 25) << " above "
        << furuta::testing::d_str(enclosure[e].hi());
  }
}

// The kind of matrix the balance controller's verification needs: the linearised Furuta plant
// about upright (an unstable pendulum, a stiff damped arm), and seeded random ones.
std::vector<Eigen::MatrixXd> matrices() {
  Eigen::MatrixXd furuta(4, 4);
  furuta << 0, 0, 1, 0,  //
      0, 0, 0, 1,        //
      0, 87.3, -293.6, 0.9, 0, 120.4, -182.5, -1.1;
  std::vector<Eigen::MatrixXd> out{furuta};
  std::mt19937_64 rng(20261130);
  std::uniform_real_distribution<double> entry(-60.0, 60.0);
  for (int size : {2, 3, 4, 4, 5, 6}) {
    Eigen::MatrixXd m(size, size);
    for (int i = 0; i < size; ++i) {
      for (int j = 0; j < size; ++j) m(i, j) = entry(rng);
    }
    out.push_back(m);
  }
  return out;
}

TEST(ExpEnclosure, HoldsTheExactExponentialAtAPointTimeAndIsNarrow) {
  for (const Eigen::MatrixXd& a : matrices()) {
    for (const double t : {0.0, 0.001, 0.004, 0.008, 0.016, 0.05}) {
      const std::vector<Interval> enclosure = exp_enclosure(a, Interval(t));
      const std::vector<Mp> exact = exact_exponential(a, t);
      expect_contains(enclosure, exact, "point t");
      for (std::size_t e = 0; e < exact.size(); ++e) {
        const double value = mpfr_get_d(exact[e], MPFR_RNDN);
        EXPECT_LT(enclosure[e].width(), 1e-9 * (1.0 + std::abs(value)))
            << "t " << t << " entry " << e;
      }
    }
  }
}

TEST(ExpEnclosure, HoldsTheExactExponentialAtEveryTimeOfAnInterval) {
  for (const Eigen::MatrixXd& a : matrices()) {
    const Interval t(0.004, 0.006);
    const std::vector<Interval> enclosure = exp_enclosure(a, t);
    for (int i = 0; i <= 10; ++i) {
      const double ti = i == 10 ? t.hi() : t.lo() + 0.0002 * i;
      expect_contains(enclosure, exact_exponential(a, ti), "interval t");
    }
  }
}

TEST(ExpEnclosure, AnUnboundedOrEmptyTimeGivesEmptyEntries) {
  const Eigen::MatrixXd a = Eigen::MatrixXd::Identity(2, 2);
  for (const Interval& t :
       {Interval(0.0, std::numeric_limits<double>::infinity()), Interval::empty()}) {
    for (const Interval& e : exp_enclosure(a, t)) EXPECT_TRUE(e.is_empty());
  }
}

}  // namespace
}  // namespace furuta::validated::matrix_exponential_test
