// Hand-picked cases for every interval operation: exact results where IEEE 754 makes them exact,
// outward rounding where it does not (checked against MPFR), and the edge cases: infinities,
// overflow, underflow and subnormals, signed zeros, 0 * inf, division by intervals containing
// zero, NaN and empty operands, sin/cos extremes. Then the backward operators: contraction on
// examples and soundness on random points.
#include "furuta/interval/interval.hpp"

#include <gtest/gtest.h>
#include <mpfr.h>

#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <string>

namespace furuta::interval::interval_test {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kMax = std::numeric_limits<double>::max();
constexpr double kMinNormal = std::numeric_limits<double>::min();
constexpr double kMinSub = std::numeric_limits<double>::denorm_min();
constexpr double kPi = 3.14159265358979323846;

double up(double x) {
  return std::nextafter(x, kInf);
}
double down(double x) {
  return std::nextafter(x, -kInf);
}

const Interval kEmpty = Interval::empty();
const Interval kEntire = Interval::entire();

std::string str(const Interval& x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

// The exact real value of an MPFR expression at 200 bits lies in x (with directed roundings).
class Exact {
 public:
  Exact() { mpfr_init2(v_, 200); }
  ~Exact() { mpfr_clear(v_); }
  Exact(const Exact&) = delete;
  Exact& operator=(const Exact&) = delete;
  mpfr_ptr get() { return v_; }
  bool in(const Interval& x) const {
    return mpfr_cmp_d(v_, x.lo()) >= 0 && mpfr_cmp_d(v_, x.hi()) <= 0;
  }
  bool strictly_in(const Interval& x) const {
    return mpfr_cmp_d(v_, x.lo()) > 0 && mpfr_cmp_d(v_, x.hi()) < 0;
  }

 private:
  mpfr_t v_;
};

// ---- Construction and predicates ----------------------------------------------------------------

TEST(Interval, DefaultIsTheWholeLine) {
  const Interval x;
  EXPECT_TRUE(x.is_entire());
  EXPECT_EQ(x.lo(), -kInf);
  EXPECT_EQ(x.hi(), kInf);
  EXPECT_FALSE(x.is_bounded());
  EXPECT_TRUE(x.contains(0.0));
  EXPECT_TRUE(x.contains(kMax));
  EXPECT_FALSE(x.contains(kInf));  // intervals are sets of reals
}

TEST(Interval, PointsAndBounds) {
  const Interval p(2.5);
  EXPECT_TRUE(p.is_point());
  EXPECT_EQ(p.lo(), 2.5);
  EXPECT_EQ(p.hi(), 2.5);
  const Interval x(-1.0, 3.0);
  EXPECT_FALSE(x.is_point());
  EXPECT_TRUE(x.is_bounded());
  EXPECT_TRUE(x.contains(-1.0));
  EXPECT_TRUE(x.contains(3.0));
  EXPECT_FALSE(x.contains(up(3.0)));
  EXPECT_FALSE(x.contains(kNaN));
}

TEST(Interval, InvalidBoundsGiveTheEmptyInterval) {
  EXPECT_TRUE(Interval(kNaN).is_empty());
  EXPECT_TRUE(Interval(kNaN, 1.0).is_empty());
  EXPECT_TRUE(Interval(1.0, kNaN).is_empty());
  EXPECT_TRUE(Interval(2.0, 1.0).is_empty());
  EXPECT_TRUE(Interval(kInf).is_empty());
  EXPECT_TRUE(Interval(-kInf).is_empty());
  EXPECT_TRUE(Interval(kInf, kInf).is_empty());
  EXPECT_FALSE(Interval(-kInf, kInf).is_empty());
  EXPECT_FALSE(Interval(1.0, kInf).is_empty());
  EXPECT_EQ(Interval(2.0, 1.0), kEmpty);
  EXPECT_FALSE(kEmpty.is_bounded());
  EXPECT_FALSE(kEmpty.is_point());
  EXPECT_FALSE(kEmpty.is_entire());
  EXPECT_FALSE(kEmpty.contains(0.0));
  EXPECT_FALSE(kEmpty.contains_zero());
}

TEST(Interval, SignedZerosAreOneZero) {
  const Interval z(-0.0, -0.0);
  EXPECT_EQ(z, Interval(0.0));
  EXPECT_FALSE(std::signbit(z.lo()));
  EXPECT_FALSE(std::signbit(z.hi()));
  EXPECT_EQ(str(Interval(-0.0, 1.0)), "[0, 1]");
  EXPECT_EQ(-Interval(0.0, 1.0), Interval(-1.0, 0.0));
  EXPECT_FALSE(std::signbit((-Interval(0.0, 1.0)).hi()));
}

TEST(Interval, PiIsEnclosedByTwoAdjacentDoubles) {
  const Interval pi = Interval::pi();
  EXPECT_EQ(pi.hi(), up(pi.lo()));
  Exact e;
  mpfr_const_pi(e.get(), MPFR_RNDN);
  EXPECT_TRUE(e.strictly_in(pi));
  EXPECT_TRUE(pi.contains(kPi));
}

TEST(Interval, WidthMidRadMagMig) {
  EXPECT_EQ(Interval(1.0, 3.0).width(), 2.0);
  EXPECT_EQ(Interval(1.0, 3.0).mid(), 2.0);
  EXPECT_EQ(Interval(1.0, 3.0).rad(), 1.0);
  EXPECT_EQ(Interval(-0x1p-60, 1.0).width(), up(1.0));  // rounded up
  EXPECT_EQ(kEmpty.width(), 0.0);
  EXPECT_TRUE(std::isnan(kEmpty.mid()));
  EXPECT_EQ(kEmpty.rad(), 0.0);
  EXPECT_TRUE(std::isnan(kEmpty.mag()));
  EXPECT_TRUE(std::isnan(kEmpty.mig()));
  EXPECT_EQ(kEntire.width(), kInf);
  EXPECT_EQ(kEntire.mid(), 0.0);
  EXPECT_EQ(kEntire.rad(), kInf);
  EXPECT_EQ(Interval(1.0, kInf).mid(), kMax);
  EXPECT_EQ(Interval(-kInf, 1.0).mid(), -kMax);
  EXPECT_EQ(Interval(-kMax, kMax).width(), kInf);  // overflows upward
  EXPECT_EQ(Interval(-kMax, kMax).mid(), 0.0);
  EXPECT_EQ(Interval(kMax / 2, kMax).mid(), 0.75 * kMax);  // no overflow
  EXPECT_TRUE(Interval(kMinSub, 2 * kMinSub).contains(Interval(kMinSub, 2 * kMinSub).mid()));
  EXPECT_EQ(Interval(5.0).width(), 0.0);
  EXPECT_EQ(Interval(5.0).mid(), 5.0);
  // rad bounds the distance from mid to either bound.
  const Interval odd(0.1, 0.7);
  EXPECT_GE(odd.mid() + odd.rad(), 0.7);
  EXPECT_LE(odd.mid() - odd.rad(), 0.1);
  EXPECT_EQ(Interval(-3.0, 2.0).mag(), 3.0);
  EXPECT_EQ(Interval(-3.0, 2.0).mig(), 0.0);
  EXPECT_EQ(Interval(-3.0, -2.0).mig(), 2.0);
  EXPECT_EQ(Interval(2.0, 5.0).mig(), 2.0);
  EXPECT_EQ(Interval(-kInf, -2.0).mag(), kInf);
}

TEST(Interval, SubsetsAndIntersections) {
  const Interval a(1.0, 4.0);
  EXPECT_TRUE(Interval(2.0, 3.0).is_subset(a));
  EXPECT_TRUE(a.is_subset(a));
  EXPECT_FALSE(a.is_interior_subset(a));
  EXPECT_TRUE(Interval(2.0, 3.0).is_interior_subset(a));
  EXPECT_FALSE(Interval(1.0, 3.0).is_interior_subset(a));
  EXPECT_TRUE(Interval(1.0, kInf).is_interior_subset(Interval(0.0, kInf)));
  EXPECT_TRUE(kEntire.is_interior_subset(kEntire));  // the interior of R is R
  EXPECT_TRUE(kEmpty.is_subset(a));
  EXPECT_TRUE(kEmpty.is_subset(kEmpty));
  EXPECT_TRUE(kEmpty.is_interior_subset(a));
  EXPECT_FALSE(a.is_subset(kEmpty));
  EXPECT_TRUE(a.intersects(Interval(4.0, 5.0)));  // closed: touching counts
  EXPECT_FALSE(a.intersects(Interval(up(4.0), 5.0)));
  EXPECT_TRUE(a.is_disjoint(Interval(up(4.0), 5.0)));
  EXPECT_FALSE(a.intersects(kEmpty));
  EXPECT_EQ(intersect(a, Interval(3.0, 9.0)), Interval(3.0, 4.0));
  EXPECT_EQ(a & Interval(4.0, 9.0), Interval(4.0));
  EXPECT_TRUE((a & Interval(5.0, 9.0)).is_empty());
  EXPECT_TRUE((a & kEmpty).is_empty());
  EXPECT_EQ(hull(a, Interval(7.0)), Interval(1.0, 7.0));
  EXPECT_EQ(a | kEmpty, a);
  EXPECT_EQ(kEmpty | a, a);
  EXPECT_TRUE((kEmpty | kEmpty).is_empty());
}

TEST(Interval, BisectSplitsAtTheRatio) {
  const auto [l, r] = Interval(0.0, 8.0).bisect();
  EXPECT_EQ(l, Interval(0.0, 4.0));
  EXPECT_EQ(r, Interval(4.0, 8.0));
  const auto [l2, r2] = Interval(0.0, 8.0).bisect(0.25);
  EXPECT_EQ(l2, Interval(0.0, 2.0));
  EXPECT_EQ(r2, Interval(2.0, 8.0));
  // Out-of-range ratios fall back to 0.5.
  EXPECT_EQ(Interval(0.0, 8.0).bisect(1.5).first, Interval(0.0, 4.0));
  EXPECT_EQ(Interval(0.0, 8.0).bisect(kNaN).first, Interval(0.0, 4.0));
  // No overflow on the widest finite interval.
  const auto [l3, r3] = Interval(-kMax, kMax).bisect();
  EXPECT_EQ(l3.hi(), 0.0);
  EXPECT_EQ(r3.lo(), 0.0);
  // Two adjacent doubles: halves are the lower point and the whole (nothing in between).
  const auto [l4, r4] = Interval(1.0, up(1.0)).bisect();
  EXPECT_EQ(hull(l4, r4), Interval(1.0, up(1.0)));
  // Three doubles: both halves strictly smaller.
  const auto [l5, r5] = Interval(1.0, up(up(1.0))).bisect(1e-30);
  EXPECT_EQ(l5, Interval(1.0, up(1.0)));
  EXPECT_EQ(r5, Interval(up(1.0), up(up(1.0))));
  const auto [l6, r6] = kEntire.bisect();
  EXPECT_EQ(l6, Interval(-kInf, 0.0));
  EXPECT_EQ(r6, Interval(0.0, kInf));
  const auto [l7, r7] = Interval(3.0).bisect();
  EXPECT_EQ(l7, Interval(3.0));
  EXPECT_EQ(r7, Interval(3.0));
  EXPECT_TRUE(kEmpty.bisect().first.is_empty());
  EXPECT_TRUE(kEmpty.bisect().second.is_empty());
}

TEST(Interval, PrintsRoundTripDigits) {
  EXPECT_EQ(str(Interval(1.0, 2.0)), "[1, 2]");
  EXPECT_EQ(str(kEmpty), "[empty]");
  EXPECT_EQ(str(kEntire), "[-inf, inf]");
  EXPECT_EQ(str(Interval(0.1)), "[0.10000000000000001, 0.10000000000000001]");
  const Interval x = Interval(0.1) + Interval(0.2);
  std::istringstream in(str(x).substr(1));
  double lo = 0, hi = 0;
  char comma = 0;
  in >> lo >> comma >> hi;
  EXPECT_EQ(lo, x.lo());
  EXPECT_EQ(hi, x.hi());
  // The stream's own precision is untouched.
  std::ostringstream s;
  s << Interval(1.0 / 3) << ' ' << 1.0 / 3;
  EXPECT_EQ(s.str(), "[0.33333333333333331, 0.33333333333333331] 0.333333");
}

// ---- Arithmetic ---------------------------------------------------------------------------------

TEST(IntervalArithmetic, ExactWhereIeeeIsExact) {
  EXPECT_EQ(Interval(1.0, 2.0) + Interval(3.0, 4.0), Interval(4.0, 6.0));
  EXPECT_EQ(Interval(1.0, 2.0) - Interval(3.0, 4.0), Interval(-3.0, -1.0));
  EXPECT_EQ(Interval(1.0, 2.0) * Interval(3.0, 4.0), Interval(3.0, 8.0));
  EXPECT_EQ(Interval(-1.0, 2.0) * Interval(3.0, 4.0), Interval(-4.0, 8.0));
  EXPECT_EQ(Interval(-1.0, 2.0) * Interval(-3.0, 4.0), Interval(-6.0, 8.0));
  EXPECT_EQ(Interval(1.0, 2.0) / Interval(4.0, 8.0), Interval(0.125, 0.5));
  EXPECT_EQ(Interval(-2.0, 1.0) / Interval(-4.0, -2.0), Interval(-0.5, 1.0));
  EXPECT_EQ(-Interval(1.0, 2.0), Interval(-2.0, -1.0));
  // Subnormal sums are exact.
  EXPECT_EQ(Interval(kMinSub) + Interval(kMinSub), Interval(2 * kMinSub));
  EXPECT_EQ(Interval(kMinNormal) - Interval(kMinSub), Interval(kMinNormal - kMinSub));
  Interval a(1.0, 2.0);
  a += Interval(1.0);
  a *= Interval(2.0);
  a -= Interval(1.0);
  a /= Interval(2.0);
  EXPECT_EQ(a, Interval(1.5, 2.5));
}

TEST(IntervalArithmetic, InexactResultsAreOneUlpWideAndContainTheExactValue) {
  const Interval s = Interval(0.1) + Interval(0.2);
  EXPECT_LT(s.lo(), s.hi());
  EXPECT_EQ(s.hi(), up(s.lo()));
  Exact e;
  mpfr_set_d(e.get(), 0.1, MPFR_RNDN);
  mpfr_add_d(e.get(), e.get(), 0.2, MPFR_RNDN);  // exact at 200 bits
  EXPECT_TRUE(e.strictly_in(s));
  EXPECT_TRUE(s.contains(0.1 + 0.2));

  const Interval third = Interval(1.0) / Interval(3.0);
  EXPECT_EQ(third.hi(), up(third.lo()));
  mpfr_set_d(e.get(), 1.0, MPFR_RNDN);
  mpfr_div_d(e.get(), e.get(), 3.0, MPFR_RNDN);
  EXPECT_TRUE(e.strictly_in(third));

  const Interval p = Interval(0.1) * Interval(0.1);
  EXPECT_EQ(p.hi(), up(p.lo()));
  mpfr_set_d(e.get(), 0.1, MPFR_RNDN);
  mpfr_mul_d(e.get(), e.get(), 0.1, MPFR_RNDN);
  EXPECT_TRUE(e.strictly_in(p));

  const Interval r = sqrt(Interval(2.0));
  EXPECT_EQ(r.hi(), up(r.lo()));
  mpfr_sqrt_ui(e.get(), 2, MPFR_RNDN);
  EXPECT_TRUE(e.strictly_in(r));

  // 1 + 2^-60: the sum rounds to 1, the enclosure steps up only.
  const Interval t = Interval(1.0) + Interval(0x1p-60);
  EXPECT_EQ(t, Interval(1.0, up(1.0)));
  const Interval u = Interval(1.0) - Interval(0x1p-60);
  EXPECT_EQ(u, Interval(down(1.0), 1.0));
}

TEST(IntervalArithmetic, OverflowGivesAnInfiniteBoundOnTheRightSide) {
  EXPECT_EQ(Interval(kMax) + Interval(kMax), Interval(kMax, kInf));
  EXPECT_EQ(Interval(-kMax) - Interval(kMax), Interval(-kInf, -kMax));
  EXPECT_EQ(Interval(1e300) * Interval(1e300), Interval(kMax, kInf));
  EXPECT_EQ(Interval(-1e300) * Interval(1e300), Interval(-kInf, -kMax));
  EXPECT_EQ(Interval(1e300) / Interval(1e-300), Interval(kMax, kInf));
  EXPECT_EQ(Interval(1e300) / Interval(-1e-300), Interval(-kInf, -kMax));
  EXPECT_EQ(sqr(Interval(-1e200)), Interval(kMax, kInf));
  EXPECT_EQ(pow(Interval(1e100), 4), Interval(kMax, kInf));
  // Rounded up to exactly DBL_MAX is not an overflow: DBL_MAX + half an ulp rounds to inf.
  const Interval edge = Interval(kMax) + Interval(std::ldexp(1.0, 970));
  EXPECT_EQ(edge, Interval(kMax, kInf));
}

TEST(IntervalArithmetic, UnderflowKeepsTheSign) {
  EXPECT_EQ(Interval(1e-300) * Interval(1e-300), Interval(0.0, kMinSub));
  EXPECT_EQ(Interval(-1e-300) * Interval(1e-300), Interval(-kMinSub, 0.0));
  EXPECT_EQ(Interval(1e-300) / Interval(1e300), Interval(0.0, kMinSub));
  EXPECT_EQ(Interval(kMinSub) * Interval(0.5), Interval(0.0, kMinSub));
  EXPECT_EQ(Interval(kMinSub) * Interval(2.0), Interval(2 * kMinSub));  // exact
  EXPECT_EQ(Interval(kMinSub) / Interval(2.0), Interval(0.0, kMinSub));
  EXPECT_EQ(sqr(Interval(1e-200)), Interval(0.0, kMinSub));
  const Interval s = sqrt(Interval(kMinSub));
  Exact e;
  mpfr_set_d(e.get(), kMinSub, MPFR_RNDN);
  mpfr_sqrt(e.get(), e.get(), MPFR_RNDN);
  EXPECT_TRUE(e.in(s));
}

TEST(IntervalArithmetic, InfiniteBounds) {
  EXPECT_EQ(Interval(1.0, kInf) + Interval(1.0), Interval(2.0, kInf));
  EXPECT_EQ(Interval(-kInf, 1.0) - Interval(-kInf, 2.0), kEntire);
  EXPECT_EQ(Interval(1.0, kInf) - Interval(1.0, kInf), kEntire);
  EXPECT_EQ(Interval(1.0, kInf) * Interval(2.0, 3.0), Interval(2.0, kInf));
  EXPECT_EQ(Interval(1.0, kInf) * Interval(-3.0, -2.0), Interval(-kInf, -2.0));
  EXPECT_EQ(Interval(1.0, 2.0) * kEntire, kEntire);
  EXPECT_EQ(Interval(1.0, kInf) / Interval(1.0, kInf), Interval(0.0, kInf));
  EXPECT_EQ(Interval(1.0, 2.0) / Interval(-kInf, -1.0), Interval(-2.0, 0.0));
  EXPECT_EQ(kEntire + kEntire, kEntire);
  EXPECT_EQ(sqrt(Interval(4.0, kInf)), Interval(2.0, kInf));
}

TEST(IntervalArithmetic, ZeroTimesInfinityIsZeroForSets) {
  EXPECT_EQ(Interval(0.0) * kEntire, Interval(0.0));
  EXPECT_EQ(kEntire * Interval(0.0), Interval(0.0));
  EXPECT_EQ(Interval(0.0, 1.0) * Interval(1.0, kInf), Interval(0.0, kInf));
  EXPECT_EQ(Interval(-1.0, 0.0) * Interval(-kInf, 0.0), Interval(0.0, kInf));
  EXPECT_EQ(Interval(0.0) * Interval(-kInf, 5.0), Interval(0.0));
  EXPECT_EQ(Interval(0.0) / Interval(-kInf, -1.0), Interval(0.0));
}

TEST(IntervalArithmetic, DivisionByIntervalsContainingZero) {
  EXPECT_TRUE((Interval(1.0, 2.0) / Interval(0.0)).is_empty());
  EXPECT_TRUE((Interval(-1.0, 2.0) / Interval(0.0)).is_empty());
  EXPECT_TRUE((Interval(0.0) / Interval(0.0)).is_empty());
  EXPECT_EQ(Interval(1.0, 2.0) / Interval(-1.0, 1.0), kEntire);  // hull of the two pieces
  EXPECT_EQ(Interval(0.0, 2.0) / Interval(-1.0, 1.0), kEntire);
  EXPECT_EQ(Interval(0.0, 1.0) / Interval(0.0, 1.0), kEntire);
  EXPECT_EQ(Interval(1.0, 2.0) / Interval(0.0, 1.0), Interval(1.0, kInf));
  EXPECT_EQ(Interval(1.0, 2.0) / Interval(0.0, 4.0), Interval(0.25, kInf));
  EXPECT_EQ(Interval(-2.0, -1.0) / Interval(0.0, 4.0), Interval(-kInf, -0.25));
  EXPECT_EQ(Interval(1.0, 2.0) / Interval(-4.0, 0.0), Interval(-kInf, -0.25));
  EXPECT_EQ(Interval(-2.0, -1.0) / Interval(-4.0, 0.0), Interval(0.25, kInf));
  EXPECT_EQ(Interval(0.0) / Interval(1.0, 2.0), Interval(0.0));
  EXPECT_EQ(Interval(1.0, 2.0) / Interval(0.0, kInf), Interval(0.0, kInf));
}

TEST(IntervalArithmetic, EmptyAndNaNOperandsGiveEmpty) {
  const Interval x(1.0, 2.0);
  const Interval nan(kNaN);
  for (const Interval& e : {kEmpty, nan}) {
    EXPECT_TRUE((x + e).is_empty());
    EXPECT_TRUE((e - x).is_empty());
    EXPECT_TRUE((x * e).is_empty());
    EXPECT_TRUE((e * Interval(0.0)).is_empty());
    EXPECT_TRUE((x / e).is_empty());
    EXPECT_TRUE((e / x).is_empty());
    EXPECT_TRUE((-e).is_empty());
    EXPECT_TRUE(sqr(e).is_empty());
    EXPECT_TRUE(sqrt(e).is_empty());
    EXPECT_TRUE(abs(e).is_empty());
    EXPECT_TRUE(pow(e, 0).is_empty());
    EXPECT_TRUE(pow(e, 3).is_empty());
    EXPECT_TRUE(sin(e).is_empty());
    EXPECT_TRUE(cos(e).is_empty());
  }
}

// ---- Elementary functions ----------------------------------------------------------------------

TEST(IntervalFunctions, SqrAndEvenPowersAreTight) {
  EXPECT_EQ(sqr(Interval(-1.0, 2.0)), Interval(0.0, 4.0));
  EXPECT_EQ(sqr(Interval(-3.0, -2.0)), Interval(4.0, 9.0));
  EXPECT_EQ(sqr(Interval(2.0, 3.0)), Interval(4.0, 9.0));
  EXPECT_EQ(sqr(kEntire), Interval(0.0, kInf));
  EXPECT_EQ(sqr(Interval(-kInf, -2.0)), Interval(4.0, kInf));
  EXPECT_EQ(pow(Interval(-2.0, 1.0), 2), Interval(0.0, 4.0));
  EXPECT_EQ(pow(Interval(-1.0, 2.0), 4), Interval(0.0, 16.0));
  EXPECT_EQ(pow(Interval(-3.0, -2.0), 4), Interval(16.0, 81.0));
  EXPECT_EQ(pow(Interval(-2.0, 1.0), 3), Interval(-8.0, 1.0));
  EXPECT_EQ(pow(Interval(-3.0, -2.0), 5), Interval(-243.0, -32.0));
  EXPECT_EQ(pow(Interval(-2.0, 1.0), 1), Interval(-2.0, 1.0));
  EXPECT_EQ(pow(Interval(-2.0, 1.0), 0), Interval(1.0));
  EXPECT_EQ(pow(Interval(0.0), 0), Interval(1.0));
  EXPECT_EQ(pow(Interval(2.0), 60), Interval(0x1p60));
  // Negative exponents (outside the contract) are enclosed through the division.
  EXPECT_EQ(pow(Interval(2.0, 4.0), -1), Interval(0.25, 0.5));
  const Interval p = pow(Interval(0.1), 5);
  Exact e;
  mpfr_set_d(e.get(), 0.1, MPFR_RNDN);
  mpfr_pow_ui(e.get(), e.get(), 5, MPFR_RNDN);
  EXPECT_TRUE(e.in(p));
  EXPECT_LE(p.width(), 8 * (up(p.lo()) - p.lo()));
}

TEST(IntervalFunctions, SqrtOfTheNonNegativePart) {
  EXPECT_EQ(sqrt(Interval(4.0, 9.0)), Interval(2.0, 3.0));
  EXPECT_EQ(sqrt(Interval(-4.0, 4.0)), Interval(0.0, 2.0));
  EXPECT_EQ(sqrt(Interval(-4.0, 0.0)), Interval(0.0));
  EXPECT_TRUE(sqrt(Interval(-4.0, -1.0)).is_empty());
  EXPECT_EQ(sqrt(kEntire), Interval(0.0, kInf));
}

TEST(IntervalFunctions, Abs) {
  EXPECT_EQ(abs(Interval(-3.0, 2.0)), Interval(0.0, 3.0));
  EXPECT_EQ(abs(Interval(-3.0, -2.0)), Interval(2.0, 3.0));
  EXPECT_EQ(abs(Interval(2.0, 3.0)), Interval(2.0, 3.0));
  EXPECT_EQ(abs(Interval(-kInf, 1.0)), Interval(0.0, kInf));
}

TEST(IntervalFunctions, SinAndCosExactAtZero) {
  EXPECT_EQ(sin(Interval(0.0)), Interval(0.0));
  EXPECT_EQ(cos(Interval(0.0)), Interval(1.0));
  EXPECT_EQ(cos(Interval(-0.1, 0.1)).hi(), 1.0);
  EXPECT_LT(cos(Interval(-0.1, 0.1)).lo(), std::cos(0.1));
}

TEST(IntervalFunctions, SinAndCosOverWideIntervalsAreTheUnitInterval) {
  const Interval unit(-1.0, 1.0);
  EXPECT_EQ(sin(Interval(-10.0, 10.0)), unit);
  EXPECT_EQ(cos(Interval(-10.0, 10.0)), unit);
  EXPECT_EQ(sin(Interval(0.0, 2 * kPi)), unit);
  EXPECT_EQ(sin(Interval(1e6, 2e6)), unit);
  EXPECT_EQ(sin(kEntire), unit);
  EXPECT_EQ(cos(Interval(0.0, kInf)), unit);
  EXPECT_EQ(sin(Interval(1e300)), unit);  // beyond 2^40: [-1, 1], sound and simple
  EXPECT_EQ(cos(Interval(-1e20)), unit);
  // Width just under 2 pi still reaches both extremes when it straddles them.
  EXPECT_EQ(sin(Interval(1.0, 1.0 + 6.2)), unit);
}

TEST(IntervalFunctions, SinAndCosFindTheExtremesInside) {
  // [0, pi]: the maximum 1 at pi/2, the minimum near 0 at the ends.
  const Interval s = sin(Interval(0.0, kPi));
  EXPECT_EQ(s.hi(), 1.0);
  EXPECT_LE(s.lo(), 0.0);
  EXPECT_GT(s.lo(), -1e-15);
  // cos over [3, 3.2] contains pi: its minimum -1.
  const Interval c = cos(Interval(3.0, 3.2));
  EXPECT_EQ(c.lo(), -1.0);
  EXPECT_GE(c.hi(), std::cos(3.2));
  EXPECT_LT(c.hi(), -0.98);
  // Around 3pi/2 + 2pi * 1e5: the minimum of sin.
  const double x = 1.5 * kPi + 2 * kPi * 1e5;
  EXPECT_EQ(sin(Interval(x - 1e-3, x + 1e-3)).lo(), -1.0);
  EXPECT_GT(sin(Interval(x - 1e-3, x + 1e-3)).hi(), -1.0);
  // At the double nearest pi/2 (below pi/2) the enclosure keeps 1.
  EXPECT_EQ(sin(Interval(kPi / 2)).hi(), 1.0);
  EXPECT_EQ(cos(Interval(kPi)).lo(), -1.0);
}

TEST(IntervalFunctions, SinAndCosWithoutExtremesAreTheEndpointEnclosures) {
  const Interval s = sin(Interval(0.1, 0.2));
  EXPECT_LE(s.lo(), std::sin(0.1));
  EXPECT_GE(s.hi(), std::sin(0.2));
  EXPECT_LT(s.hi(), 0.2);
  EXPECT_LE(s.width(), std::sin(0.2) - std::sin(0.1) + 1e-15);
  const Interval c = cos(Interval(1.0, 2.0));
  EXPECT_LE(c.lo(), std::cos(2.0));
  EXPECT_GE(c.hi(), std::cos(1.0));
  EXPECT_LT(c.hi(), 0.55);
  EXPECT_GT(c.lo(), -0.42);
  // Narrow intervals far out stay narrow.
  const Interval far = sin(Interval(1e9, 1e9 + 1e-6));
  EXPECT_LT(far.width(), 2e-6);
  // Tiny arguments: sin x is just below x; the enclosure contains it.
  const Interval tiny = sin(Interval(1e-300));
  EXPECT_TRUE(tiny.contains(1e-300));
  EXPECT_LT(tiny.width(), 1e-313);
  Exact e;
  mpfr_set_d(e.get(), 1e-300, MPFR_RNDN);
  mpfr_sin(e.get(), e.get(), MPFR_RNDN);
  EXPECT_TRUE(e.in(tiny));
}

TEST(IntervalFunctions, SinAndCosOfPointsAreAFewUlpsWide) {
  for (const double x : {0.5, 1.0, 2.0, 3.0, 10.0, 100.0, 12345.678, -7.25}) {
    const Interval s = sin(Interval(x));
    const Interval c = cos(Interval(x));
    EXPECT_TRUE(s.contains(std::sin(x))) << x;
    EXPECT_TRUE(c.contains(std::cos(x))) << x;
    EXPECT_LE(s.width(), 8 * std::fabs(up(std::sin(x)) - std::sin(x))) << x;
    EXPECT_LE(c.width(), 8 * std::fabs(up(std::cos(x)) - std::cos(x))) << x;
  }
}

// ---- Backward operators: contraction -----------------------------------------------------------

TEST(IntervalBackward, AddContracts) {
  Interval x1(0.0, 10.0), x2(0.0, 0.5);
  bwd_add(Interval(1.0, 2.0), x1, x2);
  EXPECT_EQ(x1, Interval(0.5, 2.0));
  EXPECT_EQ(x2, Interval(0.0, 0.5));
  Interval a(0.0, 1.0), b(0.0, 1.0);
  bwd_add(Interval(5.0, 6.0), a, b);
  EXPECT_TRUE(a.is_empty());
  EXPECT_TRUE(b.is_empty());
  Interval c(1.0, 2.0), d;
  bwd_add(Interval(3.0), c, d);
  EXPECT_EQ(d, Interval(1.0, 2.0));
}

TEST(IntervalBackward, SubContracts) {
  Interval x1(0.0, 10.0), x2(0.0, 0.5);
  bwd_sub(Interval(1.0, 2.0), x1, x2);  // x1 - x2 in [1, 2]
  EXPECT_EQ(x1, Interval(1.0, 2.5));
  EXPECT_EQ(x2, Interval(0.0, 0.5));
  Interval a(0.0, 10.0), b(0.0, 10.0);
  bwd_sub(Interval(9.0, 20.0), a, b);
  EXPECT_EQ(a, Interval(9.0, 10.0));
  EXPECT_EQ(b, Interval(0.0, 1.0));
}

TEST(IntervalBackward, MulContracts) {
  Interval x1(-10.0, 10.0), x2(1.0, 2.0);
  bwd_mul(Interval(2.0, 4.0), x1, x2);
  EXPECT_EQ(x1, Interval(1.0, 4.0));
  EXPECT_EQ(x2, Interval(1.0, 2.0));
  // x2 touches 0: the extended division gives a half-line.
  Interval a(-10.0, 10.0), b(0.0, 2.0);
  bwd_mul(Interval(1.0, 2.0), a, b);
  EXPECT_EQ(a, Interval(0.5, 10.0));
  EXPECT_EQ(b.hi(), 2.0);  // [1, 2] / [0.5, 10] = [0.1, 4], 0.1 rounded down
  EXPECT_EQ(b.lo(), down(0.1));
  // y = 0 forces the other factor to 0 when one cannot be.
  Interval c(1.0, 2.0), d(-1.0, 1.0);
  bwd_mul(Interval(0.0), c, d);
  EXPECT_EQ(c, Interval(1.0, 2.0));
  EXPECT_EQ(d, Interval(0.0));
  // x2 = 0 cannot give y != 0.
  Interval e(-1.0, 1.0), f(0.0);
  bwd_mul(Interval(1.0, 2.0), e, f);
  EXPECT_TRUE(e.is_empty());
  EXPECT_TRUE(f.is_empty());
}

TEST(IntervalBackward, MulLeavesArgumentsWhenZeroMakesEverythingConsistent) {
  Interval x1(-10.0, 10.0), x2(-1.0, 1.0);
  bwd_mul(Interval(1.0, 2.0), x1, x2);  // y / x2 is the whole line
  EXPECT_EQ(x1, Interval(-10.0, 10.0));
  EXPECT_EQ(x2, Interval(-1.0, 1.0));
  Interval a(-10.0, 10.0), b(-1.0, 1.0);
  bwd_mul(Interval(-1.0, 1.0), a, b);
  EXPECT_EQ(a, Interval(-10.0, 10.0));
  EXPECT_EQ(b, Interval(-1.0, 1.0));
  Interval c(5.0, 6.0), d(0.0);
  bwd_mul(Interval(0.0), c, d);  // 5 * 0 = 0
  EXPECT_EQ(c, Interval(5.0, 6.0));
  EXPECT_EQ(d, Interval(0.0));
}

TEST(IntervalBackward, DivContracts) {
  Interval x1(-10.0, 10.0), x2(1.0, 2.0);
  bwd_div(Interval(1.0, 2.0), x1, x2);
  EXPECT_EQ(x1, Interval(1.0, 4.0));
  EXPECT_EQ(x2, Interval(1.0, 2.0));
  Interval a(1.0, 8.0), b(-10.0, 10.0);
  bwd_div(Interval(2.0, 4.0), a, b);  // b = a / y in [0.25, 4]
  EXPECT_EQ(a, Interval(1.0, 8.0));
  EXPECT_EQ(b, Interval(0.25, 4.0));
  // y = 0 forces x1 = 0, x2 stays (any non-zero x2).
  Interval c(-1.0, 1.0), d(1.0, 2.0);
  bwd_div(Interval(0.0), c, d);
  EXPECT_EQ(c, Interval(0.0));
  EXPECT_EQ(d, Interval(1.0, 2.0));
  Interval e(1.0, 2.0), f(1.0, 2.0);
  bwd_div(Interval(10.0, 20.0), e, f);
  EXPECT_TRUE(e.is_empty());
  EXPECT_TRUE(f.is_empty());
}

TEST(IntervalBackward, NegAndSqr) {
  Interval x(-10.0, 10.0);
  bwd_neg(Interval(1.0, 2.0), x);
  EXPECT_EQ(x, Interval(-2.0, -1.0));
  Interval s(-10.0, 1.0);
  bwd_sqr(Interval(4.0, 9.0), s);
  EXPECT_EQ(s, Interval(-3.0, -2.0));
  Interval t(-10.0, 10.0);
  bwd_sqr(Interval(4.0, 9.0), t);
  EXPECT_EQ(t, Interval(-3.0, 3.0));  // the hull of the two branches
  Interval u(-10.0, 10.0);
  bwd_sqr(Interval(-2.0, -1.0), u);
  EXPECT_TRUE(u.is_empty());
  Interval v(-10.0, 10.0);
  bwd_sqr(Interval(-2.0, 4.0), v);
  EXPECT_EQ(v, Interval(-2.0, 2.0));
  Interval w(2.5, 10.0);
  bwd_sqr(Interval(1.0, 4.0), w);
  EXPECT_TRUE(w.is_empty());
}

TEST(IntervalBackward, SinProjectsOntoArcsinBranches) {
  Interval x(-1.0, 1.0);
  bwd_sin(Interval(2.0, 3.0), x);
  EXPECT_TRUE(x.is_empty());
  // sin x in [0.5, 1] on [0, 10]: x in [pi/6, 5pi/6] or [pi/6 + 2pi, 5pi/6 + 2pi].
  Interval y(0.0, 10.0);
  bwd_sin(Interval(0.5, 1.0), y);
  EXPECT_LE(y.lo(), kPi / 6);
  EXPECT_GT(y.lo(), kPi / 6 - 1e-12);
  EXPECT_GE(y.hi(), 5 * kPi / 6 + 2 * kPi);
  EXPECT_LT(y.hi(), 5 * kPi / 6 + 2 * kPi + 1e-12);
  // Only the falling branch inside [2, 4].
  Interval z(2.0, 4.0);
  bwd_sin(Interval(0.5, 1.0), z);
  EXPECT_EQ(z.lo(), 2.0);
  EXPECT_GE(z.hi(), 5 * kPi / 6);
  EXPECT_LT(z.hi(), 5 * kPi / 6 + 1e-12);
  // Nothing to remove when y covers [-1, 1].
  Interval w(0.0, 10.0);
  bwd_sin(Interval(-5.0, 5.0), w);
  EXPECT_EQ(w, Interval(0.0, 10.0));
  // Unbounded x: left as it is.
  Interval u;
  bwd_sin(Interval(0.5, 1.0), u);
  EXPECT_TRUE(u.is_entire());
  // sin over x misses y: empty.
  Interval v(0.1, 0.2);
  bwd_sin(Interval(0.5, 1.0), v);
  EXPECT_TRUE(v.is_empty());
}

TEST(IntervalBackward, CosProjectsOntoArccosBranches) {
  Interval x(-1.0, 7.0);
  bwd_cos(Interval(1.0), x);  // x in {0, 2pi}
  EXPECT_LE(x.lo(), 0.0);
  EXPECT_GT(x.lo(), -1e-7);
  EXPECT_GE(x.hi(), 2 * kPi);
  EXPECT_LT(x.hi(), 2 * kPi + 1e-7);
  Interval y(1.5, 3.0);
  bwd_cos(Interval(0.5, 1.0), y);
  EXPECT_TRUE(y.is_empty());
  Interval z(-1.0, 1.0);
  bwd_cos(Interval(-3.0, -2.0), z);
  EXPECT_TRUE(z.is_empty());
  // cos x in [-1, -0.5] on [0, 4]: x in [2pi/3, 4].
  Interval w(0.0, 4.0);
  bwd_cos(Interval(-1.0, -0.5), w);
  EXPECT_LE(w.lo(), 2 * kPi / 3);
  EXPECT_GT(w.lo(), 2 * kPi / 3 - 1e-12);
  EXPECT_EQ(w.hi(), 4.0);
}

// ---- Backward operators: soundness on random points (forward enclosures as y) -------------------

TEST(IntervalBackward, RandomPointsSurvive) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  std::uniform_real_distribution<double> w(0.0, 3.0);
  auto around = [&](double p) { return Interval(p - w(rng), p + w(rng)); };
  int kept = 0;
  for (int n = 0; n < 20'000; ++n) {
    const double p1 = u(rng), p2 = u(rng);
    const Interval P1(p1), P2(p2);
    struct Case {
      const char* name;
      void (*bwd)(const Interval&, Interval&, Interval&);
      Interval y;
    };
    const Case cases[] = {{"add", bwd_add, P1 + P2},
                          {"sub", bwd_sub, P1 - P2},
                          {"mul", bwd_mul, P1 * P2},
                          {"div", bwd_div, P1 / P2}};
    for (const Case& c : cases) {
      Interval x1 = around(p1), x2 = around(p2);
      c.bwd(c.y, x1, x2);
      ASSERT_TRUE(x1.contains(p1) && x2.contains(p2))
          << c.name << " y = " << c.y << " lost " << p1 << ", " << p2;
      ++kept;
    }
    Interval x = around(p1);
    bwd_sqr(sqr(P1), x);
    ASSERT_TRUE(x.contains(p1)) << "sqr " << p1;
    x = around(p1);
    bwd_neg(-P1, x);
    ASSERT_TRUE(x.contains(p1)) << "neg " << p1;
    x = around(p1);
    bwd_sin(sin(P1), x);
    ASSERT_TRUE(x.contains(p1)) << "sin " << p1;
    x = around(p1);
    bwd_cos(cos(P1), x);
    ASSERT_TRUE(x.contains(p1)) << "cos " << p1;
  }
  EXPECT_EQ(kept, 80'000);
}

TEST(IntervalBackward, EmptyInputsGiveEmpty) {
  Interval x1(1.0, 2.0), x2 = kEmpty;
  bwd_add(Interval(1.0), x1, x2);
  EXPECT_TRUE(x1.is_empty());
  Interval a(1.0, 2.0), b(1.0, 2.0);
  bwd_mul(kEmpty, a, b);
  EXPECT_TRUE(a.is_empty());
  EXPECT_TRUE(b.is_empty());
  Interval s(1.0, 2.0);
  bwd_sin(kEmpty, s);
  EXPECT_TRUE(s.is_empty());
  Interval c = kEmpty;
  bwd_cos(Interval(0.5), c);
  EXPECT_TRUE(c.is_empty());
}

}  // namespace
}  // namespace furuta::interval::interval_test
