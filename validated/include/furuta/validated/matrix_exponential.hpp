#pragma once
// An interval enclosure of the matrix exponential, for linear maps that must be exact over a time
// interval (the closed loop's verification, verification/).

#include <Eigen/Dense>
#include <vector>

#include "furuta/interval/interval.hpp"

namespace furuta::validated {

// An n x n interval matrix, row-major, holding e^(a t) for every t in `t` (a square, finite; t
// bounded and non-empty, else every entry is empty): the Taylor series of the scaled a t to order
// 20 with its tail bounded, squared back, in outward-rounded interval arithmetic.
std::vector<interval::Interval> exp_enclosure(const Eigen::MatrixXd& a, interval::Interval t);

}  // namespace furuta::validated
