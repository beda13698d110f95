// Intervals with outward rounding computed in round-to-nearest (see interval/README.md): each bound
// is the round-to-nearest result, stepped one ulp outward only when an error-free transformation
// shows the rounding went inward. No FPU rounding-mode switches, so no global state.
//
// The error-free transformations assume IEEE 754 binary64 arithmetic evaluated as written: no
// x87 excess precision (x86_64 uses SSE2, aarch64 has none), no -ffast-math, and no contraction of
// a*b+c into an FMA (GCC contracts on FMA targets even in ISO mode: the project passes
// -ffp-contract=off).

#include "furuta/interval/interval.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <ostream>
#include <sstream>

namespace furuta::interval {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMax = std::numeric_limits<double>::max();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Below this magnitude the residual of an error-free transformation could underflow to zero and
// lose its sign (see mul_error_sign); the operands are then scaled by 2^kScale, exactly.
constexpr double kTiny = 0x1p-900;
constexpr int kScale = 600;

// The two doubles around pi: 0x1.921fb54442d18p+1 < pi < 0x1.921fb54442d19p+1.
constexpr double kPiLo = 0x1.921fb54442d18p+1;
constexpr double kPiHi = 0x1.921fb54442d19p+1;

// Beyond this magnitude sin and cos return [-1, 1] (see README: the extremum analysis is rigorous
// at any magnitude, but the libm error bound is only tested up to here).
constexpr double kTrigLimit = 0x1p40;

// The libm error bound, in ulps of the computed value, by which sin, cos, asin and acos results
// are widened. glibc documents at most 1 ulp for these on x86_64 and aarch64 (manual section
// "Known Maximum Errors in Math Functions", from sysdeps/*/libm-test-ulps; both use the same
// generic double-precision code); 4 is a margin.
constexpr int kLibmUlps = detail::kLibmErrorUlps;

// std::nextafter(x, +-inf), inline (interval.hpp).
double next_up(double x) {
  return detail::next_up(x);
}
double next_down(double x) {
  return detail::next_down(x);
}

// ---- Addition (TwoSum) --------------------------------------------------------------------------
//
// These out-of-line forms of + - * are the general ones: the inline code in interval.hpp computes
// the same bounds for the common cases and calls them (through detail::) for the rest.

// The rounded sum and the sign of (exact - rounded): -1, 0, +1; 2 when unknown (then stepping
// both ways is needed).
int sum_error_sign(double a, double b, double s) {
  const double bb = s - a;
  const double err = (a - (s - bb)) + (b - bb);
  if (!std::isfinite(err)) return 2;
  return err > 0 ? 1 : (err < 0 ? -1 : 0);
}

double add_down_any(double a, double b) {
  const double s = a + b;
  if (std::isnan(s)) return -kInf;  // inf - inf: cannot happen for valid bounds; sound anyway
  if (std::isinf(s)) {
    if (std::isinf(a) || std::isinf(b)) return s;
    return s > 0 ? kMax : -kInf;  // overflow: the exact sum is finite
  }
  const int e = sum_error_sign(a, b, s);
  return (e < 0 || e == 2) ? next_down(s) : s;
}

double add_up_any(double a, double b) {
  const double s = a + b;
  if (std::isnan(s)) return kInf;
  if (std::isinf(s)) {
    if (std::isinf(a) || std::isinf(b)) return s;
    return s < 0 ? -kMax : kInf;
  }
  const int e = sum_error_sign(a, b, s);
  return e > 0 ? next_up(s) : s;
}

double sub_up(double a, double b) {
  return add_up_any(a, -b);
}

// ---- Multiplication (FMA residual), with 0 * inf = 0 as set-based bounds need ----------------

// Sign of (a*b - p) for finite non-zero a, b and p = fl(a*b) finite: -1, 0, +1. Near underflow the
// residual itself could underflow to zero, so the smaller factor and p are first scaled by 2^600
// (exact), which scales the residual alike. p == 0 with a, b != 0 is never exact.
int mul_error_sign(double a, double b, double p) {
  if (p == 0) return (a > 0) == (b > 0) ? 1 : -1;
  if (std::fabs(p) < kTiny) {
    if (std::fabs(a) > std::fabs(b)) std::swap(a, b);
    a = std::ldexp(a, kScale);
    p = std::ldexp(p, kScale);
  }
  const double e = std::fma(a, b, -p);  // a*b - p, its sign exact
  return e > 0 ? 1 : (e < 0 ? -1 : 0);
}

double mul_down_any(double a, double b) {
  if (a == 0 || b == 0) return 0.0;
  const double p = a * b;
  if (std::isinf(p)) {
    if (std::isinf(a) || std::isinf(b)) return p;
    return p > 0 ? kMax : -kInf;  // overflow: the exact product is finite
  }
  return mul_error_sign(a, b, p) < 0 ? next_down(p) : p;
}

double mul_up_any(double a, double b) {
  if (a == 0 || b == 0) return 0.0;
  const double p = a * b;
  if (std::isinf(p)) {
    if (std::isinf(a) || std::isinf(b)) return p;
    return p < 0 ? -kMax : kInf;
  }
  return mul_error_sign(a, b, p) > 0 ? next_up(p) : p;
}

// ---- Division (FMA residual). b != 0; a, b finite, a != 0. ------------------------------------

// Sign of (a/b - q) for q = fl(a/b) finite: -1, 0, +1. a/b - q = (a - q*b)/b; near underflow a and
// q are scaled by 2^600 first (exact; the residual scales alike). q == 0 is never exact.
int div_error_sign(double a, double b, double q) {
  if (q == 0) return (a > 0) == (b > 0) ? 1 : -1;
  if (std::fabs(q) < kTiny || std::fabs(a) < kTiny) {
    a = std::ldexp(a, kScale);
    q = std::ldexp(q, kScale);
  }
  const double r = std::fma(-q, b, a);  // a - q*b, its sign exact
  if (r == 0) return 0;
  return ((r > 0) == (b > 0)) ? 1 : -1;
}

double div_down(double a, double b) {
  if (a == 0 || std::isinf(b)) return 0.0;  // exact (a limit for b infinite)
  if (std::isinf(a)) return a / b;
  const double q = a / b;
  if (std::isinf(q)) return q > 0 ? kMax : -kInf;
  return div_error_sign(a, b, q) < 0 ? next_down(q) : q;
}

double div_up(double a, double b) {
  if (a == 0 || std::isinf(b)) return 0.0;
  if (std::isinf(a)) return a / b;
  const double q = a / b;
  if (std::isinf(q)) return q < 0 ? -kMax : kInf;
  return div_error_sign(a, b, q) > 0 ? next_up(q) : q;
}

// ---- Square root (FMA residual). a >= 0. ------------------------------------------------------

// Sign of (sqrt(a) - r) for r = fl(sqrt(a)), a > 0 finite: the sign of a - r*r (scaled by 2^600,
// r by 2^300, near underflow).
int sqrt_error_sign(double a, double r) {
  if (a < kTiny) {
    a = std::ldexp(a, kScale);
    r = std::ldexp(r, kScale / 2);
  }
  const double e = std::fma(-r, r, a);
  return e > 0 ? 1 : (e < 0 ? -1 : 0);
}

double sqrt_down(double a) {
  if (a == 0 || std::isinf(a)) return std::sqrt(a) + 0.0;
  const double r = std::sqrt(a);
  return sqrt_error_sign(a, r) < 0 ? next_down(r) : r;
}

double sqrt_up(double a) {
  if (a == 0 || std::isinf(a)) return std::sqrt(a) + 0.0;
  const double r = std::sqrt(a);
  return sqrt_error_sign(a, r) > 0 ? next_up(r) : r;
}

// ---- Integer powers of non-negative numbers (monotone, so directed bounds compose) ------------

double pow_down(double a, unsigned n) {
  double r = 1.0;
  double base = a;
  while (n != 0) {
    if (n & 1U) r = std::max(0.0, mul_down_any(r, base));
    n >>= 1U;
    if (n != 0) base = std::max(0.0, mul_down_any(base, base));
  }
  return r;
}

double pow_up(double a, unsigned n) {
  double r = 1.0;
  double base = a;
  while (n != 0) {
    if (n & 1U) r = mul_up_any(r, base);
    n >>= 1U;
    if (n != 0) base = mul_up_any(base, base);
  }
  return r;
}

// ---- Transcendental helpers --------------------------------------------------------------------

double steps_down(double v, int n) {
  for (int i = 0; i < n; ++i) v = next_down(v);
  return v;
}
double steps_up(double v, int n) {
  for (int i = 0; i < n; ++i) v = next_up(v);
  return v;
}

// An enclosure of a libm value v with the documented error bound, clamped to [lo_clamp, hi_clamp]
// (bounds of the function's range that are certainly outside or on it).
Interval widen_libm(double v, double lo_clamp, double hi_clamp) {
  return Interval(std::max(lo_clamp, steps_down(v, kLibmUlps)),
                  std::min(hi_clamp, steps_up(v, kLibmUlps)));
}

Interval sin_point(double x) {
  if (x == 0) return Interval(0.0);
  return widen_libm(std::sin(x), -1.0, 1.0);
}

Interval cos_point(double x) {
  if (x == 0) return Interval(1.0);
  return widen_libm(std::cos(x), -1.0, 1.0);
}

Interval asin_point(double y) {  // y in [-1, 1]
  if (y == 0) return Interval(0.0);
  return widen_libm(std::asin(y), -kPiHi / 2, kPiHi / 2);
}

Interval acos_point(double y) {  // y in [-1, 1]
  if (y == 1) return Interval(0.0);
  return widen_libm(std::acos(y), 0.0, kPiHi);
}

// sin (offset 0.5) or cos (offset 0) over a bounded, non-empty [a, b]: their extremes are at
// (k + offset) * pi, with value (-1)^k. Every k that may lie in [a, b] (judged with an enclosure
// of pi, so an uncertain one is counted in) contributes its extreme; the rest of the range is
// the hull of the endpoint enclosures, the function being monotone between extremes.
Interval sin_cos(const Interval& x, double offset, Interval (*point)(double)) {
  if (x.is_empty()) return Interval::empty();
  const Interval unit(-1.0, 1.0);
  if (!x.is_bounded() || x.mag() > kTrigLimit) return unit;
  const double a = x.lo();
  const double b = x.hi();
  const Interval pi = Interval::pi();
  const double ta = (Interval(a) / pi - Interval(offset)).lo();
  const double tb = (Interval(b) / pi - Interval(offset)).hi();
  const double kmin = std::ceil(ta);
  const double kmax = std::floor(tb);
  if (kmax - kmin >= 1) return unit;  // two consecutive extremes: one of each sign
  Interval r = point(a);
  if (b != a) r = hull(r, point(b));
  if (kmin == kmax) {
    const bool even = std::fmod(kmin, 2.0) == 0;
    r = even ? Interval(r.lo(), 1.0) : Interval(-1.0, r.hi());
  }
  return r;
}

// Sets both arguments empty (no consistent value) and returns true when x is empty.
bool empty_out(const Interval& x, Interval& a, Interval& b) {
  if (!x.is_empty()) return false;
  a = Interval::empty();
  b = Interval::empty();
  return true;
}

}  // namespace

