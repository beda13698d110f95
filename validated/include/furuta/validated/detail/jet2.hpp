#pragma once
// `Jet2<N>`: a second-order directional jet, the first order a linear form in N interval
// coordinates, the second order an interval. Part of furuta/validated/taylor.hpp: include that.

#include <array>
#include <cstddef>

#include "furuta/interval/interval.hpp"

namespace furuta::validated {

using interval::Interval;

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

}  // namespace furuta::validated
