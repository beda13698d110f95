#pragma once
// Square interval matrices for the Lohner step (internal to the validated integrator): products
// with interval matrices and vectors, the midpoint matrix, and an interval enclosure of the inverse
// of a point matrix.

#include <Eigen/Dense>
#include <cstddef>
#include <optional>
#include <vector>

#include "furuta/interval/interval.hpp"

namespace furuta::validated::detail {

using interval::Interval;
using Matrix = Eigen::MatrixXd;

// A square interval matrix, row-major.
struct IMatrix {
  std::size_t n = 0;
  std::vector<Interval> v;

  explicit IMatrix(std::size_t size = 0) : n(size), v(size * size, Interval(0.0)) {}
  Interval& operator()(std::size_t i, std::size_t j) { return v[i * n + j]; }
  const Interval& operator()(std::size_t i, std::size_t j) const { return v[i * n + j]; }
};

IMatrix from_point(const Matrix& a);
IMatrix from_point(std::size_t n, const std::vector<double>& row_major);
IMatrix operator*(const IMatrix& a, const IMatrix& b);
std::vector<Interval> operator*(const IMatrix& a, const std::vector<Interval>& x);
Matrix mid(const IMatrix& a);

// An interval matrix containing the inverse of the point matrix q, from an approximate inverse
// x: with E = I - x q, q^-1 = (I - E)^-1 x, so |q^-1 - x| <= ||E|| ||x|| / (1 - ||E||)
// entrywise (infinity norms). Nothing when ||E|| > max_error (< 1).
std::optional<IMatrix> inverse_enclosure(const Matrix& q, const Matrix& x, double max_error);

// An interval enclosure of b^-1 (b invertible in practice: a QR or parallelepiped frame).
std::optional<IMatrix> frame_inverse(const Matrix& b);

// An interval matrix containing e^(a t) for every t in `t` (bounded, non-empty): the Taylor series
// of a t / 2^s (scaled so that its infinity norm is at most 1/2) to order 20, the rest of the
// series bounded by the norm's geometric tail on every entry, then squared s times, all in
// outward-rounded interval arithmetic. Empty entries for an unbounded or empty t.
IMatrix exp_enclosure(const Matrix& a, Interval t);

}  // namespace furuta::validated::detail