// ---- Interval members ---------------------------------------------------------------------------

Interval Interval::pi() {
  return Interval(kPiLo, kPiHi);
}

double Interval::width() const {
  if (is_empty()) return 0.0;
  return sub_up(hi_, lo_);
}

double Interval::rad() const {
  if (is_empty()) return 0.0;
  if (!is_bounded()) return kInf;
  const double m = mid();
  return std::max(sub_up(m, lo_), sub_up(hi_, m));
}

double Interval::mag() const {
  if (is_empty()) return kNaN;
  return std::max(std::fabs(lo_), std::fabs(hi_));
}

double Interval::mig() const {
  if (is_empty()) return kNaN;
  if (lo_ <= 0 && 0 <= hi_) return 0.0;
  return std::min(std::fabs(lo_), std::fabs(hi_));
}

bool Interval::contains(double x) const {
  return std::isfinite(x) && lo_ <= x && x <= hi_;
}

bool Interval::is_subset(const Interval& other) const {
  if (is_empty()) return true;
  return other.lo_ <= lo_ && hi_ <= other.hi_;
}

bool Interval::is_interior_subset(const Interval& other) const {
  if (is_empty()) return true;
  if (other.is_empty()) return false;
  const bool lo_ok = other.lo_ < lo_ || other.lo_ == -kInf;
  const bool hi_ok = hi_ < other.hi_ || other.hi_ == kInf;
  return lo_ok && hi_ok;
}

