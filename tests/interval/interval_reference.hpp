#pragma once
// The interval + - * and sqr as they were before the inline fast paths (interval.cpp until the
// interval-speed change): every bound rounded to nearest, then stepped with std::nextafter when
// TwoSum or std::fma's residual says it went inward, the product as the min and max of the four
// corner products. The tests compare the inline operators with it bit for bit.
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "furuta/interval/interval.hpp"

namespace furuta::interval::reference {

inline constexpr double kRefInf = std::numeric_limits<double>::infinity();
inline constexpr double kRefMax = std::numeric_limits<double>::max();

inline double next_up(double x) {
  return std::nextafter(x, kRefInf);
}
inline double next_down(double x) {
  return std::nextafter(x, -kRefInf);
}

inline int sum_error_sign(double a, double b, double s) {
  const double bb = s - a;
  const double err = (a - (s - bb)) + (b - bb);
  if (!std::isfinite(err)) return 2;
  return err > 0 ? 1 : (err < 0 ? -1 : 0);
}

inline double add_down(double a, double b) {
  const double s = a + b;
  if (std::isnan(s)) return -kRefInf;
  if (std::isinf(s)) {
    if (std::isinf(a) || std::isinf(b)) return s;
    return s > 0 ? kRefMax : -kRefInf;
  }
  const int e = sum_error_sign(a, b, s);
  return (e < 0 || e == 2) ? next_down(s) : s;
}

inline double add_up(double a, double b) {
  const double s = a + b;
  if (std::isnan(s)) return kRefInf;
  if (std::isinf(s)) {
    if (std::isinf(a) || std::isinf(b)) return s;
    return s < 0 ? -kRefMax : kRefInf;
  }
  const int e = sum_error_sign(a, b, s);
  return e > 0 ? next_up(s) : s;
}

inline int mul_error_sign(double a, double b, double p) {
  if (p == 0) return (a > 0) == (b > 0) ? 1 : -1;
  if (std::fabs(p) < 0x1p-900) {
    if (std::fabs(a) > std::fabs(b)) std::swap(a, b);
    a = std::ldexp(a, 600);
    p = std::ldexp(p, 600);
  }
  const double e = std::fma(a, b, -p);
  return e > 0 ? 1 : (e < 0 ? -1 : 0);
}

inline double mul_down(double a, double b) {
  if (a == 0 || b == 0) return 0.0;
  const double p = a * b;
  if (std::isinf(p)) {
    if (std::isinf(a) || std::isinf(b)) return p;
    return p > 0 ? kRefMax : -kRefInf;
  }
  return mul_error_sign(a, b, p) < 0 ? next_down(p) : p;
}

inline double mul_up(double a, double b) {
  if (a == 0 || b == 0) return 0.0;
  const double p = a * b;
  if (std::isinf(p)) {
    if (std::isinf(a) || std::isinf(b)) return p;
    return p < 0 ? -kRefMax : kRefInf;
  }
  return mul_error_sign(a, b, p) > 0 ? next_up(p) : p;
}

inline Interval add(const Interval& x, const Interval& y) {
  if (x.is_empty() || y.is_empty()) return Interval::empty();
  return Interval(add_down(x.lo(), y.lo()), add_up(x.hi(), y.hi()));
}

inline Interval sub(const Interval& x, const Interval& y) {
  if (x.is_empty() || y.is_empty()) return Interval::empty();
  return Interval(add_down(x.lo(), -y.hi()), add_up(x.hi(), -y.lo()));
}

inline Interval mul(const Interval& x, const Interval& y) {
  if (x.is_empty() || y.is_empty()) return Interval::empty();
  const double xl = x.lo(), xh = x.hi(), yl = y.lo(), yh = y.hi();
  const double lo =
      std::min({mul_down(xl, yl), mul_down(xl, yh), mul_down(xh, yl), mul_down(xh, yh)});
  const double hi = std::max({mul_up(xl, yl), mul_up(xl, yh), mul_up(xh, yl), mul_up(xh, yh)});
  return Interval(lo, hi);
}

inline Interval sqr(const Interval& x) {
  if (x.is_empty()) return x;
  const double m = x.mig();
  const double M = x.mag();
  return Interval(std::max(0.0, mul_down(m, m)), mul_up(M, M));
}

}  // namespace furuta::interval::reference
