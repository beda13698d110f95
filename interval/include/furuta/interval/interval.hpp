#pragma once
// Closed real intervals [lo, hi] with guaranteed outward rounding, the operations the Furuta model
// needs, and their backward (projection) forms for forward-backward contractors.
//
// Every operation returns an interval that contains the exact real result for every choice of
// arguments inside the operands: that is the only promise, and the test suite checks it against
// MPFR. The empty interval is a value (an empty operand gives an empty result), never a crash.
// Intervals are sets of reals (IEEE 1788 set-based): infinite bounds are allowed, infinite points
// are not. The empty interval has lo() = +inf and hi() = -inf. See interval/README.md.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <iosfwd>
#include <limits>
#include <utility>

namespace furuta::interval {

class Interval {
 public:
  // The whole real line, like Codac/IBEX: an unknown with no prior.
  Interval() : lo_(-kInf), hi_(kInf) {}
  // The point [x, x]; NaN (or an infinity, not a real) gives the empty interval.
  Interval(double x) : Interval(x, x) {}  // NOLINT(google-explicit-constructor): points mix freely
  // [lo, hi]; lo > hi or a NaN bound gives the empty interval.
  Interval(double lo, double hi) : lo_(lo + 0.0), hi_(hi + 0.0) {
    // Intervals are sets of reals: a NaN bound, lo > hi, lo = +inf or hi = -inf is the empty set.
    // (x + 0.0 turns -0 into +0 so that bounds print and compare plainly.)
    if (!(lo <= hi) || lo == kInf || hi == -kInf) {
      lo_ = kInf;
      hi_ = -kInf;
    }
  }

  static Interval empty() { return Interval(kInf, -kInf); }
  static Interval entire() { return Interval(); }
  // A rigorous enclosure of pi (the two doubles around it).
  static Interval pi();

  double lo() const { return lo_; }
  double hi() const { return hi_; }
  bool is_empty() const { return lo_ > hi_; }
  bool is_entire() const { return lo_ == -kInf && hi_ == kInf; }
  bool is_bounded() const {  // non-empty with both bounds finite
    return !is_empty() && std::isfinite(lo_) && std::isfinite(hi_);
  }
  bool is_point() const { return lo_ == hi_; }  // lo == hi

  // hi - lo rounded up; 0 for the empty interval.
  double width() const;
  // A point inside (the midpoint, rounded; a finite point for unbounded intervals: 0 for the
  // whole line, +-DBL_MAX for a half-line, as IEEE 1788); NaN if empty.
  double mid() const {
    if (is_empty()) return std::numeric_limits<double>::quiet_NaN();
    constexpr double kMax = std::numeric_limits<double>::max();
    if (lo_ == -kInf) return hi_ == kInf ? 0.0 : -kMax;
    if (hi_ == kInf) return kMax;
    if (lo_ == hi_) return lo_;
    double m = (lo_ + hi_) * 0.5;
    if (!std::isfinite(m)) m = lo_ * 0.5 + hi_ * 0.5;
    return std::clamp(m, lo_, hi_) + 0.0;
  }
  double rad() const;  // an upper bound of width()/2, and of the distance from mid() to the bounds
  double mag() const;  // max |x| over the interval; NaN if empty
  double mig() const;  // min |x| over the interval; NaN if empty

  bool contains(double x) const;
  bool contains_zero() const { return contains(0.0); }
  bool is_subset(const Interval& other) const;  // also true when *this is empty
  // Strictly inside (bounds differ; an infinite bound of other counts as open, as IEEE 1788).
  bool is_interior_subset(const Interval& other) const;
  bool intersects(const Interval& other) const;
  bool is_disjoint(const Interval& other) const { return !intersects(other); }

  // The two halves at lo + ratio * width (ratio in (0, 1)); both non-empty for a non-degenerate
  // interval, their union is *this. A ratio outside (0, 1) means 0.5; an unbounded interval is
  // split at mid().
  std::pair<Interval, Interval> bisect(double ratio = 0.5) const;

  inline Interval& operator+=(const Interval& y);  // + - * inline, below
  inline Interval& operator-=(const Interval& y);
  inline Interval& operator*=(const Interval& y);
  Interval& operator/=(const Interval& y);

  friend bool operator==(const Interval& a, const Interval& b);