bool Interval::intersects(const Interval& other) const {
  if (is_empty() || other.is_empty()) return false;
  return std::max(lo_, other.lo_) <= std::min(hi_, other.hi_);
}

std::pair<Interval, Interval> Interval::bisect(double ratio) const {
  if (is_empty()) return {empty(), empty()};
  if (!(ratio > 0 && ratio < 1)) ratio = 0.5;
  double m;
  if (!is_bounded()) {
    m = mid();
  } else {
    m = lo_ + ratio * (hi_ - lo_);
    if (!std::isfinite(m)) m = lo_ * (1 - ratio) + hi_ * ratio;
    m = std::clamp(m, lo_, hi_);
    if ((m == lo_ || m == hi_) && lo_ < hi_) {
      const double inside = next_up(lo_);
      m = inside < hi_ ? inside : lo_;
    }
  }
  return {Interval(lo_, m), Interval(m, hi_)};
}

Interval& Interval::operator/=(const Interval& y) {
  return *this = *this / y;
}

bool operator==(const Interval& a, const Interval& b) {
  if (a.is_empty() || b.is_empty()) return a.is_empty() && b.is_empty();
  return a.lo_ == b.lo_ && a.hi_ == b.hi_;
}

// ---- Arithmetic ---------------------------------------------------------------------------------

