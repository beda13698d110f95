#pragma once
// Taylor-mode automatic differentiation for the validated integrator (see validated/README.md).
//
// - `Taylor<T>`: a truncated power series in t (coefficients c[0..order]) with + - * / sqr sin cos.
//   Every operation is built on the per-coefficient recurrences of namespace `series`, which give
//   coefficient i of a result from coefficients 0..i of its operands (and 0..i-1 of itself).
// - `Grad<N>`: a forward-mode gradient (value and N partial derivatives, all intervals). Taylor
//   coefficients computed with T = Grad<N> carry their derivatives with respect to the initial
//   state: the Jacobian of the Taylor map.
// - `Jet2<N>`: a second-order directional jet (value, first and second coefficient in a scalar s
//   along an uncertain direction, linear in N interval coordinates): the second-order term of the
//   Taylor map over a set.
// - `Tape`, `record`: a vector field f, written once as a template over its scalar type, is
//   recorded into a list of operations by evaluating it on `Recorder` scalars.
// - `TaylorRunner<T>`: the Taylor coefficients x_[0..k] of the solution of x' = f(x), x(0) = x0,
//   from the tape, one order at a time over all nodes (coefficient i of a product costs O(i), so
//   the whole series costs O(k^2) per operation). T = Interval gives rigorous enclosures (every
//   operation is outward rounded); T = double or long double a plain point series.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <vector>

#include "furuta/interval/interval.hpp"

namespace furuta::validated {

using interval::Interval;

// ---- Per-coefficient recurrences ----------------------------------------------------------------
// T needs + - * / (and += -=) with itself, construction from double, and sin/cos for order 0.
namespace series {

// x times / divided by the integer k (cheaper than a product for gradients and jets).
template <class T>
T scale(const T& x, int k) {
  if constexpr (std::is_arithmetic_v<T>) {
    return x * static_cast<T>(k);
  } else {
    return x * Interval(static_cast<double>(k));
  }
}
template <class T>
T unscale(const T& x, int k) {
  if constexpr (std::is_arithmetic_v<T>) {
    return x / static_cast<T>(k);
  } else {
    return x / Interval(static_cast<double>(k));
  }
}

// Coefficient i of a * b.
template <class T>
T mul(const T* a, const T* b, int i) {
  T s = a[0] * b[i];
  for (int j = 1; j <= i; ++j) s += a[j] * b[i - j];
  return s;
}

// Coefficient i of a^2 (each cross product once, doubled; the middle term squared).
template <class T>
T sqr(const T* a, int i) {
  T s(0.0);
  for (int j = 0; 2 * j < i; ++j) s += a[j] * a[i - j];
  s = s + s;
  if (i % 2 == 0) {
    if constexpr (std::is_arithmetic_v<T>) {
      s += a[i / 2] * a[i / 2];
    } else {
      s += sqr(a[i / 2]);  // tight for intervals (found by ADL)
    }
  }
  return s;
}

// Coefficient i of c = a / b, given c[0..i-1]: c_i = (a_i - sum_{j=1..i} b_j c_{i-j}) / b_0.
template <class T>
T div(const T* a, const T* b, const T* c, int i) {
  T s = a[i];
  for (int j = 1; j <= i; ++j) s -= b[j] * c[i - j];
  return s / b[0];
}

// Coefficient i of s = sin a and c = cos a together (s' = c a', c' = -s a'):
// s_i = (1/i) sum_{j=1..i} j a_j c_{i-j},  c_i = -(1/i) sum_{j=1..i} j a_j s_{i-j}.
// ja: the products j a_j (j = 1..i) when the caller keeps them, else nullptr.
template <class T>
void sin_cos(const T* a, T* s, T* c, int i, const T* ja = nullptr) {
  if (i == 0) {
    using std::cos;
    using std::sin;
    s[0] = sin(a[0]);
    c[0] = cos(a[0]);
    return;
  }
  T ss(0.0);
  T cc(0.0);
  for (int j = 1; j <= i; ++j) {
    const T jaj = ja != nullptr ? ja[j] : scale(a[j], j);
    ss += jaj * c[i - j];
    cc += jaj * s[i - j];
  }
  s[i] = unscale(ss, i);
  c[i] = -unscale(cc, i);
}

}  // namespace series

// ---- Truncated power series ---------------------------------------------------------------------

template <class T>
class Taylor {
 public:
  Taylor() = default;
  // The constant series c0 (higher coefficients 0).
  explicit Taylor(int order, const T& c0 = T(0.0))
      : c_(static_cast<std::size_t>(order) + 1, T(0.0)) {
    c_[0] = c0;
  }
  // The series of the time variable shifted to v: v + t.
  static Taylor variable(const T& v, int order) {
    Taylor x(order, v);
    if (order >= 1) x.c_[1] = T(1.0);
    return x;
  }

