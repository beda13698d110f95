#pragma once
// The tube's steps as a run builds them (internal to the validated integrator; the Tube's own
// methods are in tube.cpp too).

#include "a_priori.hpp"
#include "doubleton.hpp"
#include "furuta/interval/box.hpp"
#include "furuta/validated/integrator.hpp"

namespace furuta::validated::detail {

// A step over [set.t, enclosure.t1] from the set at its start: the set (C, B, r, r0, origin, P)
// and the remainder coefficient; the Taylor form's coefficients are filled in by taylor_map().
TubeStep start_step(const Doubleton& set, const StepEnclosure& enclosure);

// Appends the step with its a priori box and the tight box at its end, and its box over the step
// (its Taylor form over [0, h] inside the a priori box).
void append_step(Tube& tube, TubeStep step, const Box& apriori, const Box& end);

}  // namespace furuta::validated::detail