// Unary minus, + - * and sqr are inline (interval.hpp); these are their out-of-line parts.

double detail::add_down_special(double a, double b) {
  return add_down_any(a, b);
}
double detail::add_up_special(double a, double b) {
  return add_up_any(a, b);
}
double detail::mul_down_special(double a, double b) {
  return mul_down_any(a, b);
}
double detail::mul_up_special(double a, double b) {
  return mul_up_any(a, b);
}

// The general product (infinite bounds, bounds beyond 2^500, empty operands): all four corners.
Interval detail::mul_general(const Interval& x, const Interval& y) {
  if (x.is_empty() || y.is_empty()) return Interval::empty();
  // The bounds are among the four corner products (with 0 * inf = 0, IEEE 1788's rule for
  // bounds: [0, 0] * [-inf, inf] = [0, 0]).
  const double xl = x.lo(), xh = x.hi(), yl = y.lo(), yh = y.hi();
  const double lo = std::min(
      {mul_down_any(xl, yl), mul_down_any(xl, yh), mul_down_any(xh, yl), mul_down_any(xh, yh)});
  const double hi =
      std::max({mul_up_any(xl, yl), mul_up_any(xl, yh), mul_up_any(xh, yl), mul_up_any(xh, yh)});
  return Interval(lo, hi);
}

Interval operator/(const Interval& x, const Interval& y) {
  if (x.is_empty() || y.is_empty()) return Interval::empty();
  const double xl = x.lo(), xh = x.hi(), yl = y.lo(), yh = y.hi();
  if (yl == 0 && yh == 0) return Interval::empty();
  if (yl < 0 && yh > 0) return Interval::entire();  // hull of two unbounded pieces
  if (xl <= 0 && 0 <= xh && yl <= 0 && 0 <= yh) return Interval::entire();
  if (yl == 0) {  // y = [0, yh], yh > 0; 0 not in x
    if (xl > 0) return Interval(div_down(xl, yh), kInf);
    return Interval(-kInf, div_up(xh, yh));
  }
  if (yh == 0) {  // y = [yl, 0], yl < 0; 0 not in x
    if (xl > 0) return Interval(-kInf, div_up(xl, yl));
    return Interval(div_down(xh, yl), kInf);
  }
  if (yl > 0) {
    if (xl >= 0) return Interval(div_down(xl, yh), div_up(xh, yl));
    if (xh <= 0) return Interval(div_down(xl, yl), div_up(xh, yh));
    return Interval(div_down(xl, yl), div_up(xh, yl));
  }
  // y < 0
  if (xl >= 0) return Interval(div_down(xh, yh), div_up(xl, yl));
  if (xh <= 0) return Interval(div_down(xh, yl), div_up(xl, yh));
  return Interval(div_down(xh, yh), div_up(xl, yh));
}

