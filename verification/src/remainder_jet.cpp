#include "remainder_jet.hpp"

#include <cstddef>
#include <utility>

namespace furuta::verification::detail {

namespace {

// A value and its derivatives to the third order in the three variables, each an interval:
// forward-mode differentiation over boxes (the sum, product, quotient and chain rules hold at every
// point of them). h and t hold the symmetric second and third derivatives by sorted index
// (kPairs, kTriples in remainder_jet.hpp).

struct Jet {
  Interval v;
  std::array<Interval, 3> d;
  std::array<Interval, 6> h;
  std::array<Interval, 10> t;
  bool third = true;  // t is carried (else left at 0: not asked for)

  explicit Jet(const Interval& value) : v(value) {
    d.fill(Interval(0.0));
    h.fill(Interval(0.0));
    t.fill(Interval(0.0));
  }
};

Jet variable(const Interval& v, std::size_t k, bool third) {
  Jet out(v);
  out.d[k] = Interval(1.0);
  out.third = third;
  return out;
}

Jet constant(const Interval& v) {
  return Jet(v);
}

Jet operator+(const Jet& x, const Jet& y) {
  Jet out(x.v + y.v);
  out.third = x.third && y.third;
  for (std::size_t k = 0; k < 3; ++k) out.d[k] = x.d[k] + y.d[k];
  for (std::size_t k = 0; k < 6; ++k) out.h[k] = x.h[k] + y.h[k];
  for (std::size_t k = 0; k < 10 && out.third; ++k) out.t[k] = x.t[k] + y.t[k];
  return out;
}

Jet operator-(const Jet& x, const Jet& y) {
  Jet out(x.v - y.v);
  out.third = x.third && y.third;
  for (std::size_t k = 0; k < 3; ++k) out.d[k] = x.d[k] - y.d[k];
  for (std::size_t k = 0; k < 6; ++k) out.h[k] = x.h[k] - y.h[k];
  for (std::size_t k = 0; k < 10 && out.third; ++k) out.t[k] = x.t[k] - y.t[k];
  return out;
}

Jet operator*(const Interval& a, const Jet& x) {
  Jet out(a * x.v);
  out.third = x.third;
  for (std::size_t k = 0; k < 3; ++k) out.d[k] = a * x.d[k];
  for (std::size_t k = 0; k < 6; ++k) out.h[k] = a * x.h[k];
  for (std::size_t k = 0; k < 10 && out.third; ++k) out.t[k] = a * x.t[k];
  return out;
}

// The terms of (z y)'s derivatives in which y is differentiated fewer times than the order:
// (z y)_ijk = z_ijk y + z_ij y_k + z_ik y_j + z_jk y_i + z_i y_jk + z_j y_ik + z_k y_ij + z y_ijk
// less the last. The product adds it; the quotient (x = z y) solves for z's highest order.
Jet product_without_last(const Jet& z, const Jet& y) {
  Jet out(z.v * y.v);
  out.third = z.third && y.third;
  for (std::size_t k = 0; k < 3; ++k) out.d[k] = y.v * z.d[k];
  for (std::size_t k = 0; k < 6; ++k) {
    const auto [i, j] = kPairs[k];
    out.h[k] = z.h[k] * y.v + z.d[i] * y.d[j] + z.d[j] * y.d[i];
  }
  for (std::size_t k = 0; k < 10 && out.third; ++k) {
    const auto [i, j, l] = kTriples[k];
    out.t[k] = z.t[k] * y.v + z.h[pair_index(i, j)] * y.d[l] + z.h[pair_index(i, l)] * y.d[j] +
               z.h[pair_index(j, l)] * y.d[i] + z.d[i] * y.h[pair_index(j, l)] +
               z.d[j] * y.h[pair_index(i, l)] + z.d[l] * y.h[pair_index(i, j)];
  }
  return out;
}

Jet operator*(const Jet& x, const Jet& y) {
  Jet out = product_without_last(x, y);
  for (std::size_t k = 0; k < 3; ++k) out.d[k] += x.v * y.d[k];
  for (std::size_t k = 0; k < 6; ++k) out.h[k] += x.v * y.h[k];
  for (std::size_t k = 0; k < 10 && out.third; ++k) out.t[k] += x.v * y.t[k];
  return out;
}

// z = x / y from x = z y, order by order: z's derivative = (x's - the rest of (z y)'s) / y.
Jet operator/(const Jet& x, const Jet& y) {
  Jet z(x.v / y.v);
  z.third = x.third && y.third;
  for (std::size_t k = 0; k < 3; ++k) z.d[k] = (x.d[k] - z.v * y.d[k]) / y.v;
  for (std::size_t k = 0; k < 6; ++k) {
    const auto [i, j] = kPairs[k];
    z.h[k] = (x.h[k] - z.d[i] * y.d[j] - z.d[j] * y.d[i] - z.v * y.h[k]) / y.v;
  }
  for (std::size_t k = 0; k < 10 && z.third; ++k) {
    const auto [i, j, l] = kTriples[k];
    const Interval rest = z.h[pair_index(i, j)] * y.d[l] + z.h[pair_index(i, l)] * y.d[j] +
                          z.h[pair_index(j, l)] * y.d[i] + z.d[i] * y.h[pair_index(j, l)] +
                          z.d[j] * y.h[pair_index(i, l)] + z.d[l] * y.h[pair_index(i, j)] +
                          z.v * y.t[k];
    z.t[k] = (x.t[k] - rest) / y.v;
  }
  return z;
}

// f(x) from f and its first three derivatives over x's range (Faa di Bruno's formula).
Jet chain(const Jet& x, const Interval& f, const Interval& f1, const Interval& f2,
          const Interval& f3) {
  Jet out(f);
  out.third = x.third;
  for (std::size_t k = 0; k < 3; ++k) out.d[k] = f1 * x.d[k];
  for (std::size_t k = 0; k < 6; ++k) {
    const auto [i, j] = kPairs[k];
    out.h[k] = f2 * (x.d[i] * x.d[j]) + f1 * x.h[k];
  }
  for (std::size_t k = 0; k < 10 && out.third; ++k) {
    const auto [i, j, l] = kTriples[k];
    out.t[k] = f3 * (x.d[i] * x.d[j] * x.d[l]) +
               f2 * (x.h[pair_index(i, j)] * x.d[l] + x.h[pair_index(i, l)] * x.d[j] +
                     x.h[pair_index(j, l)] * x.d[i]) +
               f1 * x.t[k];
  }
  return out;
}

Jet sin(const Jet& x) {
  const Interval s = interval::sin(x.v);
  const Interval c = interval::cos(x.v);
  return chain(x, s, c, -s, -c);
}

Jet cos(const Jet& x) {
  const Interval s = interval::sin(x.v);
  const Interval c = interval::cos(x.v);
  return chain(x, c, -s, -c, s);
}

// sin x - x: decreasing (its derivative cos x - 1 <= 0), so its range over [a, b] is between its
// values at b and a, without the spread of sin x and x taken apart.
Jet sin_minus_identity(const Jet& x) {
  const Interval at_hi = interval::sin(Interval(x.v.hi())) - Interval(x.v.hi());
  const Interval at_lo = interval::sin(Interval(x.v.lo())) - Interval(x.v.lo());
  const Interval s = interval::sin(x.v);
  const Interval c = interval::cos(x.v);
  return chain(x, Interval(at_hi.lo(), at_lo.hi()), c - Interval(1.0), -s, -c);
}

}  // namespace

RemainderJet remainder_jet(const MomentumPlant& plant, const model::Parameters<Interval>& p,
                           const Interval& kw, const std::array<Interval, 3>& y, bool third) {
  const Jet e = variable(y[0], 0, third);
  const Jet w1 = variable(y[1], 1, third);
  const Jet w2 = variable(y[2], 2, third);
  const model::Parameters<double>& centre = plant.centre;
  // At q2 = pi + e: sin q2 = -sin e, cos q2 = -cos e. M(q2) = [m11, m12; m12, m22].
  const Jet s = sin(e);
  const Jet c = cos(e);
  const Jet m11 = constant(p.mu1) + p.mu2 * (s * s);
  const Jet m12 = Interval(-1.0) * (p.mu3 * c);
  const Jet m22 = constant(p.mu4);
  const Jet det = m11 * m22 - m12 * m12;
  // The rates M(q2)^-1 p = w + M(q2)^-1 (M(pi) - M(q2)) w, w = M(pi)^-1 p: the small matrix
  // M(pi) - M(q2) = [-mu2 sin^2 e, -mu3 (1 - cos e); ..., 0] multiplies w first, so that w's range
  // is not spread through p (p1 and p2 are far larger than the rates they give).
  const Jet d11 = Interval(-1.0) * (p.mu2 * (s * s));
  const Jet d12 = Interval(-1.0) * (p.mu3 * (constant(Interval(1.0)) - c));
  const Jet t1 = d11 * w1 + d12 * w2;
  const Jet t2 = d12 * w1;
  const Jet excess1 = (m22 * t1 - m12 * t2) / det;
  const Jet excess2 = (m11 * t2 - m12 * t1) / det;
  const Jet dq1 = w1 + excess1;
  const Jet dq2 = w2 + excess2;
  const Interval damping = kw + p.fv1;
  const Interval damping_centre = Interval(plant.kw) + Interval(centre.fv1);
  const Jet n0 = excess1;
  const Jet n1 = excess2;
  const Jet n2 = Interval(-1.0) * ((damping - damping_centre) * w1 + damping * excess1);
  // dq' (dM/dq2) dq / 2 = mu2 sin q2 cos q2 dq1^2 - mu3 sin q2 dq1 dq2; -mug sin q2.
  const Jet n3 = p.mu2 * (s * c * dq1 * dq1) + p.mu3 * (s * dq1 * dq2) +
                 p.mug * sin_minus_identity(e) + (p.mug - Interval(centre.mug)) * e -
                 ((p.fv2 - Interval(centre.fv2)) * w2 + p.fv2 * excess2);
  RemainderJet out;
  const std::array<const Jet*, 4> rows{&n0, &n1, &n2, &n3};
  for (std::size_t i = 0; i < 4; ++i) {
    out.value[i] = rows[i]->v;
    out.gradient[i] = rows[i]->d;
    out.hessian[i] = rows[i]->h;
    out.third[i] = rows[i]->t;
  }
  return out;
}

}  // namespace furuta::verification::detail
