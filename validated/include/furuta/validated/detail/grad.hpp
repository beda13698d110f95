#pragma once
// `Grad<N>`: a forward-mode gradient (value and N partial derivatives, all intervals). Part of
// furuta/validated/taylor.hpp: include that.

#include <array>
#include <cstddef>

#include "furuta/interval/interval.hpp"

namespace furuta::validated {

using interval::Interval;

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

}  // namespace furuta::validated