  int order() const { return static_cast<int>(c_.size()) - 1; }
  T& operator[](int i) { return c_[static_cast<std::size_t>(i)]; }
  const T& operator[](int i) const { return c_[static_cast<std::size_t>(i)]; }
  T* data() { return c_.data(); }
  const T* data() const { return c_.data(); }

  // Horner evaluation at t (an interval t gives an enclosure of the polynomial over t).
  T eval(const T& t) const {
    T s = c_.back();
    for (int i = order() - 1; i >= 0; --i) s = s * t + c_[static_cast<std::size_t>(i)];
    return s;
  }

 private:
  std::vector<T> c_;
};

namespace detail {
template <class T>
int common_order(const Taylor<T>& a, const Taylor<T>& b) {
  if (a.order() != b.order()) throw std::invalid_argument("Taylor: orders differ");
  return a.order();
}
}  // namespace detail

template <class T>
Taylor<T> operator+(const Taylor<T>& a, const Taylor<T>& b) {
  Taylor<T> c(detail::common_order(a, b));
  for (int i = 0; i <= c.order(); ++i) c[i] = a[i] + b[i];
  return c;
}
template <class T>
Taylor<T> operator-(const Taylor<T>& a, const Taylor<T>& b) {
  Taylor<T> c(detail::common_order(a, b));
  for (int i = 0; i <= c.order(); ++i) c[i] = a[i] - b[i];
  return c;
}
template <class T>
Taylor<T> operator-(const Taylor<T>& a) {
  Taylor<T> c(a.order());
  for (int i = 0; i <= c.order(); ++i) c[i] = -a[i];
  return c;
}
template <class T>
Taylor<T> operator*(const Taylor<T>& a, const Taylor<T>& b) {
  Taylor<T> c(detail::common_order(a, b));
  for (int i = 0; i <= c.order(); ++i) c[i] = series::mul(a.data(), b.data(), i);
  return c;
}
template <class T>
Taylor<T> operator/(const Taylor<T>& a, const Taylor<T>& b) {
  Taylor<T> c(detail::common_order(a, b));
  for (int i = 0; i <= c.order(); ++i) c[i] = series::div(a.data(), b.data(), c.data(), i);
  return c;
}
template <class T>
Taylor<T> sqr(const Taylor<T>& a) {
  Taylor<T> c(a.order());
  for (int i = 0; i <= c.order(); ++i) c[i] = series::sqr(a.data(), i);
  return c;
}
// sin and cos of a series come together (coupled recurrences).
template <class T>
std::pair<Taylor<T>, Taylor<T>> sin_cos(const Taylor<T>& a) {
  std::pair<Taylor<T>, Taylor<T>> sc{Taylor<T>(a.order()), Taylor<T>(a.order())};
  for (int i = 0; i <= a.order(); ++i)
    series::sin_cos(a.data(), sc.first.data(), sc.second.data(), i);
  return sc;
}
template <class T>
Taylor<T> sin(const Taylor<T>& a) {
  return sin_cos(a).first;
}
template <class T>
Taylor<T> cos(const Taylor<T>& a) {
  return sin_cos(a).second;
}

// ---- Forward-mode gradient ----------------------------------------------------------------------

template <std::size_t N>
struct Grad {
  Interval v;
  std::array<Interval, N> d;

  Grad() : Grad(Interval(0.0)) {}
  Grad(const Interval& value) : v(value) { d.fill(Interval(0.0)); }  // NOLINT: constants mix in
  Grad(double value) : Grad(Interval(value)) {}                      // NOLINT
  // The independent variable number i, with value x.
  static Grad variable(const Interval& x, std::size_t i) {
    Grad g(x);
    g.d[i] = Interval(1.0);
    return g;
  }

