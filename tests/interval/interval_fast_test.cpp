// The inline + - * and sqr (interval.hpp): the bit-step neighbours against std::nextafter, every
// sign case of the product and every edge (zeros, subnormal operands and results, bounds around
// the 2^500 fast range and the 2^-900 underflow threshold, overflow, infinite bounds, empty)
// against the previous implementation (interval_reference.hpp) bit for bit, millions of random
// operand pairs across magnitudes against it, and the bounds of finite operands against MPFR: each
// must be exactly the exact corner (or sum) rounded down or up, i.e. the tightest enclosure.
//
// FURUTA_LONG_TESTS=1 multiplies the random counts by 10.
#include <gtest/gtest.h>
#include <mpfr.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "furuta/interval/interval.hpp"
#include "interval_reference.hpp"

namespace furuta::interval::interval_fast_test {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kMax = std::numeric_limits<double>::max();
constexpr double kMinNormal = std::numeric_limits<double>::min();
constexpr double kMinSub = std::numeric_limits<double>::denorm_min();

int scale() {
  const char* v = std::getenv("FURUTA_LONG_TESTS");
  return (v != nullptr && std::string(v) == "1") ? 10 : 1;
}

std::uint64_t bits(double x) {
  std::uint64_t u;
  std::memcpy(&u, &x, sizeof u);
  return u;
}

bool same_bits(double a, double b) {
  return bits(a) == bits(b) || (std::isnan(a) && std::isnan(b));
}

bool same(const Interval& a, const Interval& b) {
  return bits(a.lo()) == bits(b.lo()) && bits(a.hi()) == bits(b.hi());
}

std::string str(const Interval& x) {
  std::ostringstream s;
  s.precision(17);
  s << x << " {" << std::hexfloat << x.lo() << ", " << x.hi() << "}";
  return s.str();
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Edge values: zeros, subnormals, the smallest normal, around 2^-450 (products around the 2^-900
// underflow threshold), ordinary values (exact and inexact products), around the 2^500 fast range,
// huge (overflowing products), DBL_MAX.
std::vector<double> edge_magnitudes() {
  return {0.0,
          kMinSub,
          3 * kMinSub,
          std::nextafter(kMinNormal, 0.0),
          kMinNormal,
          0x1.8p-460,
          0x1p-450,
          std::nextafter(0x1p-450, 1.0),
          0x1.3456789abcdefp-440,
          1e-10,
          0.1,
          0.5,
          1.0,
          std::nextafter(1.0, 2.0),
          3.0,
          1e10,
          0x1p499,
          0x1.fffffffffffffp499,
          0x1p500,
          std::nextafter(0x1p500, kInf),
          0x1p510,
          1e300,
          kMax};
}

std::vector<Interval> edge_intervals() {
  std::vector<double> v;
  for (double m : edge_magnitudes()) {
    v.push_back(m);
    v.push_back(-m);
  }
  v.push_back(kInf);
  v.push_back(-kInf);
  std::vector<Interval> r{Interval::empty(), Interval::entire()};
  for (double a : v) {
    for (double b : v) {
      if (a <= b && a != kInf && b != -kInf) r.emplace_back(a, b);
    }
  }
  return r;
}

// ---- Neighbours ---------------------------------------------------------------------------------

TEST(IntervalFast, BitStepNeighboursAreNextafter) {
  std::vector<double> v{kNaN, kInf, -kInf};
  for (double m : edge_magnitudes()) {
    for (double x : {m, -m, std::nextafter(m, kInf), std::nextafter(m, -kInf)}) v.push_back(x);
  }
  v.push_back(-0.0);
  std::mt19937_64 rng(7);
  for (int i = 0; i < 100'000; ++i) {
    const std::uint64_t u = rng();
    double x;
    std::memcpy(&x, &u, sizeof x);
    v.push_back(x);
  }
  for (double x : v) {
    ASSERT_TRUE(same_bits(detail::next_up(x), std::nextafter(x, kInf))) << std::hexfloat << x;
    ASSERT_TRUE(same_bits(detail::next_down(x), std::nextafter(x, -kInf))) << std::hexfloat << x;
    if (std::isfinite(x) && x != 0) {
      ASSERT_TRUE(same_bits(detail::step_up(x), std::nextafter(x, kInf))) << std::hexfloat << x;
      ASSERT_TRUE(same_bits(detail::step_down(x), std::nextafter(x, -kInf))) << std::hexfloat << x;
    }
  }
}

// ---- Hand-picked cases --------------------------------------------------------------------------

TEST(IntervalFast, EverySignCaseOfTheProductIsExactWhenRepresentable) {
  const Interval pos(2.0, 3.0), neg(-5.0, -4.0), mixed(-1.0, 6.0), zero(0.0);
  EXPECT_EQ(pos * pos, Interval(4.0, 9.0));
  EXPECT_EQ(pos * neg, Interval(-15.0, -8.0));
  EXPECT_EQ(pos * mixed, Interval(-3.0, 18.0));
  EXPECT_EQ(neg * pos, Interval(-15.0, -8.0));
  EXPECT_EQ(neg * neg, Interval(16.0, 25.0));
  EXPECT_EQ(neg * mixed, Interval(-30.0, 5.0));
  EXPECT_EQ(mixed * pos, Interval(-3.0, 18.0));
  EXPECT_EQ(mixed * neg, Interval(-30.0, 5.0));
  EXPECT_EQ(mixed * Interval(-7.0, 2.0), Interval(-42.0, 12.0));
  EXPECT_EQ(Interval(-7.0, 2.0) * mixed, Interval(-42.0, 12.0));
  // Both straddle zero: lo from xh*yl and hi from xl*yl, then lo from xl*yh and hi from xh*yh.
  EXPECT_EQ(Interval(-3.0, 5.0) * Interval(-4.0, 2.0), Interval(-20.0, 12.0));
  EXPECT_EQ(Interval(-5.0, 3.0) * Interval(-2.0, 4.0), Interval(-20.0, 12.0));
  for (const Interval& x : {pos, neg, mixed, zero}) {
    EXPECT_EQ(x * zero, zero);
    EXPECT_EQ(zero * x, zero);
  }
  // Bounds touching zero: x >= 0 with xl = 0, y <= 0 with yh = 0.
  EXPECT_EQ(Interval(0.0, 2.0) * Interval(-3.0, 0.0), Interval(-6.0, 0.0));
  EXPECT_EQ(Interval(-2.0, 0.0) * Interval(-3.0, 0.0), Interval(0.0, 6.0));
  EXPECT_EQ(Interval(-2.0, 0.0) * Interval(-3.0, 5.0), Interval(-10.0, 6.0));
  // -0 bounds are +0 in the result.
  const Interval r = Interval(-0.0, 2.0) * Interval(-3.0, -0.0);
  EXPECT_FALSE(std::signbit(r.hi()));
  EXPECT_FALSE(std::signbit((Interval(-2.0) * Interval(0.0)).lo()));
  // Exact products of 53-bit operands stay points; inexact ones are adjacent doubles.
  const double a = 0x1.fffffffffffffp0, b = 0x1p-3;
  EXPECT_EQ(Interval(a) * Interval(b), Interval(a * b));
  const Interval t = Interval(0.1) * Interval(3.0);
  EXPECT_EQ(std::nextafter(t.lo(), kInf), t.hi());
  EXPECT_EQ(sqr(Interval(-3.0, 2.0)), Interval(0.0, 9.0));
  EXPECT_EQ(sqr(Interval(-3.0, -2.0)), Interval(4.0, 9.0));
}

TEST(IntervalFast, SubnormalsOverflowAndInfiniteBounds) {
  // A subnormal operand with a factor inside the fast range: exact, and a point.
  EXPECT_EQ(Interval(kMinSub) * Interval(0x1p500), Interval(0x1p-574));
  EXPECT_EQ(Interval(3 * kMinSub) * Interval(0x1p400), Interval(0x1.8p-673));
  // Products below 2^-900: the scaled path; a subnormal result; an underflow to zero.
  EXPECT_EQ(Interval(0x1p-500) * Interval(0x1p-500), Interval(0x1p-1000));
  const Interval u = Interval(0.1 * 0x1p-537) * Interval(0x1p-537);
  EXPECT_EQ(u, reference::mul(Interval(0.1 * 0x1p-537), Interval(0x1p-537)));
  EXPECT_EQ(std::nextafter(u.lo(), kInf), u.hi());
  // Below the 2^-900 threshold, a residual too small for TwoProduct: (1 + 2^-52)^2 2^-990 rounds to
  // (1 + 2^-51) 2^-990 with a residual of 2^-1094, below the smallest subnormal. Inline, TwoProduct
  // would compute 0 and call the product exact; the scaled path sees the residual.
  const double c = (1 + 0x1p-52) * 0x1p-495;
  const Interval cc = Interval(c) * Interval(c);
  EXPECT_EQ(cc.lo(), (1 + 0x1p-51) * 0x1p-990);
  EXPECT_EQ(cc.hi(), std::nextafter(cc.lo(), kInf));
  EXPECT_EQ(sqr(Interval(c)), cc);
  EXPECT_EQ(Interval(-c) * Interval(c), -cc);
  EXPECT_EQ(Interval(kMinSub) * Interval(0.5), Interval(0.0, kMinSub));
  EXPECT_EQ(Interval(-kMinSub) * Interval(0.5), Interval(-kMinSub, 0.0));
  // Overflow beyond the fast range.
  EXPECT_EQ(Interval(0x1p600) * Interval(0x1p600), Interval(kMax, kInf));
  EXPECT_EQ(Interval(-0x1p600) * Interval(0x1p600), Interval(-kInf, -kMax));
  EXPECT_EQ(sqr(Interval(0x1p600)), Interval(kMax, kInf));
  // Infinite bounds, 0 * inf = 0, the empty interval.
  EXPECT_EQ(Interval(0.0) * Interval::entire(), Interval(0.0));
  EXPECT_EQ(Interval(1.0, 2.0) * Interval(3.0, kInf), Interval(3.0, kInf));
  EXPECT_EQ(Interval(-2.0, 1.0) * Interval(3.0, kInf), Interval::entire());
  EXPECT_TRUE((Interval::empty() * Interval(1.0)).is_empty());
  EXPECT_TRUE((Interval(1.0) * Interval::empty()).is_empty());
  EXPECT_TRUE(sqr(Interval::empty()).is_empty());
  EXPECT_TRUE((Interval::empty() + Interval(1.0)).is_empty());
  EXPECT_EQ(Interval(kMax) + Interval(kMax), Interval(kMax, kInf));
  EXPECT_EQ(Interval(1.0, kInf) - Interval(-kInf, 2.0), Interval(-1.0, kInf));
}

// Every pair of intervals over the edge values (bounds at zeros, subnormals, 2^-450, 1, the 2^500
// fast range, 1e300, DBL_MAX, infinities), and the empty and whole intervals, bit for bit.
TEST(IntervalFast, EdgeIntervalsMatchTheReferenceBitForBit) {
  const std::vector<Interval> v = edge_intervals();
  std::uint64_t pairs = 0;
  for (const Interval& x : v) {
    ASSERT_TRUE(same(sqr(x), reference::sqr(x))) << str(x);
    ASSERT_TRUE(same(-x, x.is_empty() ? x : Interval(-x.hi(), -x.lo()))) << str(x);
    for (const Interval& y : v) {
      ++pairs;
      ASSERT_TRUE(same(x * y, reference::mul(x, y)))
          << str(x) << " * " << str(y) << " = " << str(x * y) << ", was "
          << str(reference::mul(x, y));
      ASSERT_TRUE(same(x + y, reference::add(x, y))) << str(x) << " + " << str(y);
      ASSERT_TRUE(same(x - y, reference::sub(x, y))) << str(x) << " - " << str(y);
    }
  }
  std::printf("[ measured ] %zu edge intervals, %llu pairs, all bit-identical\n", v.size(),
              static_cast<unsigned long long>(pairs));
}

// ---- Random operands across magnitudes ----------------------------------------------------------

class Draw {
 public:
  explicit Draw(std::uint64_t seed) : rng_(seed) {}

  // A finite double of one of several magnitude classes.
  double bound() {
    const double s = (rng_() & 1U) != 0 ? 1.0 : -1.0;
    switch (pick(12)) {
      case 0:
      case 1:
      case 2:  // ordinary magnitudes, full mantissas
        return s * std::ldexp(mantissa(), pick(81) - 40);
      case 3: {  // every finite double
        for (;;) {
          const std::uint64_t u = rng_();
          double d;
          std::memcpy(&d, &u, sizeof d);
          if (std::isfinite(d)) return d;
        }
      }
      case 4:  // around the fast range's edge
        return s * std::ldexp(mantissa(), pick(41) + 480);
      case 5:  // around 2^-450 (products around the 2^-900 threshold), or around 2^-500 with a
               // short low part (tiny residuals, below 2^-1074 unless scaled)
        if (pick(2) == 0) return s * std::ldexp(mantissa(), -pick(41) - 430);
        return s * std::ldexp(1 + std::ldexp(static_cast<double>(pick(16)), -52), -pick(41) - 480);
      case 6: {  // subnormal
        const std::uint64_t u = (rng_() >> 12) | 1U;
        double d;
        std::memcpy(&d, &u, sizeof d);
        return s * d;
      }
      case 7:
        return 0.0;
      case 8:  // short mantissas: exact products and sums
        return s * std::ldexp(static_cast<double>(pick(1 << 20)), pick(61) - 30);
      case 9:  // huge: overflowing products
        return s * std::ldexp(mantissa(), pick(60) + 964);
      case 10:  // near the smallest normal
        return s * kMinNormal * std::ldexp(mantissa(), pick(4) - 1);
      default:
        return s * std::ldexp(mantissa(), pick(21) - 10);
    }
  }

  Interval operand() {
    const int shape = pick(100);
    if (shape < 25) return Interval(bound());
    if (shape < 50) return sorted(bound(), bound());
    if (shape < 70) {  // narrow: a few ulps
      const double a = bound();
      double b = a;
      for (int i = pick(4); i > 0; --i) b = std::nextafter(b, kInf);
      return Interval(a, b);
    }
    if (shape < 85) return Interval(-std::fabs(bound()), std::fabs(bound()));
    if (shape < 93) {
      const double v = std::fabs(bound());
      return pick(2) == 0 ? Interval(0.0, v) : Interval(-v, 0.0);
    }
    if (shape < 97) return pick(2) == 0 ? Interval(bound(), kInf) : Interval(-kInf, bound());
    if (shape < 99) return Interval::entire();
    return Interval::empty();
  }

 private:
  int pick(int n) { return static_cast<int>(rng_() % static_cast<std::uint64_t>(n)); }
  double mantissa() {  // in [1, 2), a random 52-bit fraction
    return 1.0 + std::ldexp(static_cast<double>(rng_() >> 12), -52);
  }
  static Interval sorted(double a, double b) { return Interval(std::min(a, b), std::max(a, b)); }

  std::mt19937_64 rng_;
};

TEST(IntervalFast, RandomOperandsMatchTheReferenceBitForBit) {
  const auto t0 = std::chrono::steady_clock::now();
  const int pairs = 2'000'000 * scale();
  Draw draw(2024);
  int mismatches = 0;
  int n = 0;
  for (; n < pairs && mismatches < 10; ++n) {
    const Interval x = draw.operand();
    const Interval y = draw.operand();
    if (!same(x * y, reference::mul(x, y))) {
      ++mismatches;
      ADD_FAILURE() << str(x) << " * " << str(y) << " = " << str(x * y) << ", was "
                    << str(reference::mul(x, y));
    }
    if (!same(x + y, reference::add(x, y))) {
      ++mismatches;
      ADD_FAILURE() << str(x) << " + " << str(y) << " = " << str(x + y);
    }
    if (!same(x - y, reference::sub(x, y))) {
      ++mismatches;
      ADD_FAILURE() << str(x) << " - " << str(y) << " = " << str(x - y);
    }
    if (!same(sqr(x), reference::sqr(x))) {
      ++mismatches;
      ADD_FAILURE() << "sqr " << str(x) << " = " << str(sqr(x));
    }
  }
  std::printf(
      "[ measured ] %d random pairs (* + - sqr) against the reference, %d mismatches, "
      "%.2f s\n",
      n, mismatches, seconds_since(t0));
}

// ---- Against MPFR: the bounds are the exact values rounded down and up
// ---------------------------

// 2200 bits hold any sum or product of two finite doubles exactly (exponents -1074 to 1023).
class Exact {
 public:
  Exact() { mpfr_init2(v_, 2200); }
  ~Exact() { mpfr_clear(v_); }
  Exact(const Exact&) = delete;
  Exact& operator=(const Exact&) = delete;
  mpfr_ptr get() { return v_; }
  double down() const { return mpfr_get_d(v_, MPFR_RNDD) + 0.0; }
  double up() const { return mpfr_get_d(v_, MPFR_RNDU) + 0.0; }

 private:
  mpfr_t v_;
};

TEST(IntervalFast, FiniteBoundsAreTheExactValuesRoundedOutward) {
  const auto t0 = std::chrono::steady_clock::now();
  const int pairs = 300'000 * scale();
  Draw draw(99);
  Exact a, b, v;
  int mismatches = 0;
  int checked = 0;
  for (int n = 0; n < pairs && mismatches < 10; ++n) {
    const Interval x = draw.operand();
    const Interval y = draw.operand();
    if (!x.is_bounded() || !y.is_bounded()) continue;
    ++checked;
    // Product: min and max over the corners of the exactly rounded corner products.
    double lo = kInf, hi = -kInf;
    for (double p : {x.lo(), x.hi()}) {
      for (double q : {y.lo(), y.hi()}) {
        mpfr_set_d(a.get(), p, MPFR_RNDN);
        mpfr_set_d(b.get(), q, MPFR_RNDN);
        mpfr_mul(v.get(), a.get(), b.get(), MPFR_RNDN);  // exact at 2200 bits
        lo = std::min(lo, v.down());
        hi = std::max(hi, v.up());
      }
    }
    const Interval r = x * y;
    if (!(r.lo() == lo && r.hi() == hi)) {
      ++mismatches;
      ADD_FAILURE() << str(x) << " * " << str(y) << " = " << str(r) << ", MPFR "
                    << str(Interval(lo, hi));
    }
    // Sum and difference: the exact bound sums rounded outward.
    mpfr_set_d(a.get(), x.lo(), MPFR_RNDN);
    mpfr_set_d(b.get(), y.lo(), MPFR_RNDN);
    mpfr_add(v.get(), a.get(), b.get(), MPFR_RNDN);
    const double slo = v.down();
    mpfr_set_d(a.get(), x.hi(), MPFR_RNDN);
    mpfr_set_d(b.get(), y.hi(), MPFR_RNDN);
    mpfr_add(v.get(), a.get(), b.get(), MPFR_RNDN);
    const double shi = v.up();
    const Interval s = x + y;
    if (!(s.lo() == slo && s.hi() == shi)) {
      ++mismatches;
      ADD_FAILURE() << str(x) << " + " << str(y) << " = " << str(s) << ", MPFR "
                    << str(Interval(slo, shi));
    }
    // sqr: mig^2 rounded down, mag^2 rounded up.
    mpfr_set_d(a.get(), x.mig(), MPFR_RNDN);
    mpfr_sqr(v.get(), a.get(), MPFR_RNDN);
    const double qlo = v.down();
    mpfr_set_d(a.get(), x.mag(), MPFR_RNDN);
    mpfr_sqr(v.get(), a.get(), MPFR_RNDN);
    const double qhi = v.up();
    const Interval q = sqr(x);
    if (!(q.lo() == qlo && q.hi() == qhi)) {
      ++mismatches;
      ADD_FAILURE() << "sqr " << str(x) << " = " << str(q) << ", MPFR " << str(Interval(qlo, qhi));
    }
  }
  std::printf("[ measured ] %d bounded pairs (* + sqr) against MPFR, %d mismatches, %.2f s\n",
              checked, mismatches, seconds_since(t0));
}

}  // namespace
}  // namespace furuta::interval::interval_fast_test
