// `Grad<N, S>`: a forward-mode gradient (value and N partial derivatives) with scalars S: intervals
// (the default), or Taylor models (taylor_model.hpp), whose derivatives then keep how they vary
// over a set. Part of furuta/validated/taylor.hpp: include that.

#include <array>
#include <cstddef>
#include <type_traits>

#include "furuta/interval/interval.hpp"

namespace furuta::validated {

using interval::Interval;

template <std::size_t N, class S = Interval>
struct Grad {
  S v;
  std::array<S, N> d;

  Grad() : Grad(S(0.0)) {}
  Grad(const S& value) : v(value) { d.fill(S(0.0)); }  // NOLINT: constants mix in
  Grad(double value) : Grad(S(value)) {}               // NOLINT
  // The independent variable number i, with value x.
  static Grad variable(const S& x, std::size_t i) {
    Grad g(x);
    g.d[i] = S(1.0);
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

template <std::size_t N, class S>
Grad<N, S> operator+(Grad<N, S> a, const Grad<N, S>& b) {
  return a += b;
}
template <std::size_t N, class S>
Grad<N, S> operator-(Grad<N, S> a, const Grad<N, S>& b) {
  return a -= b;
}
template <std::size_t N, class S>
Grad<N, S> operator-(Grad<N, S> a) {
  a.v = -a.v;
  for (S& x : a.d) x = -x;
  return a;
}
template <std::size_t N, class S>
Grad<N, S> operator*(const Grad<N, S>& a, const Grad<N, S>& b) {
  Grad<N, S> r(a.v * b.v);
  for (std::size_t i = 0; i < N; ++i) r.d[i] = a.d[i] * b.v + a.v * b.d[i];
  return r;
}
template <std::size_t N, class S>
Grad<N, S> operator/(const Grad<N, S>& a, const Grad<N, S>& b) {
  Grad<N, S> r(a.v / b.v);
  if constexpr (std::is_same_v<S, Interval>) {
    for (std::size_t i = 0; i < N; ++i) r.d[i] = (a.d[i] - r.v * b.d[i]) / b.v;
  } else {
    // One reciprocal for all N derivatives (a Taylor model's 1/x is an expansion).
    const S inverse = S(1.0) / b.v;
    for (std::size_t i = 0; i < N; ++i) r.d[i] = (a.d[i] - r.v * b.d[i]) * inverse;
  }
  return r;
}
template <std::size_t N, class S>
Grad<N, S> operator*(const Grad<N, S>& a, const Interval& k) {
  Grad<N, S> r(a.v * k);
  for (std::size_t i = 0; i < N; ++i) r.d[i] = a.d[i] * k;
  return r;
}
template <std::size_t N, class S>
Grad<N, S> operator/(const Grad<N, S>& a, const Interval& k) {
  Grad<N, S> r(a.v / k);
  for (std::size_t i = 0; i < N; ++i) r.d[i] = a.d[i] / k;
  return r;
}
template <std::size_t N, class S>
Grad<N, S> sqr(const Grad<N, S>& a) {
  using interval::sqr;
  Grad<N, S> r(sqr(a.v));
  const S two_v = a.v * Interval(2.0);
  for (std::size_t i = 0; i < N; ++i) r.d[i] = two_v * a.d[i];
  return r;
}
template <std::size_t N, class S>
Grad<N, S> sin(const Grad<N, S>& a) {
  using interval::cos;
  using interval::sin;
  Grad<N, S> r(sin(a.v));
  const S c = cos(a.v);
  for (std::size_t i = 0; i < N; ++i) r.d[i] = c * a.d[i];
  return r;
}
template <std::size_t N, class S>
Grad<N, S> cos(const Grad<N, S>& a) {
  using interval::cos;
  using interval::sin;
  Grad<N, S> r(cos(a.v));
  const S ms = -sin(a.v);
  for (std::size_t i = 0; i < N; ++i) r.d[i] = ms * a.d[i];
  return r;
}

}  // namespace furuta::validated