  Grad& operator+=(const Grad& y) {
    v += y.v;
    for (std::size_t i = 0; i < N; ++i) d[i] += y.d[i];
    return *this;
  }
  Grad& operator-=(const Grad& y) {
    v -= y.v;
    for (std::size_t i = 0; i < N; ++i) d[i] -= y.d[i];
    return *this;
  }
};

template <std::size_t N>
Grad<N> operator+(Grad<N> a, const Grad<N>& b) {
  return a += b;
}
template <std::size_t N>
Grad<N> operator-(Grad<N> a, const Grad<N>& b) {
  return a -= b;
}
template <std::size_t N>
Grad<N> operator-(Grad<N> a) {
  a.v = -a.v;
  for (Interval& x : a.d) x = -x;
  return a;
}
template <std::size_t N>
Grad<N> operator*(const Grad<N>& a, const Grad<N>& b) {
  Grad<N> r(a.v * b.v);
  for (std::size_t i = 0; i < N; ++i) r.d[i] = a.d[i] * b.v + a.v * b.d[i];
  return r;
}
template <std::size_t N>
Grad<N> operator/(const Grad<N>& a, const Grad<N>& b) {
  Grad<N> r(a.v / b.v);
  for (std::size_t i = 0; i < N; ++i) r.d[i] = (a.d[i] - r.v * b.d[i]) / b.v;
  return r;
}
template <std::size_t N>
Grad<N> operator*(const Grad<N>& a, const Interval& k) {
  Grad<N> r(a.v * k);
  for (std::size_t i = 0; i < N; ++i) r.d[i] = a.d[i] * k;
  return r;
}
template <std::size_t N>
Grad<N> operator/(const Grad<N>& a, const Interval& k) {
  Grad<N> r(a.v / k);
  for (std::size_t i = 0; i < N; ++i) r.d[i] = a.d[i] / k;
  return r;
}
template <std::size_t N>
Grad<N> sqr(const Grad<N>& a) {
  Grad<N> r(interval::sqr(a.v));
  const Interval two_v = Interval(2.0) * a.v;
  for (std::size_t i = 0; i < N; ++i) r.d[i] = two_v * a.d[i];
  return r;
}
template <std::size_t N>
Grad<N> sin(const Grad<N>& a) {
  Grad<N> r(interval::sin(a.v));
  const Interval c = interval::cos(a.v);
  for (std::size_t i = 0; i < N; ++i) r.d[i] = c * a.d[i];
  return r;
}
template <std::size_t N>
Grad<N> cos(const Grad<N>& a) {
  Grad<N> r(interval::cos(a.v));
  const Interval ms = -interval::sin(a.v);
  for (std::size_t i = 0; i < N; ++i) r.d[i] = ms * a.d[i];
  return r;
}

// ---- Second-order directional jet --------------------------------------------------------------

// g(s) = v + d1 s + d2 s^2 + O(s^3): the second-order expansion in s of a function of y + s delta,
// where the direction delta = L rho + e is a linear form L in N uncertain coordinates rho (an
// interval vector) plus an interval vector e. d1 is carried as that linear form (coefficients g
// over rho, interval part e), so that its range is evaluated without wrapping; d2 as an interval.
// Taylor coefficients computed with these jets from x0 = (y, row of L, e, 0) carry, in d2, half
// the second directional derivative D^2 x_[i](y)[delta, delta] over every y in the box y and every
// delta of the form. N = 0: the direction is just an interval vector.
template <std::size_t N>
struct Jet2 {
  Interval v;
  std::array<Interval, N> g;
  Interval e;
  Interval d2;
  const Interval* rho = nullptr;  // the N coordinates' box (null for constants)

  Jet2() : Jet2(Interval(0.0)) {}
  Jet2(const Interval& value) : v(value), e(0.0), d2(0.0) {  // NOLINT: constants mix in
    g.fill(Interval(0.0));
  }
  Jet2(double value) : Jet2(Interval(value)) {}  // NOLINT

  // The range of d1 = g . rho + e (computed once per value: values are used in many products).
  const Interval& first() const {
    if (!has_first_) {
      first_ = e;
      if (rho != nullptr) {
        for (std::size_t i = 0; i < N; ++i) first_ += g[i] * rho[i];
      }
      has_first_ = true;
    }
    return first_;
  }

  Jet2& operator+=(const Jet2& y) {
    has_first_ = false;
    v += y.v;
    for (std::size_t i = 0; i < N; ++i) g[i] += y.g[i];
    e += y.e;
    d2 += y.d2;
    if (rho == nullptr) rho = y.rho;
    return *this;
  }
  Jet2& operator-=(const Jet2& y) {
    has_first_ = false;
    v -= y.v;
    for (std::size_t i = 0; i < N; ++i) g[i] -= y.g[i];
    e -= y.e;
    d2 -= y.d2;
    if (rho == nullptr) rho = y.rho;
    return *this;
  }
  // Call after changing g, e or rho directly.
  void changed() { has_first_ = false; }

