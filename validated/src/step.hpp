#pragma once
// One step of the validated integrator once its a priori enclosure is accepted (internal; method
// steps 3-5 and 8 of validated/README.md): the Taylor map of the set (at the centre with its
// Jacobian, the second-order term over the set, the new quadratic part) and Lohner's update of the
// set, with the tight enclosure at the step's end.

#include <cstddef>
#include <vector>

#include "a_priori.hpp"
#include "doubleton.hpp"
#include "furuta/interval/box.hpp"
#include "furuta/interval/interval.hpp"
#include "furuta/validated/integrator.hpp"
#include "furuta/validated/taylor.hpp"
#include "interval_matrix.hpp"
#include "lohner_frame.hpp"

namespace furuta::validated::detail {

// T(x0) = T(m) + J (C rho + P(rho) + e) + S(rho) + R over the set, S the second-order term.
struct TaylorMap {
  IMatrix j;                      // J = sum_i h^i V_[i](m)
  std::vector<Interval> z;        // T(m) + what S leaves (after P') + R
  std::vector<double> p_next;     // P' = mid(J P + Q) (zero without the quadratic model)
  std::vector<Interval> p_range;  // P(r0) at the step's start
};

// Method steps 3-4 over [set.t, enclosure.t1]: fills step.centre, step.jacobian (at the centre m,
// thin) and step.second (over the set's box with the centre); `live` as in LiveSet.
TaylorMap taylor_map(const Tape& tape, const Doubleton& set, const std::vector<std::size_t>& live,
                     const StepEnclosure& enclosure, const IntegratorOptions& options,
                     TubeStep& step);

// The set at the step's end, and its parts for the excess ratio.
struct LohnerStep {
  Doubleton set;                          // at enclosure.t1 (origin, r0 and h_next carried over)
  std::vector<Interval> exact;            // C' r0
  std::vector<Interval> exact_quadratic;  // P'(r0)
  std::vector<Interval> error;            // B' r'
  bool qr = false;                        // the QR frame was used
};

// Method step 5: m' = mid(z), C' = mid(J C), the frame B' and r' (choose_frame), and the tight
// enclosure (m' + C' r0 + P'(r0) + B' r') intersected with the direct image of the set.
LohnerStep lohner_step(const Doubleton& set, const TaylorMap& map, const TubeStep& step,
                       const StepEnclosure& enclosure, LiveSet& live,
                       const IntegratorOptions& options);

}  // namespace furuta::validated::detail
