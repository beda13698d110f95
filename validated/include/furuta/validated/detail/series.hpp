#pragma once
// Taylor-coefficient arithmetic: the per-coefficient recurrences (coefficient i of a result from
// coefficients 0..i of the operands). Part of furuta/validated/taylor.hpp: include that.

#include <cmath>
#include <type_traits>

#include "furuta/interval/interval.hpp"

namespace furuta::validated {

using interval::Interval;

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

}  // namespace furuta::validated
