#pragma once
// `Taylor<T>`: a truncated power series in t with + - * / sqr sin cos, on the recurrences of
// series.hpp. Part of furuta/validated/taylor.hpp: include that.

#include <cstddef>
#include <stdexcept>
#include <utility>
#include <vector>

#include "furuta/interval/interval.hpp"
#include "furuta/validated/detail/series.hpp"

namespace furuta::validated {

using interval::Interval;

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

}  // namespace furuta::validated