 private:
  mutable Interval first_ = Interval(0.0);
  mutable bool has_first_ = false;
};

template <std::size_t N>
Jet2<N> operator+(Jet2<N> a, const Jet2<N>& b) {
  return a += b;
}
template <std::size_t N>
Jet2<N> operator-(Jet2<N> a, const Jet2<N>& b) {
  return a -= b;
}
template <std::size_t N>
Jet2<N> operator-(Jet2<N> a) {
  a.changed();
  a.v = -a.v;
  for (Interval& x : a.g) x = -x;
  a.e = -a.e;
  a.d2 = -a.d2;
  return a;
}
template <std::size_t N>
Jet2<N> operator*(const Jet2<N>& a, const Interval& k) {
  Jet2<N> r = a;
  r.changed();
  r.v = a.v * k;
  for (Interval& x : r.g) x *= k;
  r.e = a.e * k;
  r.d2 = a.d2 * k;
  return r;
}
template <std::size_t N>
Jet2<N> operator/(const Jet2<N>& a, const Interval& k) {
  Jet2<N> r = a;
  r.changed();
  r.v = a.v / k;
  for (Interval& x : r.g) x /= k;
  r.e = a.e / k;
  r.d2 = a.d2 / k;
  return r;
}
template <std::size_t N>
Jet2<N> operator*(const Jet2<N>& a, const Jet2<N>& b) {
  Jet2<N> r;
  r.rho = a.rho != nullptr ? a.rho : b.rho;
  r.v = a.v * b.v;
  for (std::size_t i = 0; i < N; ++i) r.g[i] = a.v * b.g[i] + b.v * a.g[i];
  r.e = a.v * b.e + b.v * a.e;
  r.d2 = a.v * b.d2 + a.d2 * b.v + a.first() * b.first();
  return r;
}
template <std::size_t N>
Jet2<N> operator/(const Jet2<N>& a, const Jet2<N>& b) {
  Jet2<N> r;
  r.rho = a.rho != nullptr ? a.rho : b.rho;
  r.v = a.v / b.v;
  for (std::size_t i = 0; i < N; ++i) r.g[i] = (a.g[i] - r.v * b.g[i]) / b.v;
  r.e = (a.e - r.v * b.e) / b.v;
  r.d2 = (a.d2 - r.v * b.d2 - r.first() * b.first()) / b.v;
  return r;
}
template <std::size_t N>
Jet2<N> sqr(const Jet2<N>& a) {
  Jet2<N> r;
  r.rho = a.rho;
  const Interval two_v = Interval(2.0) * a.v;
  r.v = interval::sqr(a.v);
  for (std::size_t i = 0; i < N; ++i) r.g[i] = two_v * a.g[i];
  r.e = two_v * a.e;
  r.d2 = two_v * a.d2 + interval::sqr(a.first());
  return r;
}
template <std::size_t N>
Jet2<N> sin(const Jet2<N>& a) {
  const Interval s = interval::sin(a.v);
  const Interval c = interval::cos(a.v);
  Jet2<N> r = a * c;
  r.v = s;
  r.d2 = c * a.d2 - Interval(0.5) * s * interval::sqr(a.first());
  return r;
}
template <std::size_t N>
Jet2<N> cos(const Jet2<N>& a) {
  const Interval s = interval::sin(a.v);
  const Interval c = interval::cos(a.v);
  Jet2<N> r = a * (-s);
  r.v = c;
  r.d2 = -(s * a.d2) - Interval(0.5) * c * interval::sqr(a.first());
  return r;
}

// ---- Second-order jet with a quadratic form
// ------------------------------------------------------

// Like Jet2 (g(s) = v + d1 s + d2 s^2 along delta = L rho + e, d1 the linear form g . rho + e),
// but the s^2 coefficient is carried as a quadratic form in rho (interval coefficients `q`, one per
// pair a <= b: the coefficient of rho_a rho_b) plus an interval `d2e` (the terms with e). The
// products of first-order forms, g rho h rho, go into q exactly instead of being bounded as the
// product of two ranges: in a field like the Furuta model's (M^-1 applied to a right-hand side,
// large terms that cancel) the interval bound of each product adds up where the true second
// derivative cancels. The coefficients of q are then evaluated over the box y, so they wrap only
// the Hessian's variation over it (third order in the set's size). `range()` bounds the whole s^2
// coefficient over rho (each rho_a^2 as a square, not a product).
template <std::size_t N>
struct QuadJet {
  static constexpr std::size_t kPairs = N * (N + 1) / 2;
  Interval v;
  std::array<Interval, N> g;
  Interval e;
  std::array<Interval, kPairs> q;  // (a, b), a <= b, row by row
  Interval d2e;
  const Interval* rho = nullptr;  // the N coordinates' box (null for constants)

  QuadJet() : QuadJet(Interval(0.0)) {}
  QuadJet(const Interval& value) : v(value), e(0.0), d2e(0.0) {  // NOLINT: constants mix in
    g.fill(Interval(0.0));
    q.fill(Interval(0.0));
  }
  QuadJet(double value) : QuadJet(Interval(value)) {}  // NOLINT

