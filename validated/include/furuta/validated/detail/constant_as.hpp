#pragma once
// `constant_as<T>`: an interval constant as a scalar of type T. Part of
// furuta/validated/taylor.hpp: include that.

#include <type_traits>

#include "furuta/interval/interval.hpp"

namespace furuta::validated {

using interval::Interval;

// An interval constant as a scalar of type T: itself for intervals and gradients, its midpoint for
// floating-point T (exact for the point constants that point simulations use).
template <class T>
T constant_as(const Interval& v) {
  if constexpr (std::is_floating_point_v<T>) {
    return static_cast<T>(v.mid());
  } else {
    return T(v);
  }
}

}  // namespace furuta::validated
