#pragma once
// Taylor models: a polynomial of total degree <= k in n normalised variables z in
// [-1, 1]^n with point coefficients, plus an interval remainder. A model stands for the set
// { p(z) + r : z in [-1, 1]^n, r in R }; every operation returns a model whose set holds the
// result for every z and every pair of values of its operands at that z (the operands must share
// their variables: the same MonomialSpace). Rounding errors of the coefficients, the terms above
// degree k and the Lagrange remainders of sin, cos and 1/x go into R.
//
// It is a scalar for TaylorRunner (taylor.hpp): T(0.0), T(Interval), + - * /, sqr, sin, cos.
// A model without a space is a constant (its set is R alone); it mixes with any model.
//
//   auto space = std::make_shared<MonomialSpace>(2, 3);           // 2 variables, degree 3
//   TaylorModel x = TaylorModel::variable(space, 0, Interval(0.9, 1.1));  // 1 + 0.1 z0
//   TaylorModel y = sin(x) * x;   Interval range = y.bound();

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "furuta/interval/interval.hpp"

namespace furuta::validated {

using interval::Interval;

// The monomials z^e of total degree <= order in `variables` variables, graded (1, z0, z1, ...,
// z0^2, z0 z1, ...), with the table of their products.
class MonomialSpace {
 public:
  // 1..16 variables, order 0..12, at most 2048 monomials (11 variables: order 4).
  MonomialSpace(std::size_t variables, int order);

  std::size_t variables() const { return variables_; }
  int order() const { return order_; }
  std::size_t size() const { return degrees_.size(); }
  int degree(std::size_t m) const { return degrees_[m]; }
  // The exponent of variable v in monomial m.
  int exponent(std::size_t m, std::size_t v) const { return exponents_[m * variables_ + v]; }
  // The monomial z_v (degree 1).
  std::size_t variable(std::size_t v) const { return 1 + v; }
  // The product of monomials a and b, or npos when its degree is above order().
  std::size_t product(std::size_t a, std::size_t b) const { return products_[a * size() + b]; }
  // The range of z^e over [-1, 1]^n: 1 for the constant, [0, 1] when every exponent is even,
  // else [-1, 1].
  const Interval& range(std::size_t m) const { return ranges_[m]; }
  // The range of the product of monomials a and b (any degree).
  Interval product_range(std::size_t a, std::size_t b) const;
  // One past the last monomial of degree <= d (d >= order(): size()).
  std::size_t end_of_degree(int d) const {
    return d < 0 ? 0 : ends_[static_cast<std::size_t>(std::min(d, order_))];
  }

  static constexpr std::size_t npos = static_cast<std::size_t>(-1);

 private:
  std::size_t variables_;
  int order_;
  std::vector<std::uint8_t> exponents_;  // size() x variables_
  std::vector<int> degrees_;
  std::vector<Interval> ranges_;
  std::vector<std::size_t> products_;  // size() x size()
  std::vector<std::size_t> ends_;      // per degree 0..order_
};

class TaylorModel {
 public:
  TaylorModel() : TaylorModel(Interval(0.0)) {}
  TaylorModel(double value) : TaylorModel(Interval(value)) {}  // NOLINT: constants mix in
  TaylorModel(const Interval& value) : remainder_(value) {}    // NOLINT
  // The constant `value` in `space` (its polynomial: mid(value), the rest in the remainder).
  TaylorModel(std::shared_ptr<const MonomialSpace> space, const Interval& value);
  // Variable v ranging over `range`: mid + rad z_v (the rounding of mid and rad in the remainder).
  static TaylorModel variable(std::shared_ptr<const MonomialSpace> space, std::size_t v,
                              const Interval& range);