 private:
  static constexpr double kInf = std::numeric_limits<double>::infinity();

  double lo_;
  double hi_;
};

// ---- Outward-rounded + - * and sqr, inline -----------------------------------------------------
//
// The hot operations of the validated integrator's Taylor recurrences are defined here so that
// they inline into them; the rare cases (infinite bounds, bounds beyond 2^500, products below
// 2^-900, empty operands) go to out-of-line functions in interval.cpp, which compute exactly what
// the inline code would have (see interval/README.md, "Rounding"). Everything in detail is an
// implementation detail, not API.
namespace detail {

// The error bound of glibc's sin, cos, asin and acos, in ulps of the computed value, by which
// their results are widened (interval.cpp; the MPFR tests measure it on each architecture).
inline constexpr int kLibmErrorUlps = 4;

inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr double kMax = std::numeric_limits<double>::max();
inline constexpr double kMinSubnormal = std::numeric_limits<double>::denorm_min();
// Below this magnitude a product's residual could underflow and lose its sign: such products go
// to the out-of-line path, which scales them by 2^600 (interval.cpp, mul_error_sign).
inline constexpr double kTiny = 0x1p-900;
// Inline products need every bound within +-2^500: products then stay below 2^1000, far from
// overflow, and Veltkamp's splitting (x * (2^27 + 1)) of a bound cannot overflow either.
inline constexpr double kFastRange = 0x1p500;

// The helpers below are forced inline (GCC and Clang): left to its heuristics, GCC kept the
// product's bound functions out of line in the integrator's large functions, a call per bound.

// std::nextafter(x, +inf) and std::nextafter(x, -inf), for every x (NaN, infinities, zeros), by
// stepping the IEEE 754 representation: for finite non-zero x the neighbour away from zero is
// bits + 1 and the one towards zero bits - 1 (the encoding is sign-magnitude, and the magnitudes'
// bit patterns are ordered like the magnitudes, subnormals and the step to and from infinity
// included).
[[gnu::always_inline]] inline double next_up(double x) {
  if (!(x < kInf)) return x;  // NaN, +inf
  if (x == 0) return kMinSubnormal;
  const auto u = std::bit_cast<std::uint64_t>(x);
  return std::bit_cast<double>(x > 0 ? u + 1 : u - 1);
}
[[gnu::always_inline]] inline double next_down(double x) {
  if (!(x > -kInf)) return x;  // NaN, -inf
  if (x == 0) return -kMinSubnormal;
  const auto u = std::bit_cast<std::uint64_t>(x);
  return std::bit_cast<double>(x > 0 ? u - 1 : u + 1);
}
// The same for x finite and non-zero (what the fast products produce), without the checks.
[[gnu::always_inline]] inline double step_up(double x) {
  const auto u = std::bit_cast<std::uint64_t>(x);
  return std::bit_cast<double>(x > 0 ? u + 1 : u - 1);
}
[[gnu::always_inline]] inline double step_down(double x) {
  const auto u = std::bit_cast<std::uint64_t>(x);
  return std::bit_cast<double>(x > 0 ? u - 1 : u + 1);
}

// The rare cases, out of line (interval.cpp): a + b not finite; a product of zero or below 2^-900
// in magnitude (with 0 * inf = 0, overflow, and the 2^600 scaling); the general product and
// square (infinite bounds, bounds beyond 2^500, empty operands).
double add_down_special(double a, double b);
double add_up_special(double a, double b);
double mul_down_special(double a, double b);
double mul_up_special(double a, double b);
Interval mul_general(const Interval& x, const Interval& y);
Interval sqr_general(const Interval& x);

// a + b rounded down / up: round to nearest, and TwoSum's exact error (a + b) - fl(a + b) says
// whether the rounding went the wrong way (6 additions, exact for any finite a, b, s without an
// intermediate overflow; if one overflows, the error is unknown and the bound steps).
[[gnu::always_inline]] inline double add_down(double a, double b) {
  const double s = a + b;
  if (!(std::fabs(s) <= kMax)) [[unlikely]]
    return add_down_special(a, b);
  const double bb = s - a;
  const double err = (a - (s - bb)) + (b - bb);
  return (err < 0 || !(std::fabs(err) <= kMax)) ? next_down(s) : s;
}
[[gnu::always_inline]] inline double add_up(double a, double b) {
  const double s = a + b;
  if (!(std::fabs(s) <= kMax)) [[unlikely]]
    return add_up_special(a, b);
  const double bb = s - a;
  const double err = (a - (s - bb)) + (b - bb);
  return (err > 0 || !(std::fabs(err) <= kMax)) ? next_up(s) : s;
}

// a*b - p exactly, for p = fl(a*b), |a|, |b| <= 2^500 and |p| >= 2^-900 (so that nothing in it
// overflows or underflows). With FMA in the instruction set (x86-64 with -mfma or -march=haswell or
// later; every aarch64) it is one fused multiply-add. Without it (the x86-64 baseline), std::fma is
// a call into libm, so Dekker's TwoProduct is used instead: Veltkamp's splitting cuts each factor
// into two halves of at most 26 significant bits, every partial product and partial sum below is
// then exact (all are multiples of ulp(a) ulp(b) >= |a b| 2^-106 >= 2^-1006, none overflows), and
// so is the result (Dekker 1971; Boldo 2006 for a formal proof that covers underflow). It needs
// every a*b + c evaluated as written: the project compiles with -ffp-contract=off (CMakeLists.txt),
// so GCC does not fuse them on an FMA target either.
[[gnu::always_inline]] inline double mul_residual(double a, double b, double p) {
#if defined(__FMA__) || defined(__ARM_FEATURE_FMA)
  return std::fma(a, b, -p);
#else
  constexpr double kSplit = 0x1p27 + 1;
  const double ca = kSplit * a;
  const double ah = ca - (ca - a);
  const double al = a - ah;
  const double cb = kSplit * b;
  const double bh = cb - (cb - b);
  const double bl = b - bh;
  return ((ah * bh - p) + ah * bl + al * bh) + al * bl;
#endif
}

// a * b rounded down / up for |a|, |b| <= 2^500 (the product is finite).
[[gnu::always_inline]] inline double mul_down_fast(double a, double b) {
  const double p = a * b;
  if (!(std::fabs(p) >= kTiny)) [[unlikely]]
    return (a == 0 || b == 0) ? 0.0 : mul_down_special(a, b);
  return mul_residual(a, b, p) < 0 ? step_down(p) : p;
}
[[gnu::always_inline]] inline double mul_up_fast(double a, double b) {
  const double p = a * b;
  if (!(std::fabs(p) >= kTiny)) [[unlikely]]
    return (a == 0 || b == 0) ? 0.0 : mul_up_special(a, b);
  return mul_residual(a, b, p) > 0 ? step_up(p) : p;
}

// Non-empty, with both bounds within +-2^500 (false for NaN bounds and for the empty interval).
[[gnu::always_inline]] inline bool fast_range(double lo, double hi) {
  return -kFastRange <= lo && lo <= hi && hi <= kFastRange;
}

}  // namespace detail

inline Interval operator-(const Interval& x) {
  if (x.is_empty()) return x;
  return Interval(-x.hi(), -x.lo());
}

inline Interval operator+(const Interval& x, const Interval& y) {
  if (x.is_empty() || y.is_empty()) return Interval::empty();
  return Interval(detail::add_down(x.lo(), y.lo()), detail::add_up(x.hi(), y.hi()));
}

inline Interval operator-(const Interval& x, const Interval& y) {
  if (x.is_empty() || y.is_empty()) return Interval::empty();
  return Interval(detail::add_down(x.lo(), -y.hi()), detail::add_up(x.hi(), -y.lo()));
}

// The bounds of x * y are among the four corner products; by the operands' signs only one
// candidate per bound is left, except when both straddle zero (two). The corner products, rounded
// down or up, are monotone in each factor over a sign orthant, so the result is bit for bit the
// minimum and maximum of all four. With 0 * inf = 0 (IEEE 1788's rule for bounds:
// [0, 0] * [-inf, inf] = [0, 0]) in the general path.
inline Interval operator*(const Interval& x, const Interval& y) {
  using detail::mul_down_fast;
  using detail::mul_up_fast;
  const double xl = x.lo(), xh = x.hi(), yl = y.lo(), yh = y.hi();
  if (!(detail::fast_range(xl, xh) && detail::fast_range(yl, yh))) [[unlikely]]
    return detail::mul_general(x, y);
  double lo;
  double hi;
  if (xl >= 0) {
    if (yl >= 0) {
      lo = mul_down_fast(xl, yl);
      hi = mul_up_fast(xh, yh);
    } else if (yh <= 0) {
      lo = mul_down_fast(xh, yl);
      hi = mul_up_fast(xl, yh);
    } else {
      lo = mul_down_fast(xh, yl);
      hi = mul_up_fast(xh, yh);
    }
  } else if (xh <= 0) {
    if (yl >= 0) {
      lo = mul_down_fast(xl, yh);
      hi = mul_up_fast(xh, yl);
    } else if (yh <= 0) {
      lo = mul_down_fast(xh, yh);
      hi = mul_up_fast(xl, yl);
    } else {
      lo = mul_down_fast(xl, yh);
      hi = mul_up_fast(xl, yl);
    }
  } else {
    if (yl >= 0) {
      lo = mul_down_fast(xl, yh);
      hi = mul_up_fast(xh, yh);
    } else if (yh <= 0) {
      lo = mul_down_fast(xh, yl);
      hi = mul_up_fast(xl, yl);
    } else {
      lo = std::min(mul_down_fast(xl, yh), mul_down_fast(xh, yl));
      hi = std::max(mul_up_fast(xl, yl), mul_up_fast(xh, yh));
    }
  }
  return Interval(lo, hi);
}

// Tight: [mig^2, mag^2], not x * x.
inline Interval sqr(const Interval& x) {
  const double xl = x.lo(), xh = x.hi();
  if (!detail::fast_range(xl, xh)) [[unlikely]]
    return detail::sqr_general(x);
  double mig;
  double mag;
  if (xl >= 0) {
    mig = xl;
    mag = xh;
  } else if (xh <= 0) {
    mig = -xh;
    mag = -xl;
  } else {
    mig = 0.0;
    mag = std::max(-xl, xh);
  }
  return Interval(std::max(0.0, detail::mul_down_fast(mig, mig)), detail::mul_up_fast(mag, mag));
}

inline Interval& Interval::operator+=(const Interval& y) {
  return *this = *this + y;
}
inline Interval& Interval::operator-=(const Interval& y) {
  return *this = *this - y;
}
inline Interval& Interval::operator*=(const Interval& y) {
  return *this = *this * y;
}

// Division by an interval containing zero gives the hull of the two pieces (possibly entire);
// by [0, 0] it gives the empty interval.
Interval operator/(const Interval& x, const Interval& y);

Interval hull(const Interval& a, const Interval& b);
Interval intersect(const Interval& a, const Interval& b);
Interval operator|(const Interval& a, const Interval& b);  // hull
Interval operator&(const Interval& a, const Interval& b);  // intersection

// sqr(x) (tight: [mig^2, mag^2]) is defined inline above, with the products.
Interval sqrt(const Interval& x);  // of the non-negative part; empty when x < 0 entirely
Interval abs(const Interval& x);
Interval pow(const Interval& x, int n);  // integer power, n >= 0 (n < 0: 1 / pow(x, -n))
// Rigorous: libm's result widened by its error bound, extremes found with an enclosure of pi.
// Beyond |x| = 2^40 (and for unbounded x) the result is [-1, 1].
Interval sin(const Interval& x);
Interval cos(const Interval& x);

// Backward operators (HC4-revise): given y = f(x1, x2) with y, x1, x2 already enclosed, shrink the
// arguments to the values consistent with y. Each returns the contracted arguments in place; an
// empty result means no argument value is consistent (then every argument is set empty).
void bwd_add(const Interval& y, Interval& x1, Interval& x2);
void bwd_sub(const Interval& y, Interval& x1, Interval& x2);
void bwd_mul(const Interval& y, Interval& x1, Interval& x2);
void bwd_div(const Interval& y, Interval& x1, Interval& x2);
void bwd_neg(const Interval& y, Interval& x);
void bwd_sqr(const Interval& y, Interval& x);
void bwd_sin(const Interval& y, Interval& x);
void bwd_cos(const Interval& y, Interval& x);

std::ostream& operator<<(std::ostream& out, const Interval& x);

}  // namespace furuta::interval