Interval hull(const Interval& a, const Interval& b) {
  if (a.is_empty()) return b;
  if (b.is_empty()) return a;
  return Interval(std::min(a.lo(), b.lo()), std::max(a.hi(), b.hi()));
}

Interval intersect(const Interval& a, const Interval& b) {
  if (a.is_empty() || b.is_empty()) return Interval::empty();
  return Interval(std::max(a.lo(), b.lo()), std::min(a.hi(), b.hi()));
}

Interval operator|(const Interval& a, const Interval& b) {
  return hull(a, b);
}
Interval operator&(const Interval& a, const Interval& b) {
  return intersect(a, b);
}

// ---- Elementary functions ----------------------------------------------------------------------

Interval detail::sqr_general(const Interval& x) {
  if (x.is_empty()) return x;
  const double m = x.mig();
  const double M = x.mag();
  return Interval(std::max(0.0, mul_down_any(m, m)), mul_up_any(M, M));
}

Interval sqrt(const Interval& x) {
  const Interval nonneg = intersect(x, Interval(0.0, kInf));
  if (nonneg.is_empty()) return nonneg;
  return Interval(sqrt_down(nonneg.lo()), sqrt_up(nonneg.hi()));
}

Interval abs(const Interval& x) {
  if (x.is_empty()) return x;
  return Interval(x.mig(), x.mag());
}

Interval pow(const Interval& x, int n) {
  if (x.is_empty()) return x;
  if (n < 0) return Interval(1.0) / pow(x, -n);  // outside the contract; sound anyway
  if (n == 0) return Interval(1.0);
  const auto u = static_cast<unsigned>(n);
  if (n % 2 == 0) return Interval(pow_down(x.mig(), u), pow_up(x.mag(), u));
  const double xl = x.lo(), xh = x.hi();
  const double lo = xl >= 0 ? pow_down(xl, u) : -pow_up(-xl, u);
  const double hi = xh >= 0 ? pow_up(xh, u) : -pow_down(-xh, u);
  return Interval(lo, hi);
}

Interval sin(const Interval& x) {
  return sin_cos(x, 0.5, sin_point);
}
Interval cos(const Interval& x) {
  return sin_cos(x, 0.0, cos_point);
}

// ---- Backward operators -------------------------------------------------------------------------

void bwd_add(const Interval& y, Interval& x1, Interval& x2) {
  const Interval yy = intersect(y, x1 + x2);
  if (empty_out(yy, x1, x2)) return;
  x1 = intersect(x1, yy - x2);
  if (empty_out(x1, x1, x2)) return;
  x2 = intersect(x2, yy - x1);
  empty_out(x2, x1, x2);
}

void bwd_sub(const Interval& y, Interval& x1, Interval& x2) {
  const Interval yy = intersect(y, x1 - x2);
  if (empty_out(yy, x1, x2)) return;
  x1 = intersect(x1, yy + x2);
  if (empty_out(x1, x1, x2)) return;
  x2 = intersect(x2, x1 - yy);
  empty_out(x2, x1, x2);
}

void bwd_mul(const Interval& y, Interval& x1, Interval& x2) {
  const Interval yy = intersect(y, x1 * x2);
  if (empty_out(yy, x1, x2)) return;
  // x1 * x2 = y with 0 in y and 0 in x2: every x1 is consistent (x2 = 0), leave x1 alone.
  // Otherwise x1 = y / x2 over the non-zero x2 (or y != 0), which the extended division encloses.
  if (!(yy.contains_zero() && x2.contains_zero())) {
    x1 = intersect(x1, yy / x2);
    if (empty_out(x1, x1, x2)) return;
  }
  if (!(yy.contains_zero() && x1.contains_zero())) {
    x2 = intersect(x2, yy / x1);
    empty_out(x2, x1, x2);
  }
}

void bwd_div(const Interval& y, Interval& x1, Interval& x2) {
  const Interval yy = intersect(y, x1 / x2);
  if (empty_out(yy, x1, x2)) return;
  // y = x1 / x2 (x2 != 0): x1 = y * x2, and x2 = x1 / y unless y = 0 = x1 is possible (then any
  // non-zero x2 is consistent).
  x1 = intersect(x1, yy * x2);
  if (empty_out(x1, x1, x2)) return;
  if (!(yy.contains_zero() && x1.contains_zero())) {
    x2 = intersect(x2, x1 / yy);
    empty_out(x2, x1, x2);
  }
}

