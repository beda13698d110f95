#pragma once
// `QuadJet<N>`: the second-order jet with its second order carried as a quadratic form in the
// coordinates. Part of furuta/validated/taylor.hpp: include that.

#include <array>
#include <cstddef>

#include "furuta/interval/interval.hpp"

namespace furuta::validated {

using interval::Interval;

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

}  // namespace furuta::validated