  // The range of g . rho (computed once per value: values are used in many products).
  const Interval& linear() const {
    if (!has_linear_) {
      linear_ = Interval(0.0);
      if (rho != nullptr) {
        for (std::size_t i = 0; i < N; ++i) linear_ += g[i] * rho[i];
      }
      has_linear_ = true;
    }
    return linear_;
  }
  Interval first() const { return linear() + e; }
  // The s^2 coefficient over every rho in its box.
  Interval range() const {
    Interval out = d2e;
    if (rho == nullptr) return out;
    std::size_t k = 0;
    for (std::size_t a = 0; a < N; ++a) {
      out += q[k++] * sqr(rho[a]);
      for (std::size_t b = a + 1; b < N; ++b) out += q[k++] * (rho[a] * rho[b]);
    }
    return out;
  }

  QuadJet& operator+=(const QuadJet& y) {
    has_linear_ = false;
    v += y.v;
    for (std::size_t i = 0; i < N; ++i) g[i] += y.g[i];
    e += y.e;
    for (std::size_t i = 0; i < kPairs; ++i) q[i] += y.q[i];
    d2e += y.d2e;
    if (rho == nullptr) rho = y.rho;
    return *this;
  }
  QuadJet& operator-=(const QuadJet& y) {
    has_linear_ = false;
    v -= y.v;
    for (std::size_t i = 0; i < N; ++i) g[i] -= y.g[i];
    e -= y.e;
    for (std::size_t i = 0; i < kPairs; ++i) q[i] -= y.q[i];
    d2e -= y.d2e;
    if (rho == nullptr) rho = y.rho;
    return *this;
  }
  // Call after changing g or rho directly.
  void changed() { has_linear_ = false; }

  // q += the form of k (g . rho)(h . rho): k g_a h_a on the diagonal, k (g_a h_b + g_b h_a) off it.
  void add_outer(const Interval& k, const std::array<Interval, N>& ga,
                 const std::array<Interval, N>& hb) {
    std::size_t p = 0;
    for (std::size_t a = 0; a < N; ++a) {
      const Interval ka = k * ga[a];
      const Interval kb = k * hb[a];
      q[p++] += ka * hb[a];
      for (std::size_t b = a + 1; b < N; ++b) q[p++] += ka * hb[b] + kb * ga[b];
    }
  }
  // The part of d1_x d1_y that is not in the form: (g_x . rho) e_y + e_x (g_y . rho) + e_x e_y.
  static Interval cross(const QuadJet& x, const QuadJet& y) {
    return x.linear() * y.e + x.e * y.linear() + x.e * y.e;
  }