void bwd_neg(const Interval& y, Interval& x) {
  x = intersect(x, -y);
}

void bwd_sqr(const Interval& y, Interval& x) {
  const Interval yy = intersect(intersect(y, sqr(x)), Interval(0.0, kInf));
  if (yy.is_empty()) {
    x = Interval::empty();
    return;
  }
  const Interval r = sqrt(yy);
  x = hull(intersect(x, -r), intersect(x, r));
}

namespace {

// Preimage pieces are built for k in [floor(x.lo / 2pi) - 1, floor(x.hi / 2pi) + 1]; beyond this
// many, x is left as it is.
constexpr double kMaxPeriods = 64;

// The hull of x's intersection with the pieces [lo(k), hi(k)] of a 2pi-periodic preimage, every
// piece lying within [2k pi - 3pi/2, 2k pi + 3pi/2] (so the k range above covers x). lo(k) and
// hi(k) are outward enclosures of the pieces' bounds.
template <class Pieces>
void contract_periodic(Interval& x, const Pieces& pieces) {
  if (!x.is_bounded() || x.mag() > kTrigLimit) return;
  const double two_pi = 2 * kPiLo;
  const double kmin = std::floor(x.lo() / two_pi) - 1;
  const double kmax = std::floor(x.hi() / two_pi) + 1;
  if (kmax - kmin > kMaxPeriods) return;
  Interval r = Interval::empty();
  for (double k = kmin; k <= kmax; k += 1) {
    for (const Interval& piece : pieces(k)) r = hull(r, intersect(x, piece));
  }
  x = r;
}

}  // namespace

void bwd_sin(const Interval& y, Interval& x) {
  const Interval yy = intersect(intersect(y, Interval(-1.0, 1.0)), sin(x));
  if (yy.is_empty()) {
    x = Interval::empty();
    return;
  }
  if (yy.lo() == -1 && yy.hi() == 1) return;
  const Interval asin_lo = asin_point(yy.lo());
  const Interval asin_hi = asin_point(yy.hi());
  const Interval pi = Interval::pi();
  // sin x in [yl, yh]: x in [asin yl, asin yh] + 2k pi (rising branch) or
  // x in [pi - asin yh, pi - asin yl] + 2k pi (falling branch).
  contract_periodic(x, [&](double k) {
    const Interval even = Interval(2 * k) * pi;
    const Interval odd = Interval(2 * k + 1) * pi;
    return std::array<Interval, 2>{Interval((asin_lo + even).lo(), (asin_hi + even).hi()),
                                   Interval((odd - asin_hi).lo(), (odd - asin_lo).hi())};
  });
}

void bwd_cos(const Interval& y, Interval& x) {
  const Interval yy = intersect(intersect(y, Interval(-1.0, 1.0)), cos(x));
  if (yy.is_empty()) {
    x = Interval::empty();
    return;
  }
  if (yy.lo() == -1 && yy.hi() == 1) return;
  const Interval acos_of_hi = acos_point(yy.hi());  // the smaller angle
  const Interval acos_of_lo = acos_point(yy.lo());
  const Interval pi = Interval::pi();
  // cos x in [yl, yh]: x in [acos yh, acos yl] + 2k pi or x in [-acos yl, -acos yh] + 2k pi.
  contract_periodic(x, [&](double k) {
    const Interval even = Interval(2 * k) * pi;
    return std::array<Interval, 2>{Interval((even + acos_of_hi).lo(), (even + acos_of_lo).hi()),
                                   Interval((even - acos_of_lo).lo(), (even - acos_of_hi).hi())};
  });
}

// ---- Output -------------------------------------------------------------------------------------

std::ostream& operator<<(std::ostream& out, const Interval& x) {
  if (x.is_empty()) return out << "[empty]";
  std::ostringstream s;
  s.precision(std::numeric_limits<double>::max_digits10);
  s << '[' << x.lo() << ", " << x.hi() << ']';
  return out << s.str();
}

}  // namespace furuta::interval
