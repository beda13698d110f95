// Square interval matrices (see interval_matrix.hpp).

#include "interval_matrix.hpp"

#include <algorithm>

namespace furuta::validated::detail {

IMatrix from_point(const Matrix& a) {
  const auto n = static_cast<std::size_t>(a.rows());
  IMatrix m(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      m(i, j) = Interval(a(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)));
    }
  }
  return m;
}

IMatrix from_point(std::size_t n, const std::vector<double>& row_major) {
  IMatrix m(n);
  for (std::size_t e = 0; e < n * n; ++e) m.v[e] = Interval(row_major[e]);
  return m;
}

IMatrix operator*(const IMatrix& a, const IMatrix& b) {
  IMatrix c(a.n);
  for (std::size_t i = 0; i < a.n; ++i) {
    for (std::size_t l = 0; l < a.n; ++l) {
      const Interval& ail = a(i, l);
      for (std::size_t j = 0; j < a.n; ++j) c(i, j) += ail * b(l, j);
    }
  }
  return c;
}

std::vector<Interval> operator*(const IMatrix& a, const std::vector<Interval>& x) {
  std::vector<Interval> y(a.n, Interval(0.0));
  for (std::size_t i = 0; i < a.n; ++i) {
    for (std::size_t j = 0; j < a.n; ++j) y[i] += a(i, j) * x[j];
  }
  return y;
}

Matrix mid(const IMatrix& a) {
  const auto n = static_cast<Eigen::Index>(a.n);
  Matrix m(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j) {
      m(i, j) = a(static_cast<std::size_t>(i), static_cast<std::size_t>(j)).mid();
    }
  }
  return m;
}

std::optional<IMatrix> inverse_enclosure(const Matrix& q, const Matrix& x, double max_error) {
  const auto n = static_cast<std::size_t>(q.rows());
  const IMatrix qi = from_point(q);
  const IMatrix b = from_point(x);
  const IMatrix bq = b * qi;
  double e_norm = 0.0;
  double b_norm = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    Interval e_row(0.0);
    Interval b_row(0.0);
    for (std::size_t j = 0; j < n; ++j) {
      const Interval eij = Interval(i == j ? 1.0 : 0.0) - bq(i, j);
      e_row += Interval(eij.mag());
      b_row += Interval(b(i, j).mag());
    }
    e_norm = std::max(e_norm, e_row.hi());
    b_norm = std::max(b_norm, b_row.hi());
  }
  if (!(e_norm <= max_error && e_norm < 1.0)) return std::nullopt;
  const double delta =
      (Interval(e_norm) * Interval(b_norm) / (Interval(1.0) - Interval(e_norm))).hi();
  IMatrix inv = b;
  for (Interval& x : inv.v) x += Interval(-delta, delta);
  return inv;
}

std::optional<IMatrix> frame_inverse(const Matrix& b) {
  const Matrix approx = b.partialPivLu().inverse();
  if (!approx.allFinite()) return std::nullopt;
  return inverse_enclosure(b, approx, 0.5);
}

IMatrix exp_enclosure(const Matrix& a, Interval t) {
  const auto n = static_cast<std::size_t>(a.rows());
  IMatrix m(n);
  if (!t.is_bounded()) {
    for (Interval& e : m.v) e = Interval::empty();
    return m;
  }
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      m(i, j) = Interval(a(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j))) * t;
    }
  }
  // An upper bound of the infinity norm of every matrix in m.
  const auto norm = [n](const IMatrix& x) {
    double largest = 0;
    for (std::size_t i = 0; i < n; ++i) {
      Interval row(0.0);
      for (std::size_t j = 0; j < n; ++j) row += abs(x(i, j));
      largest = std::max(largest, row.hi());
    }
    return largest;
  };
  // Halving is exact (a power of two), so the scaled matrices are the exact a t / 2^s.
  int squarings = 0;
  for (double size = norm(m); size > 0.5; size = norm(m)) {
    for (Interval& e : m.v) e = e * Interval(0.5);
    ++squarings;
  }
  constexpr int kOrder = 20;
  IMatrix sum(n);
  IMatrix term(n);
  for (std::size_t i = 0; i < n; ++i) sum(i, i) = term(i, i) = Interval(1.0);
  for (int k = 1; k <= kOrder; ++k) {
    term = term * m;
    for (Interval& e : term.v) e = e / Interval(static_cast<double>(k));
    for (std::size_t e = 0; e < n * n; ++e) sum.v[e] += term.v[e];
  }
  // |sum over k > N of M^k / k!| <= ||M||^(N+1) / (N+1)! / (1 - ||M|| / (N+2)) entrywise.
  const Interval size(0.0, norm(m));
  Interval tail = pow(size, kOrder + 1);
  for (int k = 2; k <= kOrder + 1; ++k) tail = tail / Interval(static_cast<double>(k));
  tail = tail / (Interval(1.0) - size / Interval(static_cast<double>(kOrder + 2)));
  const Interval rest(-tail.hi(), tail.hi());
  for (Interval& e : sum.v) e += rest;
  for (int s = 0; s < squarings; ++s) sum = sum * sum;
  return sum;
}

}  // namespace furuta::validated::detail