 private:
  mutable Interval linear_ = Interval(0.0);
  mutable bool has_linear_ = false;
};

template <std::size_t N>
QuadJet<N> operator+(QuadJet<N> a, const QuadJet<N>& b) {
  return a += b;
}
template <std::size_t N>
QuadJet<N> operator-(QuadJet<N> a, const QuadJet<N>& b) {
  return a -= b;
}
template <std::size_t N>
QuadJet<N> operator-(QuadJet<N> a) {
  a.changed();
  a.v = -a.v;
  for (Interval& x : a.g) x = -x;
  a.e = -a.e;
  for (Interval& x : a.q) x = -x;
  a.d2e = -a.d2e;
  return a;
}
template <std::size_t N>
QuadJet<N> operator*(const QuadJet<N>& a, const Interval& k) {
  QuadJet<N> r = a;
  r.changed();
  r.v = a.v * k;
  for (Interval& x : r.g) x *= k;
  r.e = a.e * k;
  for (Interval& x : r.q) x *= k;
  r.d2e = a.d2e * k;
  return r;
}
template <std::size_t N>
QuadJet<N> operator/(const QuadJet<N>& a, const Interval& k) {
  QuadJet<N> r = a;
  r.changed();
  r.v = a.v / k;
  for (Interval& x : r.g) x /= k;
  r.e = a.e / k;
  for (Interval& x : r.q) x /= k;
  r.d2e = a.d2e / k;
  return r;
}
template <std::size_t N>
QuadJet<N> operator*(const QuadJet<N>& a, const QuadJet<N>& b) {
  QuadJet<N> r;
  r.rho = a.rho != nullptr ? a.rho : b.rho;
  r.v = a.v * b.v;
  for (std::size_t i = 0; i < N; ++i) r.g[i] = a.v * b.g[i] + b.v * a.g[i];
  r.e = a.v * b.e + b.v * a.e;
  for (std::size_t i = 0; i < QuadJet<N>::kPairs; ++i) r.q[i] = a.v * b.q[i] + b.v * a.q[i];
  r.add_outer(Interval(1.0), a.g, b.g);
  r.d2e = a.v * b.d2e + b.v * a.d2e + QuadJet<N>::cross(a, b);
  return r;
}
template <std::size_t N>
QuadJet<N> operator/(const QuadJet<N>& a, const QuadJet<N>& b) {
  // r = a / b: r0 = a0 / b0, r1 = (a1 - r0 b1) / b0, r2 = (a2 - r0 b2 - r1 b1) / b0.
  QuadJet<N> r;
  r.rho = a.rho != nullptr ? a.rho : b.rho;
  r.v = a.v / b.v;
  for (std::size_t i = 0; i < N; ++i) r.g[i] = (a.g[i] - r.v * b.g[i]) / b.v;
  r.e = (a.e - r.v * b.e) / b.v;
  for (std::size_t i = 0; i < QuadJet<N>::kPairs; ++i) r.q[i] = a.q[i] - r.v * b.q[i];
  r.add_outer(Interval(-1.0), r.g, b.g);
  for (Interval& x : r.q) x /= b.v;
  r.d2e = (a.d2e - r.v * b.d2e - QuadJet<N>::cross(r, b)) / b.v;
  return r;
}
template <std::size_t N>
QuadJet<N> sqr(const QuadJet<N>& a) {
  QuadJet<N> r;
  r.rho = a.rho;
  const Interval two_v = Interval(2.0) * a.v;
  r.v = interval::sqr(a.v);
  for (std::size_t i = 0; i < N; ++i) r.g[i] = two_v * a.g[i];
  r.e = two_v * a.e;
  for (std::size_t i = 0; i < QuadJet<N>::kPairs; ++i) r.q[i] = two_v * a.q[i];
  r.add_outer(Interval(1.0), a.g, a.g);
  r.d2e = two_v * a.d2e + Interval(2.0) * a.linear() * a.e + interval::sqr(a.e);
  return r;
}
// sin(a0 + u) = sin a0 + cos a0 u - sin a0 u^2 / 2 + ...: the s^2 coefficient is
// cos a0 a2 - sin a0 a1^2 / 2.
template <std::size_t N>
QuadJet<N> sin_cos_jet(const QuadJet<N>& a, const Interval& slope, const Interval& curvature,
                       const Interval& value) {
  QuadJet<N> r = a * slope;
  r.v = value;
  r.add_outer(Interval(0.5) * curvature, a.g, a.g);
  r.d2e += Interval(0.5) * curvature * (Interval(2.0) * a.linear() * a.e + interval::sqr(a.e));
  return r;
}
template <std::size_t N>
QuadJet<N> sin(const QuadJet<N>& a) {
  const Interval s = interval::sin(a.v);
  const Interval c = interval::cos(a.v);
  return sin_cos_jet(a, c, -s, s);
}
template <std::size_t N>
QuadJet<N> cos(const QuadJet<N>& a) {
  const Interval s = interval::sin(a.v);
  const Interval c = interval::cos(a.v);
  return sin_cos_jet(a, -s, -c, c);
}

// ---- Operation tape -----------------------------------------------------------------------------

enum class Op : std::uint8_t { variable, constant, add, sub, neg, mul, div, sqr, sin, cos };

struct TapeNode {
  Op op = Op::constant;
  int a = -1;  // first operand (node index); for a variable, its component number
  int b = -1;  // second operand
  Interval value = Interval(0.0);  // a constant's value
  // The node's series is constant in t (constants, variables with zero derivative, and what only
  // depends on them): its coefficients of order >= 1 are 0 and need no work.
  bool time_constant = false;
};

// A vector field x' = f(x) on R^n as a list of operations. Nodes 0..n-1 are the variables x_i;
// `outputs[i]` is the node of f_i. A sin node is always followed by the cos node of the same
// operand (the recurrences compute both).
struct Tape {
  std::size_t dimension = 0;
  std::vector<TapeNode> nodes;
  std::vector<int> outputs;
};

// The scalar on which a vector field is recorded. Constants (doubles, intervals and what is
// computed from them alone) are folded in interval arithmetic at record time.
class Recorder {
 public:
  Recorder() : Recorder(0.0) {}
  Recorder(double c) : value_(c) {}           // NOLINT: constants mix in
  Recorder(const Interval& c) : value_(c) {}  // NOLINT
  Recorder(Tape* tape, int node) : tape_(tape), node_(node) {}

  bool is_constant() const { return node_ < 0; }
  int node() const { return node_; }
  const Interval& value() const { return value_; }
  Tape* tape() const { return tape_; }

