#include "furuta/interval/box.hpp"

#include <algorithm>
#include <cmath>
#include <ostream>
#include <stdexcept>
#include <string>

namespace furuta::interval {
namespace {

void require_same_size(const Box& a, const Box& b, const char* what) {
  if (a.size() != b.size()) {
    throw std::invalid_argument(std::string(what) + ": boxes of sizes " + std::to_string(a.size()) +
                                " and " + std::to_string(b.size()));
  }
}

}  // namespace

Box::Box(std::size_t n, const Interval& x) : c_(n, x) {}

Box::Box(std::initializer_list<Interval> components) : c_(components) {}

Box::Box(std::vector<Interval> components) : c_(std::move(components)) {}

bool Box::is_empty() const {
  return std::any_of(c_.begin(), c_.end(), [](const Interval& x) { return x.is_empty(); });
}

void Box::set_empty() {
  for (Interval& x : c_) x = Interval::empty();
}

double Box::max_width() const {
  double w = 0.0;
  for (const Interval& x : c_) w = std::max(w, x.width());
  return w;
}

std::size_t Box::widest_index() const {
  std::size_t best = 0;
  double best_width = -1.0;
  for (std::size_t i = 0; i < c_.size(); ++i) {
    const double w = c_[i].width();
    if (w > best_width) {
      best = i;
      best_width = w;
    }
  }
  return best;
}

std::size_t Box::widest_relative_index(const std::vector<double>& scale) const {
  if (scale.size() != c_.size()) {
    throw std::invalid_argument("widest_relative_index: scale of size " +
                                std::to_string(scale.size()) + " for a box of size " +
                                std::to_string(c_.size()));
  }
  std::size_t best = c_.size();
  double best_ratio = -1.0;
  for (std::size_t i = 0; i < c_.size(); ++i) {
    if (!(scale[i] > 0)) continue;  // 0, negative or NaN scales never win
    double ratio = c_[i].width() / scale[i];
    if (std::isnan(ratio)) ratio = 0.0;  // inf / inf
    if (ratio > best_ratio) {
      best = i;
      best_ratio = ratio;
    }
  }
  return best == c_.size() ? widest_index() : best;
}

std::vector<double> Box::mid() const {
  std::vector<double> m;
  m.reserve(c_.size());
  for (const Interval& x : c_) m.push_back(x.mid());
  return m;
}

bool Box::contains(const std::vector<double>& point) const {
  if (point.size() != c_.size()) return false;
  for (std::size_t i = 0; i < c_.size(); ++i) {
    if (!c_[i].contains(point[i])) return false;
  }
  return true;
}

bool Box::is_subset(const Box& other) const {
  if (other.size() != size()) return false;
  if (is_empty()) return true;
  for (std::size_t i = 0; i < c_.size(); ++i) {
    if (!c_[i].is_subset(other.c_[i])) return false;
  }
  return true;
}

bool Box::intersects(const Box& other) const {
  if (other.size() != size()) return false;
  for (std::size_t i = 0; i < c_.size(); ++i) {
    if (!c_[i].intersects(other.c_[i])) return false;
  }
  return true;
}

std::pair<Box, Box> Box::bisect(std::size_t i, double ratio) const {
  if (i >= c_.size()) {
    throw std::out_of_range("Box::bisect: component " + std::to_string(i) + " of a box of size " +
                            std::to_string(c_.size()));
  }
  auto [lower, upper] = c_[i].bisect(ratio);
  std::pair<Box, Box> halves{*this, *this};
  halves.first.c_[i] = lower;
  halves.second.c_[i] = upper;
  return halves;
}

Box hull(const Box& a, const Box& b) {
  require_same_size(a, b, "hull");
  if (a.is_empty()) return b;
  if (b.is_empty()) return a;
  Box r(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) r[i] = hull(a[i], b[i]);
  return r;
}

Box intersect(const Box& a, const Box& b) {
  require_same_size(a, b, "intersect");
  Box r(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) r[i] = intersect(a[i], b[i]);
  if (r.is_empty()) r.set_empty();
  return r;
}

std::ostream& operator<<(std::ostream& out, const Box& b) {
  out << '(';
  for (std::size_t i = 0; i < b.size(); ++i) {
    if (i != 0) out << ", ";
    out << b[i];
  }
  return out << ')';
}

std::vector<Box> difference(const Box& outer, const Box& inner) {
  if (outer.size() != inner.size()) {
    throw std::invalid_argument("difference: boxes of different sizes");
  }
  std::vector<Box> pieces;
  if (outer.is_empty()) return pieces;
  if (inner.is_empty()) return {outer};
  if (!inner.is_subset(outer)) {
    throw std::invalid_argument("difference: inner is not inside outer");
  }
  Box rest = outer;  // shrinks to inner, one component at a time
  for (std::size_t i = 0; i < outer.size(); ++i) {
    if (rest[i].lo() < inner[i].lo()) {
      Box below = rest;
      below[i] = Interval(rest[i].lo(), inner[i].lo());
      pieces.push_back(std::move(below));
    }
    if (inner[i].hi() < rest[i].hi()) {
      Box above = rest;
      above[i] = Interval(inner[i].hi(), rest[i].hi());
      pieces.push_back(std::move(above));
    }
    rest[i] = inner[i];
  }
  return pieces;
}

}  // namespace furuta::interval
