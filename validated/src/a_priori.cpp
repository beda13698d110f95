// The a priori enclosure of a step (see a_priori.hpp).

#include "a_priori.hpp"

#include <span>

namespace furuta::validated::internal {
namespace {

Box field(TaylorRunner<Interval>& runner, const Tape& tape, const Box& x) {
  const std::vector<Interval> xs(x.begin(), x.end());
  runner.run(tape, std::span<const Interval>(xs), 1);
  Box f(x.size());
  for (std::size_t v = 0; v < x.size(); ++v) f[v] = runner.coefficient(v, 1);
  return f;
}

}  // namespace

// A box containing every solution from x over [0, h], or nothing if Picard's test fails.
std::optional<Box> a_priori(TaylorRunner<Interval>& runner, const Tape& tape, const Box& x,
                            double h) {
  const Interval span(0.0, h);
  const std::size_t n = x.size();
  Box f = field(runner, tape, x);
  Box b(n);
  for (std::size_t v = 0; v < n; ++v) b[v] = x[v] + span * f[v];
  for (int iteration = 0; iteration < 8; ++iteration) {
    Box inflated(n);
    for (std::size_t v = 0; v < n; ++v) {
      if (!b[v].is_bounded()) return std::nullopt;
      const double d = 0.1 * b[v].width() + 1e-13 * b[v].mag() + 1e-300;
      inflated[v] = b[v] + Interval(-d, d);
    }
    f = field(runner, tape, inflated);
    bool inside = true;
    for (std::size_t v = 0; v < n; ++v) {
      if (!f[v].is_bounded()) return std::nullopt;
      b[v] = x[v] + span * f[v];
      inside = inside && b[v].is_interior_subset(inflated[v]);
    }
    // Every solution stays in `inflated`, hence in x + [0, h] f(inflated) = b.
    if (inside) return b;
  }
  return std::nullopt;
}

}  // namespace furuta::validated::internal
