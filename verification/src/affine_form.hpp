#pragma once
// Affine forms in shared noise symbols, with every rounding accounted for (internal to the
// verifier): x = centre + sum_j coef[j] e_j + [-err, err], each e_j anywhere in [-1, 1] and the
// same e_j wherever it appears, so that quantities computed from one another keep their
// correlation (a zonotope when taken together). err bounds all that the symbols do not carry: the
// rounding of the double coefficients and the radii of interval multipliers.

#include <Eigen/Dense>
#include <cstddef>
#include <functional>
#include <vector>

#include "furuta/interval/interval.hpp"

namespace furuta::verification::detail {

using interval::Interval;

struct AffineForm {
  double centre = 0;
  Eigen::VectorXd coef;  // may be shorter than the symbols handed out: the rest are 0
  double err = 0;
  // sum |coef| when known (>= 0; set where coef is made), else < 0: computed when asked.
  double norm = -1;
};

// An enclosure of every value the form takes.
Interval range(const AffineForm& a);

// Hands out the noise symbols.
class Symbols {
 public:
  std::size_t count() const { return count_; }
  // A new symbol carrying `v`: mid + rad e (an unbounded or empty v: a form over the whole line).
  AffineForm noise(const Interval& v);
  // A point (no symbol).
  static AffineForm constant(double v);
  // Starts again with `n` symbols (after a reduction renumbered them).
  void reset(std::size_t n) { count_ = n; }

 private:
  std::size_t count_ = 0;
};

// sum_i k_i a_i, each k_i an interval: the coefficients from k_i's midpoints, k_i's radii and the
// rounding into err.
class LinearCombination {
 public:
  LinearCombination& add(const Interval& k, const AffineForm& a);
  LinearCombination& add(const AffineForm& a) { return add(Interval(1.0), a); }
  AffineForm result() const;

 private:
  double centre_ = 0;
  Eigen::VectorXd coef_;
  double err_ = 0;      // carried errors and radii (a bound, before the final rounding)
  double rounded_ = 0;  // the magnitude whose products and sums were rounded
  int terms_ = 0;
};

// A linear change of coordinates of the forms' vector and its exact inverse, in interval
// arithmetic (each an enclosure of the exact map's value).
using CoordinateMap = std::function<std::vector<Interval>(const std::vector<Interval>&)>;

// Folds each form's err into a symbol of its own, then, beyond max_symbols, merges the symbols
// that matter least (Girard: the smallest sum |y| - max |y| of their columns y in the coordinates
// `to` gives) into a box in those coordinates, mapped back by `from`. Coordinates in which the
// loop contracts each direction on its own (the plant's state and the filter's error, rather than
// the state and the estimate) keep the merged part from growing. Renumbers: the forms'
// coefficients and `symbols` describe a set enclosing the old one.
//
// `sensitivities` (optional): forms d_k of the same quantities, the value being forms +
// sum_k eta_k d_k for factors eta_k in [-1, 1] shared by all; the merged symbols' columns count
// with |base| + sum_k |d_k| (into the base's box), and d_k's errors join the base's.
void reduce(std::vector<AffineForm>& forms, Symbols& symbols, std::size_t max_symbols,
            const CoordinateMap& to, const CoordinateMap& from,
            std::vector<std::vector<AffineForm>>* sensitivities = nullptr);

}  // namespace furuta::verification::detail
