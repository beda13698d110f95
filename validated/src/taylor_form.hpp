#pragma once
// Evaluation of a step's Taylor form (internal to the validated integrator): the series of one
// component from its coefficient rows, by Horner.

#include <cstddef>
#include <vector>

#include "furuta/interval/interval.hpp"

namespace furuta::validated::internal {

// sum_i s^i c[i stride + offset], i = 0..order.
inline Interval horner(const std::vector<Interval>& c, std::size_t stride, std::size_t offset,
                       int order, const Interval& s) {
  Interval y = c[static_cast<std::size_t>(order) * stride + offset];
  for (int i = order - 1; i >= 0; --i) y = y * s + c[static_cast<std::size_t>(i) * stride + offset];
  return y;
}

}  // namespace furuta::validated::internal