  // The node of this value, appending a constant node if it is one.
  int materialize(Tape& tape) const {
    if (!is_constant()) return node_;
    TapeNode n;
    n.op = Op::constant;
    n.value = value_;
    tape.nodes.push_back(n);
    return static_cast<int>(tape.nodes.size()) - 1;
  }

  friend Recorder operator+(const Recorder& x, const Recorder& y) {
    return binary(Op::add, x, y, [](const Interval& a, const Interval& b) { return a + b; });
  }
  friend Recorder operator-(const Recorder& x, const Recorder& y) {
    return binary(Op::sub, x, y, [](const Interval& a, const Interval& b) { return a - b; });
  }
  friend Recorder operator*(const Recorder& x, const Recorder& y) {
    return binary(Op::mul, x, y, [](const Interval& a, const Interval& b) { return a * b; });
  }
  friend Recorder operator/(const Recorder& x, const Recorder& y) {
    return binary(Op::div, x, y, [](const Interval& a, const Interval& b) { return a / b; });
  }
  friend Recorder operator-(const Recorder& x) {
    if (x.is_constant()) return Recorder(-x.value_);
    return x.append(Op::neg, x.node_, -1);
  }
  Recorder& operator+=(const Recorder& y) { return *this = *this + y; }
  Recorder& operator-=(const Recorder& y) { return *this = *this - y; }
  Recorder& operator*=(const Recorder& y) { return *this = *this * y; }
  Recorder& operator/=(const Recorder& y) { return *this = *this / y; }

  friend Recorder sqr(const Recorder& x) {
    if (x.is_constant()) return Recorder(interval::sqr(x.value_));
    return x.append(Op::sqr, x.node_, -1);
  }
  friend Recorder sin(const Recorder& x) {
    if (x.is_constant()) return Recorder(interval::sin(x.value_));
    return Recorder(x.tape_, x.sin_cos_pair());
  }
  friend Recorder cos(const Recorder& x) {
    if (x.is_constant()) return Recorder(interval::cos(x.value_));
    return Recorder(x.tape_, x.sin_cos_pair() + 1);
  }

 private:
  template <class Fold>
  static Recorder binary(Op op, const Recorder& x, const Recorder& y, Fold fold) {
    if (x.is_constant() && y.is_constant()) return Recorder(fold(x.value_, y.value_));
    Tape& tape = x.is_constant() ? *y.tape_ : *x.tape_;
    const int a = x.materialize(tape);
    const int b = y.materialize(tape);
    return Recorder(&tape, 0).append(op, a, b);
  }
  Recorder append(Op op, int a, int b) const {
    TapeNode n;
    n.op = op;
    n.a = a;
    n.b = b;
    tape_->nodes.push_back(n);
    return Recorder(tape_, static_cast<int>(tape_->nodes.size()) - 1);
  }
  // The sin node of this operand (its cos node follows), appended on first use.
  int sin_cos_pair() const {
    for (std::size_t i = 0; i < tape_->nodes.size(); ++i) {
      if (tape_->nodes[i].op == Op::sin && tape_->nodes[i].a == node_) return static_cast<int>(i);
    }
    append(Op::sin, node_, -1);
    append(Op::cos, node_, -1);
    return static_cast<int>(tape_->nodes.size()) - 2;
  }

