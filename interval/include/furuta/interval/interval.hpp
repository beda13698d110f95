#pragma once
// Closed real intervals [lo, hi] with guaranteed outward rounding, the operations the Furuta model
// needs, and their backward (projection) forms for forward-backward contractors.
//
// Every operation returns an interval that contains the exact real result for every choice of
// arguments inside the operands: that is the only promise, and the test suite checks it against
// MPFR. The empty interval is a value (an empty operand gives an empty result), never a crash.
// Intervals are sets of reals (IEEE 1788 set-based): infinite bounds are allowed, infinite points
// are not. The empty interval has lo() = +inf and hi() = -inf. See interval/README.md.

#include <iosfwd>
#include <limits>
#include <utility>

namespace furuta::interval {

class Interval {
 public:
  // The whole real line, like Codac/IBEX: an unknown with no prior.
  Interval();
  // The point [x, x]; NaN (or an infinity, not a real) gives the empty interval.
  Interval(double x);  // NOLINT(google-explicit-constructor): points mix freely with intervals
  // [lo, hi]; lo > hi or a NaN bound gives the empty interval.
  Interval(double lo, double hi);

  static Interval empty();
  static Interval entire();
  // A rigorous enclosure of pi (the two doubles around it).
  static Interval pi();

  double lo() const { return lo_; }
  double hi() const { return hi_; }
  bool is_empty() const;
  bool is_entire() const;
  bool is_bounded() const;  // non-empty with both bounds finite
  bool is_point() const;    // lo == hi

  // hi - lo rounded up; 0 for the empty interval.
  double width() const;
  // A point inside (the midpoint, rounded; a finite point for unbounded intervals: 0 for the
  // whole line, +-DBL_MAX for a half-line, as IEEE 1788); NaN if empty.
  double mid() const;
  double rad() const;  // an upper bound of width()/2, and of the distance from mid() to the bounds
  double mag() const;  // max |x| over the interval; NaN if empty
  double mig() const;  // min |x| over the interval; NaN if empty

  bool contains(double x) const;
  bool contains_zero() const { return contains(0.0); }
  bool is_subset(const Interval& other) const;  // also true when *this is empty
  // Strictly inside (bounds differ; an infinite bound of other counts as open, as IEEE 1788).
  bool is_interior_subset(const Interval& other) const;
  bool intersects(const Interval& other) const;
  bool is_disjoint(const Interval& other) const { return !intersects(other); }

  // The two halves at lo + ratio * width (ratio in (0, 1)); both non-empty for a non-degenerate
  // interval, their union is *this. A ratio outside (0, 1) means 0.5; an unbounded interval is
  // split at mid().
  std::pair<Interval, Interval> bisect(double ratio = 0.5) const;

  Interval& operator+=(const Interval& y);
  Interval& operator-=(const Interval& y);
  Interval& operator*=(const Interval& y);
  Interval& operator/=(const Interval& y);

  friend bool operator==(const Interval& a, const Interval& b);

 private:
  double lo_;
  double hi_;
};

Interval operator-(const Interval& x);
Interval operator+(const Interval& x, const Interval& y);
Interval operator-(const Interval& x, const Interval& y);
Interval operator*(const Interval& x, const Interval& y);
// Division by an interval containing zero gives the hull of the two pieces (possibly entire);
// by [0, 0] it gives the empty interval.
Interval operator/(const Interval& x, const Interval& y);

Interval hull(const Interval& a, const Interval& b);
Interval intersect(const Interval& a, const Interval& b);
Interval operator|(const Interval& a, const Interval& b);  // hull
Interval operator&(const Interval& a, const Interval& b);  // intersection

Interval sqr(const Interval& x);
Interval sqrt(const Interval& x);  // of the non-negative part; empty when x < 0 entirely
Interval abs(const Interval& x);
Interval pow(const Interval& x, int n);  // integer power, n >= 0 (n < 0: 1 / pow(x, -n))
// Rigorous: libm's result widened by its error bound, extremes found with an enclosure of pi.
// Beyond |x| = 2^40 (and for unbounded x) the result is [-1, 1].
Interval sin(const Interval& x);
Interval cos(const Interval& x);

// Backward operators (HC4-revise): given y = f(x1, x2) with y, x1, x2 already enclosed, shrink the
// arguments to the values consistent with y. Each returns the contracted arguments in place; an
// empty result means no argument value is consistent (then every argument is set empty).
void bwd_add(const Interval& y, Interval& x1, Interval& x2);
void bwd_sub(const Interval& y, Interval& x1, Interval& x2);
void bwd_mul(const Interval& y, Interval& x1, Interval& x2);
void bwd_div(const Interval& y, Interval& x1, Interval& x2);
void bwd_neg(const Interval& y, Interval& x);
void bwd_sqr(const Interval& y, Interval& x);
void bwd_sin(const Interval& y, Interval& x);
void bwd_cos(const Interval& y, Interval& x);

std::ostream& operator<<(std::ostream& out, const Interval& x);

}  // namespace furuta::interval