  const std::shared_ptr<const MonomialSpace>& space() const { return space_; }
  // Coefficient of monomial m (0 for a constant model's m > 0).
  double coefficient(std::size_t m) const;
  const std::vector<double>& coefficients() const { return coefficients_; }
  const Interval& remainder() const { return remainder_; }
  // Every value the model takes: the polynomial's range over [-1, 1]^n plus the remainder. The
  // polynomial's range is the intersection of two bounds: term by term, except that each variable's
  // linear and square terms are bounded as one quadratic in it (polynomial_bound(), what the
  // products use), and the linear-dominated bounder's (the box shrunk towards the corners where
  // the linear part is least and greatest).
  Interval bound() const;
  Interval polynomial_bound() const;
  // The value at a point z (each |z_v| <= 1): the polynomial at z plus the remainder.
  Interval evaluate(const std::vector<double>& z) const;
  // The polynomial alone (remainder 0).
  TaylorModel polynomial() const {
    TaylorModel out = *this;
    out.remainder_ = Interval(0.0);
    return out;
  }
  // The same set in `lower`, a space of the same variables and a lower order: the terms above
  // lower's order bounded into the remainder.
  TaylorModel reduced_to(std::shared_ptr<const MonomialSpace> lower) const;
  // The model of x(z) = this(s_0 z_0, s_1 z_1, ...) (the polynomial's coefficients times the
  // powers of s, their rounding into the remainder; the remainder unchanged).
  TaylorModel rescaled(const std::vector<double>& s) const;
  // The model of x(z) = this(..., centre + scale z_v, ...): the set over a part of z_v's range
  // (centre -+ 0.5, scale 0.5: its halves), the polynomial re-expanded in the new z_v (its
  // rounding into the remainder; the remainder unchanged). |centre| + |scale| <= 1.
  TaylorModel restricted(std::size_t v, double centre, double scale) const;
  // The polynomial's partial derivative in z_v, as a model (its rounding in the remainder; this
  // model's remainder is not differentiated: it is dropped).
  TaylorModel derivative(std::size_t v) const;
  // The model with the terms in `vars` bounded into the remainder, z_w in ranges[w] for w in
  // `vars` (ranges may reach beyond [-1, 1]) and in [-1, 1] otherwise: a model in the other
  // variables that holds the values for every z_vars in their ranges.
  TaylorModel bounded_in(const std::vector<std::size_t>& vars,
                         const std::vector<Interval>& ranges) const;
  // The polynomial's partial derivative in z_v over `box` (each z_w in box[w], which may reach
  // beyond [-1, 1]), term by term.
  Interval partial_over(std::size_t v, const std::vector<Interval>& box) const;
  // The model with its remainder widened to hold `extra` too.
  TaylorModel& add_to_remainder(const Interval& extra);

  // f about the constant coefficient c: d_i = f^(i)(c) / i! (enclosed, i = 0..k) and the Lagrange
  // factor f^(k+1)(range) / (k+1)!, range holding c and every value of a; nothing when f is not
  // defined over range.
  struct Expansion {
    std::vector<Interval> d;
    Interval lagrange;
  };
  using Expand = std::function<std::optional<Expansion>(double c, const Interval& range, int k)>;

  TaylorModel& operator+=(const TaylorModel& y);
  TaylorModel& operator-=(const TaylorModel& y);

  friend TaylorModel operator+(const TaylorModel& a, const TaylorModel& b);
  friend TaylorModel operator-(const TaylorModel& a, const TaylorModel& b);
  friend TaylorModel operator-(const TaylorModel& a);
  friend TaylorModel operator*(const TaylorModel& a, const TaylorModel& b);
  friend TaylorModel operator*(const TaylorModel& a, const Interval& k);
  friend TaylorModel operator/(const TaylorModel& a, const TaylorModel& b);
  friend TaylorModel operator/(const TaylorModel& a, const Interval& k);
  friend TaylorModel reciprocal(const TaylorModel& a);
  friend TaylorModel sqr(const TaylorModel& a);
  friend TaylorModel sin(const TaylorModel& a);
  friend TaylorModel cos(const TaylorModel& a);

 private:
  // From interval coefficients: their midpoints, the rest over each monomial's range into the
  // remainder.
  static TaylorModel from_intervals(std::shared_ptr<const MonomialSpace> space,
                                    const std::vector<Interval>& coefficients, Interval remainder);
  // f(a) = sum_{i<=k} d_i (a - c)^i + lagrange (a - c)'s range^(k+1); a's range is bounded once.
  static TaylorModel compose(const TaylorModel& a, const Expand& expand);

  std::shared_ptr<const MonomialSpace> space_;  // null: a constant (the remainder alone)
  std::vector<double> coefficients_;            // space_->size() of them
  Interval remainder_;
};

}  // namespace furuta::validated