  Tape* tape_ = nullptr;
  int node_ = -1;
  Interval value_ = Interval(0.0);
};

// Marks the time-constant nodes: variables whose derivative is the constant 0 (parameters carried
// as state), constants, and operations on time-constant operands only.
inline void mark_time_constants(Tape& tape) {
  for (TapeNode& n : tape.nodes) {
    switch (n.op) {
      case Op::constant:
        n.time_constant = true;
        break;
      case Op::variable: {
        const TapeNode& out = tape.nodes[static_cast<std::size_t>(tape.outputs[n.a])];
        n.time_constant = out.op == Op::constant && out.value == Interval(0.0);
        break;
      }
      default: {
        const bool a = tape.nodes[static_cast<std::size_t>(n.a)].time_constant;
        const bool b = n.b < 0 || tape.nodes[static_cast<std::size_t>(n.b)].time_constant;
        n.time_constant = a && b;
      }
    }
  }
}

// Records f: f(std::span<const Recorder> x, std::span<Recorder> dx) on R^n.
template <class F>
Tape record(F&& f, std::size_t n) {
  Tape tape;
  tape.dimension = n;
  std::vector<Recorder> x;
  for (std::size_t i = 0; i < n; ++i) {
    TapeNode node;
    node.op = Op::variable;
    node.a = static_cast<int>(i);
    tape.nodes.push_back(node);
    x.emplace_back(&tape, static_cast<int>(i));
  }
  std::vector<Recorder> dx(n);
  f(std::span<const Recorder>(x), std::span<Recorder>(dx));
  for (const Recorder& d : dx) tape.outputs.push_back(d.materialize(tape));
  mark_time_constants(tape);
  return tape;
}

// ---- Taylor coefficients of an ODE solution -----------------------------------------------------

// An interval constant as a scalar of type T: itself for intervals and gradients, its midpoint for
// floating-point T (exact for the point constants that point simulations use).
template <class T>
T constant_as(const Interval& v) {
  if constexpr (std::is_floating_point_v<T>) {
    return static_cast<T>(v.mid());
  } else {
    return T(v);
  }
}

template <class T>
class TaylorRunner {
 public:
  // Computes x_[0..order] of the solution of x' = f(x), x(0) = x0 (x_[i+1] = f(x)_[i] / (i+1)).
  void run(const Tape& tape, std::span<const T> x0, int order) {
    if (x0.size() != tape.dimension) throw std::invalid_argument("TaylorRunner: dimension");
    tape_ = &tape;
    stride_ = static_cast<std::size_t>(order) + 1;
    c_.assign(tape.nodes.size() * stride_, T(0.0));
    for (std::size_t v = 0; v < tape.dimension; ++v) c_[v * stride_] = x0[v];
    for (std::size_t n = tape.dimension; n < tape.nodes.size(); ++n) {
      if (tape.nodes[n].op == Op::constant) c_[n * stride_] = constant_as<T>(tape.nodes[n].value);
    }
    ja_.assign(tape.nodes.size() * stride_, T(0.0));
    for (int i = 0; i < order; ++i) {
      for (std::size_t n = tape.dimension; n < tape.nodes.size(); ++n) step(n, i);
      for (std::size_t v = 0; v < tape.dimension; ++v) {
        if (tape.nodes[v].time_constant) continue;
        const T& fi = at(static_cast<std::size_t>(tape.outputs[v]), i);
        c_[v * stride_ + static_cast<std::size_t>(i) + 1] = series::unscale(fi, i + 1);
      }
    }
  }

  // Coefficient i of component v of the solution.
  const T& coefficient(std::size_t v, int i) const { return at(v, i); }
  int order() const { return static_cast<int>(stride_) - 1; }

 private:
  const T& at(std::size_t node, int i) const {
    return c_[node * stride_ + static_cast<std::size_t>(i)];
  }
  T* series_of(std::size_t node) { return c_.data() + node * stride_; }

  void step(std::size_t n, int i) {
    const TapeNode& node = tape_->nodes[n];
    if (node.op == Op::constant || node.op == Op::cos) return;  // cos: filled with its sin
    if (i > 0 && node.time_constant) return;                    // stays 0
    const auto ia = static_cast<std::size_t>(node.a);
    const auto ib = static_cast<std::size_t>(node.b);
    T* c = series_of(n);
    const T* a = series_of(ia);
    const auto ui = static_cast<std::size_t>(i);
    switch (node.op) {
      case Op::add:
        c[ui] = a[ui] + series_of(ib)[ui];
        break;
      case Op::sub:
        c[ui] = a[ui] - series_of(ib)[ui];
        break;
      case Op::neg:
        c[ui] = -a[ui];
        break;
      case Op::mul: {
        const T* b = series_of(ib);
        if (tape_->nodes[ia].time_constant) {
          c[ui] = a[0] * b[ui];
        } else if (tape_->nodes[ib].time_constant) {
          c[ui] = a[ui] * b[0];
        } else {
          c[ui] = series::mul(a, b, i);
        }
        break;
      }
      case Op::div: {
        const T* b = series_of(ib);
        c[ui] = tape_->nodes[ib].time_constant ? a[ui] / b[0] : series::div(a, b, c, i);
        break;
      }
      case Op::sqr:
        c[ui] = series::sqr(a, i);
        break;
      case Op::sin: {
        // j a_j of the operand, kept per sin node (each is computed once).
        T* ja = ja_.data() + n * stride_;
        if (i > 0) ja[ui] = series::scale(a[ui], i);
        series::sin_cos(a, c, series_of(n + 1), i, ja);
        break;
      }
      default:
        break;
    }
  }

  const Tape* tape_ = nullptr;
  std::size_t stride_ = 1;
  std::vector<T> c_;   // node-major: c_[node * stride_ + i] = coefficient i of the node
  std::vector<T> ja_;  // for sin nodes: j times coefficient j of the operand
};

}  // namespace furuta::validated
