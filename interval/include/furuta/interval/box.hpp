#pragma once
// Boxes: vectors of intervals (IBEX's IntervalVector), with what pavers need: widths, bisection,
// hull and intersection.

#include <cstddef>
#include <initializer_list>
#include <iosfwd>
#include <utility>
#include <vector>

#include "furuta/interval/interval.hpp"

namespace furuta::interval {

class Box {
 public:
  Box() = default;
  explicit Box(std::size_t n, const Interval& x = Interval::entire());
  Box(std::initializer_list<Interval> components);
  explicit Box(std::vector<Interval> components);

  std::size_t size() const { return c_.size(); }
  Interval& operator[](std::size_t i) { return c_[i]; }
  const Interval& operator[](std::size_t i) const { return c_[i]; }
  auto begin() { return c_.begin(); }
  auto end() { return c_.end(); }
  auto begin() const { return c_.begin(); }
  auto end() const { return c_.end(); }

  // Empty as soon as one component is (and a box of size 0 is not empty).
  bool is_empty() const;
  void set_empty();  // every component empty
  double max_width() const;
  std::size_t widest_index() const;  // the first on ties; 0 for a box of size 0
  // The component whose width relative to scale[i] is largest (scale: e.g. the prior box's widths;
  // components with scale 0 never win; all 0: widest_index()). std::invalid_argument if the sizes
  // differ.
  std::size_t widest_relative_index(const std::vector<double>& scale) const;
  std::vector<double> mid() const;
  bool contains(const std::vector<double>& point) const;
  bool is_subset(const Box& other) const;
  bool intersects(const Box& other) const;
  // Splits component i at ratio (Interval::bisect); the two halves, lower first.
  // std::out_of_range if i >= size().
  std::pair<Box, Box> bisect(std::size_t i, double ratio = 0.5) const;

  // Component-wise (two empty boxes compare equal after set_empty(), which intersect() applies).
  friend bool operator==(const Box& a, const Box& b) = default;

 private:
  std::vector<Interval> c_;
};

// Both throw std::invalid_argument when the sizes differ. hull ignores an empty box; an empty
// intersection comes back with every component empty.
Box hull(const Box& a, const Box& b);
Box intersect(const Box& a, const Box& b);
// outer minus inner (inner a subset of outer, same size): at most 2 n disjoint boxes (sharing
// only faces) whose union with inner is outer, sliced one component after the other.
std::vector<Box> difference(const Box& outer, const Box& inner);

std::ostream& operator<<(std::ostream& out, const Box& b);

}  // namespace furuta::interval
