#pragma once
// The a priori enclosure of a step (internal to the validated integrator, method step 1 of
// validated/README.md).

#include <optional>

#include "furuta/interval/box.hpp"
#include "furuta/interval/interval.hpp"
#include "furuta/validated/taylor.hpp"

namespace furuta::validated::internal {

using interval::Box;
using interval::Interval;

// A box containing every solution from x over [0, h], or nothing if Picard's test fails.
std::optional<Box> a_priori(TaylorRunner<Interval>& runner, const Tape& tape, const Box& x,
                            double h);

}  // namespace furuta::validated::internal
